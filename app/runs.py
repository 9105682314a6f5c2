"""Field runs: store a tractor's fixes and score them against their plan (product.md §8).

Thin adapters between the routes, :mod:`app.tracks` (file parsing), the ``runs`` and ``fixes``
tables and :func:`navigation.score_track` (the same scoring as a simulation's).

Fixes are stored by :mod:`app.ingest` (``COPY`` on PostgreSQL, ``executemany`` on SQLite,
both ending in ``ON CONFLICT (run_id, t) DO NOTHING``): a batch that arrives twice, late or out
of order stores each timestamp once, and concurrent batches cannot race, since the database's
unique key decides. Every write is a short transaction of its own (:func:`app.db.write`),
after the parsing and before the scoring.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Final, cast

import numpy as np
import numpy.typing as npt
from sqlalchemy import select
from sqlalchemy.orm import Session

from app import ingest
from app.auth import Access, owned
from app.db import add_row, end_reads, write
from app.errors import ConflictError, NotFoundError
from app.missed import missed_ground_geojson, plan_follow_up
from app.models import Plan, Run
from app.receiver import receiver_report
from app.schemas import MAX_FIXES_PER_BATCH, FixIn, RunList, RunSummary
from app.services import (
    EXPORT_TYPES,
    ExportFile,
    coverage_plan_from_row,
    export_basename,
    json_ready,
    read_stored,
)
from app.track_fixes import (
    ParsedTrack,
    TrackFix,
    TrackFormatError,
    check_not_empty,
    parse_time,
    us_to_datetime,
)
from app.tracks import TrackStream
from navigation import TrackMetrics, score_track
from planner.export.gpx import GpxTrack, plan_to_gpx
from planner.export.kml import plan_to_kml

FloatArray = npt.NDArray[np.float64]

#: Rows per bulk ``INSERT`` statement (9 parameters each: under SQLite's 32,766 limit).
INSERT_CHUNK_ROWS: Final = 3000
#: Most vertices of the track returned for display.
MAX_TRACK_POINTS: Final = 20_000
#: Rows fetched from the driver at a time when a run's track is loaded.
_LOAD_BLOCK_ROWS: Final = 50_000
#: Default cross-track error threshold of the reported stretches [m].
DEFAULT_THRESHOLD_M: Final = 1.0


@dataclass(frozen=True, slots=True)
class RunTrack:
    """A run's fixes as arrays, in time order.

    Attributes
    ----------
    t : int array
        Times [µs since the Unix epoch].
    lon, lat : float arrays
        WGS84 [deg].
    heading_deg, speed_mps : float arrays
        NaN where unknown.
    quality : sequence of (str or None)
        Fix quality per fix (:data:`app.track_fixes.FIX_QUALITIES`), None where unknown.
    hdop, satellites : float arrays
        NaN where unknown.
    """

    t: npt.NDArray[np.int64]
    lon: FloatArray
    lat: FloatArray
    heading_deg: FloatArray
    speed_mps: FloatArray
    quality: Sequence[str | None] = field(default_factory=list)
    hdop: FloatArray = field(default_factory=lambda: np.array([], dtype=float))
    satellites: FloatArray = field(default_factory=lambda: np.array([], dtype=float))

    def time_s(self) -> FloatArray:
        """Seconds since the first fix."""
        return np.asarray((self.t - self.t[0]) / 1e6, dtype=float) if len(self.t) else np.array([])


# --- storing -------------------------------------------------------------------------------


def insert_fixes(session: Session, run_id: int, fixes: Sequence[TrackFix]) -> int:
    """Insert ``fixes`` into run ``run_id``, skipping timestamps it already has.

    Parameters
    ----------
    session : Session
        Not committed here: the caller decides (an upload stores its run and all its fixes in
        one transaction).
    run_id : int
    fixes : sequence of TrackFix
        Any order; repeated times are allowed (only the first is stored).

    Returns
    -------
    int
        How many fixes were new.
    """
    return ingest.store_fixes(session, run_id, ingest.collect(fixes))


def read_upload(stream: TrackStream) -> tuple[ingest.FixColumns, dict[str, Any]]:
    """Parse an upload's fixes into columns and its import report; nothing is written.

    Raises
    ------
    TrackFormatError
        For a malformed file or one with no usable fix.
    """
    columns = ingest.collect(stream.fixes)
    check_not_empty(stream.format, len(columns), stream.report)
    return columns, json_ready(stream.summary(len(columns), columns.duplicates))


def create_run_from_columns(
    session: Session,
    plan: Plan,
    fixes: ingest.FixColumns,
    *,
    source: str,
    report: dict[str, Any],
    name: str | None,
) -> Run:
    """Store an uploaded track as a new run of ``plan``: one write transaction, all or nothing.

    Raises
    ------
    NotFoundError
        If the plan was deleted meanwhile.
    """
    # Read now: a rolled-back try expires the loaded rows.
    plan_id, organisation_id = plan.id, plan.organisation_id

    def work(s: Session) -> Run:
        run = Run(
            plan_id=plan_id,
            organisation_id=organisation_id,
            name=name,
            source=source,
            import_report=report,
        )
        s.add(run)
        s.flush()
        ingest.store_fixes(s, run.id, fixes, new_run=True)
        return run

    return write(session, work, parent=(Plan, plan_id, "plan"))


def create_run_from_track(
    session: Session, plan: Plan, track: ParsedTrack, *, name: str | None
) -> Run:
    """Store a parsed track as a new run of ``plan``, all or nothing, and commit."""
    return create_run_from_columns(
        session,
        plan,
        ingest.collect(track.fixes),
        source=track.format,
        report=json_ready(track.report),
        name=name,
    )


def create_live_run(session: Session, plan: Plan, *, name: str | None) -> Run:
    """Create an empty live run of ``plan`` (fixes come later) and commit."""
    plan_id, organisation_id = plan.id, plan.organisation_id

    def work(s: Session) -> Run:
        run = Run(
            plan_id=plan_id,
            organisation_id=organisation_id,
            name=name,
            source="live",
            import_report={},
        )
        s.add(run)
        s.flush()
        return run

    return write(session, work, parent=(Plan, plan_id, "plan"))


def add_fixes(session: Session, run: Run, fixes_in: Sequence[FixIn]) -> tuple[int, int]:
    """Store a batch posted by a live run's logger; return ``(stored, fix_count)``.

    Raises
    ------
    ConflictError
        If the run is an uploaded track, not a live run.
    TrackFormatError
        For a batch over :data:`MAX_FIXES_PER_BATCH` or a fix with a bad time (naming it).
    """
    if run.source != "live":
        raise ConflictError(
            f"run {run.id}: is an uploaded {run.source.upper()} track; fixes can be posted to "
            "live runs only (create one with POST /api/plans/{id}/runs and no file)"
        )
    if len(fixes_in) > MAX_FIXES_PER_BATCH:
        raise TrackFormatError(
            "body", f"has {len(fixes_in)} fixes; send at most {MAX_FIXES_PER_BATCH} per batch"
        )
    fixes = [
        TrackFix(
            t=parse_time(f.t, input_name=f"[{i}].t"),
            lat=f.lat,
            lon=f.lon,
            heading_deg=f.heading_deg,
            speed_mps=f.speed_mps,
            quality=f.quality,
            hdop=f.hdop,
            satellites=f.satellites,
        )
        for i, f in enumerate(fixes_in)
    ]
    columns = ingest.collect(fixes)
    run_id = run.id
    stored = write(
        session, lambda s: ingest.store_fixes(s, run_id, columns), parent=(Run, run_id, "run")
    )
    return stored, count_fixes(session, run_id)


# --- reading -------------------------------------------------------------------------------


def read_run(session: Session, run_id: int, access: Access) -> Run:
    """Return stored run ``run_id`` of the request's organisation.

    Raises
    ------
    NotFoundError
        If there is no such run (or it is another organisation's).
    """
    return read_stored(session, Run, run_id, access, kind="run")


def count_fixes(session: Session, run_id: int) -> int:
    """Return how many fixes run ``run_id`` has (its row's ``fix_count``: nothing is counted)."""
    return session.scalar(select(Run.fix_count).where(Run.id == run_id)) or 0


def load_track(session: Session, run_id: int) -> RunTrack:
    """Load a run's fixes in time order as arrays.

    The rows come straight from the driver's cursor into numpy (one query on the
    ``(run_id, t)`` key); going through SQLAlchemy's row objects costs more than the scoring
    for a day's log. Times (µs since 1970, below 2**53 until the year 2255) pass through a
    float64 array exactly.
    """
    connection = session.connection()
    dbapi_connection = connection.connection.dbapi_connection
    assert dbapi_connection is not None
    # On PostgreSQL a named (server-side) cursor, so the client holds one block at a time.
    postgres = connection.dialect.name == "postgresql"
    cursor: Any = (
        dbapi_connection.cursor(name="tillpath_load_track")
        if postgres
        else dbapi_connection.cursor()
    )
    try:
        # ``run_id`` is an int: formatting it in is safe, and spares the two paramstyles.
        cursor.execute(
            "SELECT t, lon, lat, heading_deg, speed_mps, hdop, satellites, quality FROM fixes "
            f"WHERE run_id = {int(run_id)} ORDER BY t"
        )
        # In blocks: the driver's row tuples of a whole day's log would take ~250 bytes a fix.
        # Each block's columns are appended to growing arrays (moved, not copied, as they
        # grow), so the columns are never held twice.
        t = array("q")
        floats = [array("d") for _ in range(6)]  # lon, lat, heading, speed, hdop, satellites
        quality: list[str | None] = []
        while rows := cursor.fetchmany(_LOAD_BLOCK_ROWS):
            block = np.array([row[:7] for row in rows], dtype=np.float64)  # None -> nan
            t.frombytes(block[:, 0].astype(np.int64).tobytes())
            for i, column in enumerate(floats, start=1):
                column.frombytes(np.ascontiguousarray(block[:, i]).tobytes())
            quality.extend(row[7] for row in rows)
            del block, rows
    finally:
        cursor.close()
    if not t:
        empty = np.array([], dtype=float)
        return RunTrack(np.array([], dtype=np.int64), empty, empty, empty, empty)
    lon, lat, heading, speed, hdop, satellites = (
        np.frombuffer(c, dtype=np.float64) for c in floats
    )
    return RunTrack(
        t=np.frombuffer(t, dtype=np.int64),
        lon=lon,
        lat=lat,
        heading_deg=heading,
        speed_mps=speed,
        quality=quality,
        hdop=hdop,
        satellites=satellites,
    )


def score_run(
    plan: Plan, track: RunTrack, *, threshold_m: float, live: bool = False
) -> TrackMetrics | None:
    """Score a run's track against its plan with :func:`navigation.score_track` (None if empty).

    A live run is scored on the part of the plan driven so far: waypoints not yet reached get
    no error.
    """
    if len(track.t) == 0:
        return None
    return score_track(
        coverage_plan_from_row(plan),
        track.time_s(),
        track.lon,
        track.lat,
        threshold_m=threshold_m,
        live=live,
    )


def list_runs(session: Session, plan_id: int, access: Access) -> RunList:
    """Return ``plan_id``'s runs, newest first, with their fix counts."""
    rows = session.execute(
        owned(Run, access)
        .add_columns(Run.fix_count)
        .where(Run.plan_id == plan_id)
        .order_by(Run.created_at.desc(), Run.id.desc())
    ).all()
    items = [
        RunSummary(
            id=run.id,
            plan_id=run.plan_id,
            name=run.name,
            source=run.source,
            created_at=run.created_at,
            fix_count=int(n),
        )
        for run, n in rows
    ]
    return RunList(items=items, total=len(items))


def _stride(n: int, limit: int) -> int:
    """Every how many fixes one is drawn, so that a track of ``n`` draws about ``limit``."""
    return max(1, math.ceil(n / limit))


def _thin(n: int, limit: int) -> npt.NDArray[np.int64]:
    if n <= limit:
        return np.arange(n)
    keep = np.arange(0, n, _stride(n, limit))
    return keep if keep[-1] == n - 1 else np.append(keep, n - 1)


def track_from_columns(columns: ingest.FixColumns) -> RunTrack:
    """Return an upload's parsed columns as a :class:`RunTrack` (the same arrays, no copy)."""
    return RunTrack(
        t=columns.t,
        lon=columns.lon,
        lat=columns.lat,
        heading_deg=columns.heading_deg,
        speed_mps=columns.speed_mps,
        quality=cast("Sequence[str | None]", columns.quality),  # an object array of them
        hdop=columns.hdop,
        satellites=columns.satellites,
    )


def run_view(
    session: Session,
    run: Run,
    *,
    threshold_m: float = DEFAULT_THRESHOLD_M,
    track: RunTrack | None = None,
) -> dict[str, Any]:
    """Everything ``GET /api/runs/{id}`` answers: the run, its metrics, track and stretches.

    Parameters
    ----------
    session : Session
    run : Run
    threshold_m : float
        Cross-track error above which a stretch is reported [m].
    track : RunTrack or None
        The run's fixes when the caller holds them already (an upload just stored: exactly
        what the database has), else they are loaded.
    """
    plan = session.get(Plan, run.plan_id)
    if plan is None:  # deleted meanwhile: the run went with it
        raise NotFoundError("run", run.id)
    if track is None:
        track = load_track(session, run.id)
    end_reads(session)  # no connection held while scoring
    metrics = score_run(plan, track, threshold_m=threshold_m, live=run.source == "live")
    n = len(track.t)
    view: dict[str, Any] = {
        "id": run.id,
        "plan_id": run.plan_id,
        "name": run.name,
        "source": run.source,
        "created_at": run.created_at,
        "fix_count": n,
        "import_report": run.import_report,
        "started_at": us_to_datetime(int(track.t[0])) if n else None,
        "last_fix": None,
        "metrics": json_ready(metrics.as_dict()) if metrics else None,
        "track": None,
        "stretches": {"type": "FeatureCollection", "features": []},
        "receiver": json_ready(receiver_report(track.quality, track.hdop, track.satellites)),
        "missed": {"type": "FeatureCollection", "features": []},
    }
    if not n:
        return view
    view["missed"] = json_ready(missed_ground_geojson(plan, track))
    view["last_fix"] = {
        "t": us_to_datetime(int(track.t[-1])),
        "lat": float(track.lat[-1]),
        "lon": float(track.lon[-1]),
        "heading_deg": _finite(track.heading_deg[-1]),
        "speed_mps": _finite(track.speed_mps[-1]),
    }
    time_s = track.time_s()
    keep = _thin(n, MAX_TRACK_POINTS)
    coords = np.column_stack([track.lon[keep], track.lat[keep]]).round(8).tolist()
    if len(coords) == 1:
        coords.append(coords[0])
    view["track"] = {
        "type": "Feature",
        "properties": {
            "kind": "track",
            "source": run.source,
            "time_s": time_s[keep].round(3).tolist(),
        },
        "geometry": {"type": "LineString", "coordinates": coords},
    }
    features = []
    stride = _stride(n, MAX_TRACK_POINTS)
    for stretch in metrics.stretches if metrics else ():
        lo = int(np.searchsorted(time_s, stretch.start_s, side="left"))
        hi = int(np.searchsorted(time_s, stretch.end_s, side="right"))
        # Drawn as finely as the track: every ``stride``-th fix, and the stretch's last.
        pick = np.arange(lo, hi, stride)
        if len(pick) and pick[-1] != hi - 1:
            pick = np.append(pick, hi - 1)
        part = np.column_stack([track.lon[pick], track.lat[pick]]).round(8).tolist()
        if len(part) == 1:
            part.append(part[0])
        features.append(
            {
                "type": "Feature",
                "properties": {"kind": "stretch", **json_ready(_stretch_dict(stretch))},
                "geometry": {"type": "LineString", "coordinates": part},
            }
        )
    view["stretches"]["features"] = features
    return view


def follow_up_plan(session: Session, run: Run, *, budget_s: float) -> Plan:
    """Plan the ground ``run`` missed (:func:`app.missed.plan_follow_up`), store it, commit.

    Raises
    ------
    ConflictError
        If the run has no fix yet, or missed nothing that can be planned.
    """
    plan = session.get(Plan, run.plan_id)
    if plan is None:
        raise NotFoundError("run", run.id)
    track = load_track(session, run.id)
    if len(track.t) == 0:
        raise ConflictError(f"run {run.id}: has no fix yet; there is no missed ground to plan")
    end_reads(session)  # no connection held while planning
    follow_up = plan_follow_up(plan, track, run_id=run.id, budget_s=budget_s)
    return add_row(session, follow_up, parent=(Plan, plan.id, "plan"))


def _stretch_dict(stretch: Any) -> dict[str, Any]:
    return {
        "start_s": stretch.start_s,
        "end_s": stretch.end_s,
        "duration_s": stretch.duration_s,
        "max_error_m": stretch.max_error_m,
        "line": stretch.line,
    }


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def export_run_gpx(session: Session, run: Run) -> ExportFile:
    """Write a run as GPX: its fixes as a timed ``<trk>``, the plan as ``<rte>``.

    Raises
    ------
    TrackFormatError
        If the run has no fix yet (a new live run): there is no track to write.
    """
    return export_run_track(session, run, "gpx")


def export_run_track(session: Session, run: Run, fmt: str) -> ExportFile:
    """Write a run as ``gpx`` or ``kml`` (the fixes as a ``gx:Track``), the plan with it.

    Raises
    ------
    ConflictError
        If the run has no fix yet.
    """
    plan = session.get(Plan, run.plan_id)
    if plan is None:
        raise NotFoundError("run", run.id)
    track = load_track(session, run.id)
    if len(track.t) == 0:
        raise ConflictError(f"run {run.id}: has no fix yet; there is no track to export")
    times = [us_to_datetime(int(t)) for t in track.t]
    title = run.name or f"run {run.id}"
    writer = plan_to_kml if fmt == "kml" else plan_to_gpx
    content = writer(
        coverage_plan_from_row(plan),
        name=f"{plan.name or f'plan {plan.id}'}: {title}",
        tracks=[GpxTrack(name=title, lon=track.lon.tolist(), lat=track.lat.tolist(), time=times)],
    )
    filename = f"{export_basename(plan)}-run-{run.id}.{fmt}"
    return ExportFile(content=content, media_type=EXPORT_TYPES[fmt][0], filename=filename)
