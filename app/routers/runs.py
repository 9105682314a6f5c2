"""Field runs: upload a recorded track or stream a live one, and measure it (product.md §5, §8)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Depends, File, Form, Query, Response, UploadFile, status

from app import runs, services
from app.auth import FixPoster, Viewer, forbidden
from app.db import SessionDep
from app.errors import UploadTooLargeError
from app.models import PLAN_NAME_MAX_LENGTH
from app.schemas import ErrorRead, FixesAdded, FixIn, RunList, RunRead
from app.settings import Settings, get_settings
from app.tracks import TrackFormatError, parse_track

router = APIRouter(tags=["runs"])

_BAD_INPUT: dict[int | str, dict[str, Any]] = {
    422: {"model": ErrorRead, "description": "The input named in `detail` is wrong"}
}
_NOT_FOUND: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorRead, "description": "No such plan or run"}
}
_TOO_LARGE: dict[int | str, dict[str, Any]] = {
    413: {"model": ErrorRead, "description": "Upload or body over the configured limit"}
}
_CONFLICT: dict[int | str, dict[str, Any]] = {
    409: {"model": ErrorRead, "description": "Not possible for this run (see `detail`)"}
}

SettingsDep = Annotated[Settings, Depends(get_settings)]
ThresholdQuery = Annotated[
    float,
    Query(
        gt=0,
        le=100,
        description="Cross-track error above which a stretch is reported [m].",
    ),
]


@router.post(
    "/plans/{plan_id}/runs",
    response_model=RunRead,
    status_code=status.HTTP_201_CREATED,
    responses={**_BAD_INPUT, **_NOT_FOUND, **_TOO_LARGE},
)
def create_run(
    plan_id: int,
    session: SessionDep,
    settings: SettingsDep,
    access: FixPoster,
    response: Response,
    file: Annotated[
        UploadFile | None,
        File(description="GPX track, CSV (time,lat,lon[,heading_deg][,speed_mps]) or NMEA log."),
    ] = None,
    name: Annotated[
        str | None,
        Form(max_length=PLAN_NAME_MAX_LENGTH, description="Run name; default: the file name."),
    ] = None,
) -> dict[str, Any]:
    """Upload a recorded track as a run of the plan, or, without a file, create a live run.

    A multipart body with `file` uploads a track (format detected from its content). No body,
    an empty JSON object `{}` or a form without `file` creates an empty live run, to which the
    tractor's logger then posts fixes. Nothing is stored when the file is refused. A device
    token may open a live run; uploading a file needs the planner role.
    """
    plan = services.read_plan(session, plan_id, access)
    if name is not None and "\x00" in name:  # PostgreSQL text cannot hold NUL
        raise TrackFormatError("name", "must not contain NUL characters")
    if file is not None and access.via == "device":
        raise forbidden(
            "a device token may open a live run and post fixes; uploading a "
            "track needs the planner role"
        )
    if file is None:
        run = runs.create_live_run(session, plan, name=(name or "").strip() or None)
    else:
        limit = settings.max_upload_bytes
        data = file.file.read(limit + 1)
        if len(data) > limit:
            raise UploadTooLargeError(limit)
        track = parse_track(data)
        run_name = (name or "").strip() or (file.filename or "").strip() or None
        run = runs.create_run_from_track(
            session, plan, track, name=run_name[:PLAN_NAME_MAX_LENGTH] if run_name else None
        )
    response.headers["Location"] = f"/api/runs/{run.id}"
    return runs.run_view(session, run)


@router.get("/plans/{plan_id}/runs", response_model=RunList, responses={**_NOT_FOUND, **_BAD_INPUT})
def list_runs(plan_id: int, session: SessionDep, access: Viewer) -> RunList:
    """List a plan's runs, newest first, with their fix counts."""
    services.read_plan(session, plan_id, access)
    return runs.list_runs(session, plan_id, access)


@router.get("/runs/{run_id}", response_model=RunRead, responses={**_NOT_FOUND, **_BAD_INPUT})
def read_run(
    run_id: int,
    session: SessionDep,
    access: Viewer,
    threshold_m: ThresholdQuery = runs.DEFAULT_THRESHOLD_M,
) -> dict[str, Any]:
    """Return a run with its metrics against the plan (as a simulation's), track and stretches."""
    return runs.run_view(session, runs.read_run(session, run_id, access), threshold_m=threshold_m)


@router.post(
    "/runs/{run_id}/fixes",
    response_model=FixesAdded,
    responses={**_BAD_INPUT, **_NOT_FOUND, **_TOO_LARGE, **_CONFLICT},
)
def add_fixes(
    run_id: int, fixes: list[FixIn], session: SessionDep, access: FixPoster
) -> FixesAdded:
    """Append a batch of fixes to a live run; idempotent per timestamp.

    Batches may come late, out of order or more than once: fixes are kept in time order and
    a timestamp the run already has is not stored again.
    """
    run = runs.read_run(session, run_id, access)
    stored, total = runs.add_fixes(session, run, fixes)
    return FixesAdded(run_id=run.id, received=len(fixes), stored=stored, fix_count=total)


@router.get(
    "/runs/{run_id}/export/gpx",
    response_class=Response,
    responses={
        200: {"description": "GPX 1.1 download", "content": {"application/gpx+xml": {}}},
        **_NOT_FOUND,
        **_BAD_INPUT,
        **_CONFLICT,
    },
)
def export_run_gpx(run_id: int, session: SessionDep, access: Viewer) -> Response:
    """Download a run as GPX: its fixes as a timed track, the plan as a route."""
    export = runs.export_run_gpx(session, runs.read_run(session, run_id, access))
    return Response(
        content=export.content,
        media_type=export.media_type,
        headers={"Content-Disposition": f'attachment; filename="{export.filename}"'},
    )


@router.get(
    "/runs/{run_id}/export/kml",
    response_class=Response,
    responses={
        200: {
            "description": "KML 2.2 download",
            "content": {"application/vnd.google-earth.kml+xml": {}},
        },
        **_NOT_FOUND,
        **_BAD_INPUT,
        **_CONFLICT,
    },
)
def export_run_kml(run_id: int, session: SessionDep, access: Viewer) -> Response:
    """Download a run as KML for Google Earth: its fixes as a ``gx:Track``, the plan with it."""
    export = runs.export_run_track(session, runs.read_run(session, run_id, access), "kml")
    return Response(
        content=export.content,
        media_type=export.media_type,
        headers={"Content-Disposition": f'attachment; filename="{export.filename}"'},
    )
