"""``POST /api/fields/parse``: read a field file of any import format into its fields (§4).

The page sends the file the user picked; the answer lists every field (id, name, area) as a
GeoJSON FeatureCollection, so the page can show them all and let the user choose one. Nothing
is stored (the registry's ``POST /api/fields/import`` stores them).
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Depends, File, UploadFile

from app.auth import Viewer
from app.errors import UploadTooLargeError
from app.schemas import ErrorRead
from app.settings import Settings, get_settings
from planner.io import fields_to_geojson, read_fields

router = APIRouter(prefix="/fields", tags=["fields"])

SettingsDep = Annotated[Settings, Depends(get_settings)]


@router.post(
    "/parse",
    responses={
        200: {
            "description": "The file's fields: a FeatureCollection, one Polygon Feature per "
            "field (properties `index`, `id`, `name`, `area_m2`, `interval_m`), then the "
            "file's start and finish Points (`role`)",
            "content": {"application/geo+json": {}},
        },
        413: {"model": ErrorRead, "description": "Upload over the configured limit"},
        422: {"model": ErrorRead, "description": "The file cannot be read (see `detail`)"},
    },
)
def parse_field_file(
    settings: SettingsDep,
    _access: Viewer,
    file: Annotated[
        UploadFile,
        File(description="GeoJSON, KML, KMZ, zipped Shapefile or GeoPackage."),
    ],
) -> dict[str, Any]:
    """Read a field file into its fields, reprojected to WGS84; store nothing."""
    limit = settings.max_upload_bytes
    data = file.file.read(limit + 1)
    if len(data) > limit:
        raise UploadTooLargeError(limit)
    name = (file.filename or "").strip() or "file"
    collection = fields_to_geojson(read_fields(data, filename=name))
    collection["name"] = name
    return collection
