"""The map page at ``/``, its static files and the front-end libraries installed by npm.

The page works like TiTiler's viewer: the server renders one HTML template and passes every URL
the browser needs (the plans API, the tile servers) in ``data-`` attributes; ``static/js/map.js``
fetches plans from the API as JSON and draws them. No planning happens in the browser.
"""

from __future__ import annotations

import hashlib
import json
import logging
from pathlib import Path

from fastapi import APIRouter, FastAPI, Request
from fastapi.responses import HTMLResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates
from jinja2 import pass_context
from starlette.routing import NoMatchFound

from app import i18n
from app.dependencies import SettingsDep
from app.resources import resource_root

logger = logging.getLogger(__name__)

#: Where templates, static files and node_modules are: the checkout, or the installed wheel.
ROOT = resource_root()
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
i18n.install_jinja(templates.env)
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
def map_page(request: Request, settings: SettingsDep) -> HTMLResponse:
    """Render the map page: draw a field, plan a path, save and download it."""
    plans_url = _plans_api_url(request)
    lang = i18n.negotiate_language(
        request.headers.get("accept-language"), request.cookies.get(i18n.LANGUAGE_COOKIE)
    )
    context = {
        "lang": lang,
        "languages": i18n.LANGUAGES,
        "catalog_url": relative_url(request, "catalog", lang=lang),
        "service_worker_url": relative_url(request, "service_worker"),
        "plans_url": plans_url,
        # The API root: simulations and runs live at ``{api_url}/simulations/{id}``, ``/runs/…``.
        "api_url": plans_url.rstrip("/").removesuffix("/plans"),
        "satellite_tile_url": settings.satellite_tile_url,
        "street_tile_url": settings.street_tile_url,
    }
    with i18n.use_language(lang):
        response = templates.TemplateResponse(request, "map.html", context)
    # The page differs by language: caches must keep one copy per cookie and header.
    response.headers["Vary"] = "Accept-Language, Cookie"
    return response


@router.get("/i18n/{lang}.json", name="catalog")
def catalog(lang: str) -> JSONResponse:
    """Return the compiled catalog of ``lang`` for the page's ``t()`` (static/js/i18n.js).

    ``{"lang": "id", "messages": {msgid: translation}}``; English (the source language) and
    unknown languages answer an empty ``messages``, so the English text shows.
    """
    known = lang if lang in i18n.LANGUAGES else i18n.DEFAULT_LANGUAGE
    return JSONResponse({"lang": known, "messages": i18n.catalog_messages(known)})


@router.get("/manifest.webmanifest", name="web_manifest")
def web_manifest(request: Request) -> JSONResponse:
    """Return the web app manifest: a phone can install the page and open it full screen."""
    lang = i18n.negotiate_language(
        request.headers.get("accept-language"), request.cookies.get(i18n.LANGUAGE_COOKIE)
    )
    icon = relative_url(request, "static", path="favicon.svg")
    manifest = {
        "name": "tillpath",
        "short_name": "tillpath",
        "description": i18n.gettext("Back-and-forth paths for hand tractors", lang),
        "lang": lang,
        "start_url": relative_url(request, "map_page"),
        "scope": relative_url(request, "map_page"),
        "display": "standalone",
        "background_color": "#f6f8f6",
        "theme_color": "#1f5130",
        "icons": [{"src": icon, "sizes": "any", "type": "image/svg+xml", "purpose": "any"}],
    }
    return JSONResponse(manifest, media_type="application/manifest+json")


#: The libraries the page loads from node_modules (the service worker caches them).
VENDOR_SHELL = (
    "vendor/leaflet/leaflet.css",
    "vendor/leaflet/leaflet.js",
    "vendor/leaflet/images/layers.png",
    "vendor/leaflet/images/layers-2x.png",
    "vendor/leaflet/images/marker-icon.png",
    "vendor/leaflet-geoman/leaflet-geoman.css",
    "vendor/leaflet-geoman/leaflet-geoman.min.js",
)


def shell_paths() -> list[str]:
    """Return what the page needs offline, as paths below the site root.

    Every file under ``static/`` (so a new script module is cached without anyone listing it),
    the libraries of :data:`VENDOR_SHELL`, the manifest and one catalog per language.
    """
    static = sorted(
        "static/" + path.relative_to(STATIC_DIR).as_posix()
        for path in STATIC_DIR.rglob("*")
        if path.is_file() and path.name != "sw.js"
    )
    catalogs = [f"i18n/{lang}.json" for lang in i18n.LANGUAGES]
    return ["", "manifest.webmanifest", *catalogs, *static, *VENDOR_SHELL]


def _shell_file(path: str) -> Path | None:
    """Return the file behind a shell path, or None for the generated ones (page, catalogs)."""
    if path.startswith("static/"):
        return ROOT / path
    if path.startswith("vendor/"):
        name, rest = path.removeprefix("vendor/").split("/", 1)
        return VENDOR_DIRS[f"/vendor/{name}"][1] / rest
    return None


def shell_version(paths: list[str]) -> str:
    """Return a short hash of the shell's files and catalogs (name, size, time): the cache's name.

    A deploy that changes any of them makes the service worker fetch the shell anew.
    """
    files = [_shell_file(path) for path in paths]
    files += [i18n.po_path(lang) for lang in i18n.LANGUAGES]
    files += sorted(TEMPLATES_DIR.rglob("*.html"))
    digest = hashlib.sha256()
    for file in files:
        if file is not None and file.is_file():
            stat = file.stat()
            digest.update(f"{file.name}:{stat.st_size}:{stat.st_mtime_ns};".encode())
    return digest.hexdigest()[:12]


@router.get("/sw.js", name="service_worker")
def service_worker() -> Response:
    """Serve the service worker from the site's root so that its scope covers the page (``/``).

    The list of files to cache and the cache's version are filled in here, from the files.
    """
    paths = shell_paths()
    script = (STATIC_DIR / "js" / "sw.js").read_text(encoding="utf-8")
    script = script.replace('/*SHELL*/ [""]', json.dumps(paths))
    script = script.replace('/*VERSION*/ "dev"', json.dumps(shell_version(paths)))
    return Response(script, media_type="text/javascript", headers={"Cache-Control": "no-cache"})


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
