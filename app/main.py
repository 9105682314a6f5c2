"""The FastAPI application: ``create_app()`` wires routers, error handlers and the map page.

Run it with ``tillpath serve`` (uvicorn's factory mode: ``app.main:create_app``).
"""

from __future__ import annotations

from fastapi import FastAPI

from app.errors import BodySizeLimitMiddleware, register_error_handlers
from app.routers import (
    auth,
    field_files,
    fields,
    health,
    pages,
    plans,
    runs,
    simulations,
    vehicles,
)
from app.security import SecurityHeadersMiddleware, content_security_policy
from app.settings import Settings, get_settings

API_PREFIX = "/api"


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the application.

    Parameters
    ----------
    settings : Settings, optional
        Settings to use instead of the environment's (they then also replace the
        ``get_settings`` dependency, so the database and the page see them too).

    Returns
    -------
    FastAPI
    """
    app = FastAPI(
        title="tillpath",
        summary="Tillage paths for autonomous walk-behind hand tractors",
        description=(
            "Plan back-and-forth coverage paths over a field, store them and download their "
            "waypoints. Coordinates are WGS84 `[lon, lat]`; errors are "
            '`{"detail": "<input>: <problem>"}`.'
        ),
        version="0.1.0",
        # /docs is served offline by the pages router; ReDoc would need a CDN.
        docs_url=None,
        redoc_url=None,
    )
    if settings is not None:
        app.dependency_overrides[get_settings] = lambda: settings
    else:
        settings = get_settings()

    app.include_router(plans.router, prefix=API_PREFIX)
    app.include_router(simulations.router, prefix=API_PREFIX)
    app.include_router(runs.router, prefix=API_PREFIX)
    app.include_router(field_files.router, prefix=API_PREFIX)
    app.include_router(health.router, prefix=API_PREFIX)
    app.include_router(auth.router, prefix=API_PREFIX)
    app.include_router(fields.router, prefix=API_PREFIX)
    app.include_router(vehicles.router, prefix=API_PREFIX)
    register_error_handlers(app)
    app.add_middleware(
        BodySizeLimitMiddleware,
        max_body_bytes=settings.max_body_bytes,
        upload_bytes=settings.max_upload_bytes,
    )
    app.add_middleware(
        SecurityHeadersMiddleware,
        csp=content_security_policy([settings.satellite_tile_url, settings.street_tile_url]),
    )

    pages.mount_pages(app)
    return app
