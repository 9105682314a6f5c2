"""The FastAPI application: ``create_app()`` wires routers, error handlers and the map page.

Run it with ``tillpath serve`` (uvicorn's factory mode: ``app.main:create_app``).
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import FastAPI
from starlette.middleware.gzip import GZipMiddleware

from app import budget
from app.errors import BodySizeLimitMiddleware, register_error_handlers
from app.jobs import jobs_lifespan
from app.routers import (
    auth,
    field_files,
    fields,
    health,
    jobs,
    members,
    pages,
    plans,
    runs,
    simulations,
    vehicles,
)
from app.security import SecurityHeadersMiddleware, content_security_policy
from app.settings import Settings, get_settings

API_PREFIX = "/api"
#: Answers smaller than this go uncompressed: gzip's header would eat the gain [bytes].
GZIP_MINIMUM_BYTES = 1000


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the application.

    Parameters
    ----------
    settings : Settings, optional
        Settings to use instead of the environment's (the routes' dependencies then hand out
        these, so the database and the page see them too: :mod:`app.dependencies`).

    Returns
    -------
    FastAPI
    """
    resolved = settings or get_settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        if resolved.warm_up_planner:  # a spawned worker of `serve --workers N`
            await asyncio.to_thread(budget.warm_up().join)
        async with jobs_lifespan(app, resolved):
            yield

    app = FastAPI(
        lifespan=lifespan,
        title="tillpath",
        summary="Tillage paths for autonomous walk-behind hand tractors",
        description=(
            "Plan back-and-forth coverage paths over a field, store them and download their "
            "waypoints. Coordinates are WGS84 `[lon, lat]`; errors are "
            '`{"detail": "<input>: <problem>"}`.\n\n'
            "Every route but health, sign-in and the page needs a token "
            "(`Authorization: Bearer …`) or the page's session cookie, whose writes also send "
            "`X-CSRF-Token`. A request acts in one organisation: `X-Organisation: <id>` if "
            "given, else the one chosen on the page, else the user's first. Another "
            "organisation's rows are 404; a missing role is 403 (docs/accounts.md)."
        ),
        version="0.1.0",
        # /docs is served offline by the pages router; ReDoc would need a CDN.
        docs_url=None,
        redoc_url=None,
    )
    # What the routes' dependencies hand out (app.dependencies): no override of get_settings,
    # since any dependency override makes FastAPI rebuild every dependency of every request.
    settings = resolved
    app.state.settings = settings

    app.include_router(plans.router, prefix=API_PREFIX)
    app.include_router(simulations.router, prefix=API_PREFIX)
    app.include_router(runs.router, prefix=API_PREFIX)
    app.include_router(field_files.router, prefix=API_PREFIX)
    app.include_router(jobs.router, prefix=API_PREFIX)
    app.include_router(health.router, prefix=API_PREFIX)
    app.include_router(auth.router, prefix=API_PREFIX)
    app.include_router(fields.router, prefix=API_PREFIX)
    app.include_router(vehicles.router, prefix=API_PREFIX)
    app.include_router(members.router, prefix=API_PREFIX)
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

    # Outermost: every answer over 1 KB is gzip-compressed when the client accepts it (a plan's
    # GeoJSON, a simulation, the page's libraries: a rural mobile link pays for every byte).
    app.add_middleware(GZipMiddleware, minimum_size=GZIP_MINIMUM_BYTES)

    pages.mount_pages(app)
    return app
