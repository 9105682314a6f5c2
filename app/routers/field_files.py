"""Field files of any import format (§4, §12): read them, or import them into the registry.

``POST /api/fields/parse``: the page sends the file the user picked; the answer lists every
field (id, name, area) as a GeoJSON FeatureCollection, so the page can show them all and let
the user choose one. Nothing is stored. ``POST /api/fields/import`` stores every field of the
file in the organisation's registry at once.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, File, Response, UploadFile, status

from app.auth import Planner, Viewer
from app.db import SessionDep
from app.dependencies import SettingsDep
from app.errors import UploadTooLargeError
from app.field_import import FieldImportRead, import_fields
from app.schemas import ErrorRead
from planner.io import fields_to_geojson, read_fields

router = APIRouter(prefix="/fields", tags=["fields"])


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
    data, name = _read_upload(file, settings.max_upload_bytes)
    collection = fields_to_geojson(read_fields(data, filename=name))
    collection["name"] = name
    return collection


@router.post(
    "/import",
    response_model=FieldImportRead,
    status_code=status.HTTP_201_CREATED,
    responses={
        413: {"model": ErrorRead, "description": "Upload over the configured limit"},
        422: {"model": ErrorRead, "description": "The file or one of its fields is refused"},
    },
)
def import_field_file(
    settings: SettingsDep,
    session: SessionDep,
    access: Planner,
    response: Response,
    file: Annotated[
        UploadFile,
        File(description="GeoJSON, KML, KMZ, zipped Shapefile or GeoPackage of many fields."),
    ],
) -> FieldImportRead:
    """Store every field of the file in the registry, in file order (all or nothing).

    A field whose boundary the organisation already has is reused, not copied; the answer
    lists the file's fields as stored.
    """
    data, name = _read_upload(file, settings.max_upload_bytes)
    imported = import_fields(session, read_fields(data, filename=name), access, filename=name)
    response.headers["Location"] = "/api/fields"
    return imported


def _read_upload(file: UploadFile, limit: int) -> tuple[bytes, str]:
    data = file.file.read(limit + 1)
    if len(data) > limit:
        raise UploadTooLargeError(limit)
    return data, (file.filename or "").strip() or "file"
