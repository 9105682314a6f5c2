"""Field runs: upload a recorded track or stream a live one, and measure it (product.md §5, §8)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, File, Form, Query, Response, UploadFile, status

from app import live, runs, services
from app.auth import FixPoster, Planner, Viewer, forbidden
from app.capacity import HeavyWorkDep
from app.db import SessionDep, end_reads
from app.dependencies import SettingsDep
from app.errors import UploadTooLargeError
from app.models import PLAN_NAME_MAX_LENGTH, Plan
from app.routers.downloads import download
from app.schemas import ErrorRead, FixesAdded, FixIn, PlanRead, RunList, RunRead
from app.track_fixes import MAX_TIME_TEXT, check_text, parse_time
from app.tracks import read_track

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
_BUSY: dict[int | str, dict[str, Any]] = {
    503: {"model": ErrorRead, "description": "Server busy: retry after `Retry-After` seconds"}
}

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
    responses={**_BAD_INPUT, **_NOT_FOUND, **_TOO_LARGE, **_BUSY},
)
def create_run(
    plan_id: int,
    session: SessionDep,
    settings: SettingsDep,
    access: FixPoster,
    heavy: HeavyWorkDep,
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
    token may open a live run; uploading a file needs the planner role. The file is read as a
    stream and its fixes stored in one transaction (all or nothing).
    """
    given = check_text((name or "").strip(), input_name="name") or None
    plan = services.read_plan(session, plan_id, access)
    if file is not None and access.via == "device":
        raise forbidden(
            "a device token may open a live run and post fixes; uploading a "
            "track needs the planner role"
        )
    end_reads(session)
    track = None
    if file is None:
        run = runs.create_live_run(session, plan, name=given)
    else:
        limit = settings.max_upload_bytes
        if file.size is not None and file.size > limit:
            raise UploadTooLargeError(limit)
        filename = "".join(c for c in (file.filename or "") if c.isprintable()).strip()
        run_name = (given or filename)[:PLAN_NAME_MAX_LENGTH] or None
        with heavy.slot("upload"):
            stream = read_track(file.file)
            columns, report = runs.read_upload(stream)
        run = runs.create_run_from_columns(
            session, plan, columns, source=stream.format, report=report, name=run_name
        )
        # Scored from the columns just stored (the same fixes), not read back: one copy.
        track = runs.track_from_columns(columns)
        del columns, stream
    response.headers["Location"] = f"/api/runs/{run.id}"
    with heavy.slot("run"):
        return live.full_view(session, run, threshold_m=runs.DEFAULT_THRESHOLD_M, track=track)


@router.get("/plans/{plan_id}/runs", response_model=RunList, responses={**_NOT_FOUND, **_BAD_INPUT})
def list_runs(plan_id: int, session: SessionDep, access: Viewer) -> RunList:
    """List a plan's runs, newest first, with their fix counts."""
    services.read_plan(session, plan_id, access)
    return runs.list_runs(session, plan_id, access)


@router.get(
    "/runs/{run_id}", response_model=RunRead, responses={**_NOT_FOUND, **_BAD_INPUT, **_BUSY}
)
def read_run(
    run_id: int,
    session: SessionDep,
    access: Viewer,
    heavy: HeavyWorkDep,
    threshold_m: ThresholdQuery = runs.DEFAULT_THRESHOLD_M,
    since: Annotated[
        str | None,
        Query(
            max_length=MAX_TIME_TEXT,
            description="Only the fixes after this time (the `last_fix.t` of the previous "
            "read; ISO 8601 or epoch seconds) in `track`, and the last figures computed: a "
            "live run's poll, fast however long the run.",
        ),
    ] = None,
) -> dict[str, Any]:
    """Return a run with its metrics against the plan (as a simulation's), track and stretches."""
    run = runs.read_run(session, run_id, access)
    if since is not None:
        since_us = parse_time(since, input_name="since")
        return live.live_view(session, run, since_us=since_us, threshold_m=threshold_m, heavy=heavy)
    with heavy.slot("run"):
        return live.full_view(session, run, threshold_m=threshold_m)


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


@router.post(
    "/runs/{run_id}/follow-up",
    response_model=PlanRead,
    status_code=status.HTTP_201_CREATED,
    responses={**_NOT_FOUND, **_BAD_INPUT, **_CONFLICT},
)
def create_follow_up(
    run_id: int,
    session: SessionDep,
    access: Planner,
    settings: SettingsDep,
    response: Response,
) -> Plan:
    """Plan a path over the ground the run missed and store it as a new plan (product.md §8).

    The gaps are those of `missed` in the run's answer; each is planned with the run's plan's
    interval and options, nearest first from its start, and stored in the run's organisation
    and field. 409 if the run missed nothing.
    """
    run = runs.read_run(session, run_id, access)
    plan = runs.follow_up_plan(session, run, budget_s=settings.planning_budget_s)
    response.headers["Location"] = f"/api/plans/{plan.id}"
    return plan


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
    return download(export)


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
    return download(export)
