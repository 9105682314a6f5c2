"""The map page at ``/``, its static files and the front-end libraries installed by npm.

The page works like TiTiler's viewer: the server renders one HTML template and passes every URL
the browser needs (the plans API, the tile servers) in ``data-`` attributes; ``static/js/map.js``
fetches plans from the API as JSON and draws them. No planning happens in the browser.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, Depends, FastAPI, Request
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates
from jinja2 import pass_context
from starlette.routing import NoMatchFound

from app.settings import Settings, get_settings

logger = logging.getLogger(__name__)

#: The repository root: templates, static files and node_modules live beside ``app/``.
ROOT = Path(__file__).resolve().parents[2]
TEMPLATES_DIR = ROOT / "templates"
STATIC_DIR = ROOT / "static"
NODE_MODULES = ROOT / "node_modules"

#: URL prefix and route name -> the ``dist`` folder of an npm package. Only the built files are
#: served, never the packages' sources or anything else under node_modules.
VENDOR_DIRS: dict[str, tuple[str, Path]] = {
    "/vendor/leaflet": ("vendor-leaflet", NODE_MODULES / "leaflet" / "dist"),
    "/vendor/leaflet-geoman": (
        "vendor-leaflet-geoman",
        NODE_MODULES / "@geoman-io" / "leaflet-geoman-free" / "dist",
    ),
    "/vendor/swagger-ui": ("vendor-swagger-ui", NODE_MODULES / "swagger-ui-dist"),
}

#: Where the plans API lives when its route cannot be looked up by name.
PLANS_API_FALLBACK = "/api/plans"

templates = Jinja2Templates(directory=TEMPLATES_DIR)
router = APIRouter(include_in_schema=False)


def relative_url(request: Request, name: str, /, **path_params: object) -> str:
    """Return the path of route ``name`` (with the app's root path), never an absolute URL.

    URLs in the page are paths, so the request's ``Host`` header cannot point the page's
    scripts or API calls at another server.
    """
    path = request.app.url_path_for(name, **path_params)
    return str(request.scope.get("root_path", "")).rstrip("/") + str(path)


@pass_context
def _template_url_for(context: dict[str, object], name: str, /, **path_params: object) -> str:
    request = context["request"]
    assert isinstance(request, Request)
    return relative_url(request, name, **path_params)


templates.env.globals["url_for"] = _template_url_for


def _plans_api_url(request: Request) -> str:
    """Return the URL of the plans collection (``GET /api/plans``).

    Parameters
    ----------
    request : Request
        The page request; its base URL (and any ``root_path``) is honoured.

    Returns
    -------
    str
        A path (no host); the page derives ``/preview``, ``/{id}`` and ``/{id}/export/{format}``
        from it.
    """
    try:
        return relative_url(request, "list_plans")
    except NoMatchFound:
        # The API router names its handler ``list_plans`` (style guide); if it ever does not,
        # the documented path still works.
        return str(request.scope.get("root_path", "")).rstrip("/") + PLANS_API_FALLBACK


@router.get("/docs", response_class=HTMLResponse, name="api_docs")
def api_docs(request: Request) -> HTMLResponse:
    """Swagger UI for the OpenAPI description, served from npm like the map's libraries.

    FastAPI's default page loads Swagger UI from a CDN, which a farm office without internet
    cannot reach, and starts it with an inline script, which the Content-Security-Policy
    refuses: ``static/js/docs.js`` starts it instead.
    """
    vendor = relative_url(request, "vendor-swagger-ui", path="").rstrip("/")
    context = {"vendor_url": vendor, "openapi_url": relative_url(request, "openapi")}
    return templates.TemplateResponse(request, "docs.html", context)


@router.get("/", response_class=HTMLResponse, name="map_page")
def map_page(
    request: Request, settings: Annotated[Settings, Depends(get_settings)]
) -> HTMLResponse:
    """Render the map page: draw a field, plan a path, save and download it."""
    plans_url = _plans_api_url(request)
    context = {
        "plans_url": plans_url,
        # The API root: simulations and runs live at ``{api_url}/simulations/{id}``, ``/runs/…``.
        "api_url": plans_url.rstrip("/").removesuffix("/plans"),
        "satellite_tile_url": settings.satellite_tile_url,
        "street_tile_url": settings.street_tile_url,
    }
    return templates.TemplateResponse(request, "map.html", context)


def mount_pages(app: FastAPI) -> None:
    """Add the map page, its static files and the npm-served libraries to ``app``.

    Parameters
    ----------
    app : FastAPI
        The application; gets the ``/`` route, ``/static`` and ``/vendor/...`` mounts.
    """
    app.include_router(router)
    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    for prefix, (name, directory) in VENDOR_DIRS.items():
        if not directory.is_dir():
            # Serve the API anyway; the page explains what is missing instead of the app
            # refusing to start.
            logger.warning("%s is missing: run `npm ci` (make run does it)", directory)
        app.mount(prefix, StaticFiles(directory=directory, check_dir=False), name=name)
