"""SQLAlchemy 2.0 tables.

Geometry is stored as WGS84 GeoJSON in JSON columns, never projected. Plain ``JSON`` (not
PostgreSQL's ``JSONB``) keeps key order, so a stored plan reads back byte for byte as planned.

Tables that come later (simulations, runs, fixes) reference ``plans.id`` with
``ForeignKey("plans.id", ondelete="CASCADE")``; SQLite enforces it because every connection
turns ``foreign_keys`` on (see :mod:`app.db`).
"""

from __future__ import annotations

import datetime as dt
from typing import Any

from sqlalchemy import (
    JSON,
    BigInteger,
    DateTime,
    Dialect,
    Double,
    ForeignKey,
    Integer,
    SmallInteger,
    String,
    Text,
    text,
)
from sqlalchemy.orm import Mapped, mapped_column
from sqlalchemy.types import TypeDecorator

from app.db import Base

#: Longest plan name stored [characters].
PLAN_NAME_MAX_LENGTH = 200


def utc_now() -> dt.datetime:
    """Return the current time, timezone-aware in UTC."""
    return dt.datetime.now(dt.UTC)


class UTCDateTime(TypeDecorator[dt.datetime]):
    """A timestamp that always comes back timezone-aware in UTC.

    PostgreSQL stores ``timestamp with time zone``; SQLite has no time zones, so the value is
    stored as naive UTC and marked UTC again when read.
    """

    impl = DateTime(timezone=True)
    cache_ok = True

    def process_bind_param(self, value: dt.datetime | None, dialect: Dialect) -> dt.datetime | None:
        """Convert to UTC (naive for SQLite) on the way in."""
        if value is None:
            return None
        if value.tzinfo is None:
            raise ValueError("UTCDateTime needs a timezone-aware datetime")
        value = value.astimezone(dt.UTC)
        return value.replace(tzinfo=None) if dialect.name == "sqlite" else value

    def process_result_value(
        self, value: dt.datetime | None, dialect: Dialect
    ) -> dt.datetime | None:
        """Return aware UTC on the way out."""
        if value is None:
            return None
        if value.tzinfo is None:
            return value.replace(tzinfo=dt.UTC)
        return value.astimezone(dt.UTC)


class Plan(Base):
    """A stored coverage plan: what was asked, and what the planner answered.

    Attributes
    ----------
    id : int
        Primary key.
    name : str or None
        The plan's name, as given or taken from the field file.
    created_at : datetime
        When it was stored, UTC.
    request : dict
        The normalised request (field as a GeoJSON Polygon, start/finish resolved, defaults
        filled in): posting it again plans the same path.
    stats : dict
        The plan's figures (product.md §3, "Output").
    waypoints : list of dict
        ``{"seq", "lon", "lat", "role", "line"}`` in driving order.
    geojson : dict
        The plan as a GeoJSON FeatureCollection (product.md §4).
    organisation_id : int
        The organisation that owns it (product.md §12).
    field_id : int or None
        The registry's field it was planned on; None once that field is deleted (the plan
        keeps its own copy of the boundary in ``request``).
    """

    __tablename__ = "plans"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    organisation_id: Mapped[int] = mapped_column(
        ForeignKey("organisations.id", ondelete="CASCADE"), index=True
    )
    field_id: Mapped[int | None] = mapped_column(
        ForeignKey("fields.id", ondelete="SET NULL"), index=True
    )
    name: Mapped[str | None] = mapped_column(String(PLAN_NAME_MAX_LENGTH))
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now, index=True)
    request: Mapped[dict[str, Any]] = mapped_column(JSON)
    stats: Mapped[dict[str, Any]] = mapped_column(JSON)
    waypoints: Mapped[list[dict[str, Any]]] = mapped_column(JSON)
    geojson: Mapped[dict[str, Any]] = mapped_column(JSON)


class Simulation(Base):
    """A stored simulated run of a plan (product.md §7).

    Attributes
    ----------
    id : int
        Primary key.
    plan_id : int
        The simulated plan; deleting the plan deletes its simulations.
    created_at : datetime
        When it was run, UTC.
    config : dict
        ``{"seed", "gps", "guidance", "date"}``: running the simulator again with these gives
        the same run.
    metrics : dict
        :meth:`navigation.TrackMetrics.as_dict` of the true track.
    tracks : dict
        GeoJSON FeatureCollection of the true, estimated and GPS tracks
        (:func:`navigation.export.simulation_to_geojson`), one vertex per second.
    """

    __tablename__ = "simulations"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    organisation_id: Mapped[int] = mapped_column(
        ForeignKey("organisations.id", ondelete="CASCADE"), index=True
    )
    plan_id: Mapped[int] = mapped_column(ForeignKey("plans.id", ondelete="CASCADE"), index=True)
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)
    config: Mapped[dict[str, Any]] = mapped_column(JSON)
    metrics: Mapped[dict[str, Any]] = mapped_column(JSON)
    tracks: Mapped[dict[str, Any]] = mapped_column(JSON)


#: Where a run's fixes came from.
RUN_SOURCES = ("gpx", "csv", "nmea", "live")


class Run(Base):
    """A real run of a tractor on a plan: an uploaded log or a live stream (product.md §8).

    Attributes
    ----------
    id : int
        Primary key.
    plan_id : int
        The plan that was driven; deleting the plan deletes its runs and their fixes.
    name : str or None
        The uploaded file's name, or a name given to a live run.
    source : str
        ``gpx``, ``csv``, ``nmea`` (uploaded) or ``live`` (fixes posted by the logger).
    created_at : datetime
        When the run was created, UTC.
    import_report : dict
        What the parser kept and dropped (``{"format", "fixes", "skipped_lines", …}``); empty
        for a live run.
    fix_count : int
        The run's fixes, kept up to date by the transaction that stores each batch
        (:func:`app.ingest.store_fixes`), so that reading it counts nothing.
    """

    __tablename__ = "runs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    organisation_id: Mapped[int] = mapped_column(
        ForeignKey("organisations.id", ondelete="CASCADE"), index=True
    )
    plan_id: Mapped[int] = mapped_column(ForeignKey("plans.id", ondelete="CASCADE"), index=True)
    name: Mapped[str | None] = mapped_column(String(PLAN_NAME_MAX_LENGTH))
    source: Mapped[str] = mapped_column(String(8))
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)
    import_report: Mapped[dict[str, Any]] = mapped_column(JSON)
    fix_count: Mapped[int] = mapped_column(Integer, default=0, server_default=text("0"))


class Fix(Base):
    """One position of a run.

    The primary key ``(run_id, t)`` is the unique constraint that makes a retried batch store
    nothing twice (inserts use ``ON CONFLICT DO NOTHING``), and the index that reads a run's
    fixes in time order.

    Attributes
    ----------
    run_id : int
        The run; deleting it deletes its fixes.
    t : int
        Time of the fix [µs since 1970-01-01T00:00:00Z]: an integer, so that equal timestamps
        compare equal whatever text they came from.
    lat, lon : float
        WGS84 [deg].
    heading_deg : float or None
        Course over ground or compass heading, clockwise from true north [deg].
    speed_mps : float or None
        Speed over ground [m/s].
    quality : str or None
        Fix quality where the log says it (``rtk_fixed``, ``rtk_float``, ``dgps``, ``single``,
        ``dead_reckoning``; :data:`app.track_fixes.FIX_QUALITIES`).
    hdop : float or None
        Horizontal dilution of precision.
    satellites : int or None
        Satellites used in the fix.
    """

    __tablename__ = "fixes"

    run_id: Mapped[int] = mapped_column(ForeignKey("runs.id", ondelete="CASCADE"), primary_key=True)
    t: Mapped[int] = mapped_column(BigInteger, primary_key=True, autoincrement=False)
    lat: Mapped[float] = mapped_column(Double)
    lon: Mapped[float] = mapped_column(Double)
    heading_deg: Mapped[float | None] = mapped_column(Double)
    speed_mps: Mapped[float | None] = mapped_column(Double)
    quality: Mapped[str | None] = mapped_column(String(16))
    hdop: Mapped[float | None] = mapped_column(Double)
    satellites: Mapped[int | None] = mapped_column(SmallInteger)


class Field(Base):
    """A field of the registry (product.md §12): stored once, planned many times.

    Attributes
    ----------
    id : int
        Primary key.
    organisation_id : int
        The organisation that owns it.
    name : str
        What the farmer calls it.
    boundary : dict
        GeoJSON Polygon, WGS84; holes are obstacles.
    boundary_sha256 : str
        SHA-256 of the boundary's canonical JSON: a plan drawn on the same boundary reuses
        the field instead of storing a copy.
    start, finish : list of float or None
        ``[lon, lat]`` gates where the tractor enters and must end.
    notes : str
        Free text.
    created_at, updated_at : datetime
        UTC.
    """

    __tablename__ = "fields"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    organisation_id: Mapped[int] = mapped_column(
        ForeignKey("organisations.id", ondelete="CASCADE"), index=True
    )
    name: Mapped[str] = mapped_column(String(PLAN_NAME_MAX_LENGTH))
    boundary: Mapped[dict[str, Any]] = mapped_column(JSON)
    boundary_sha256: Mapped[str] = mapped_column(String(64), index=True)
    start: Mapped[list[float] | None] = mapped_column(JSON)
    finish: Mapped[list[float] | None] = mapped_column(JSON)
    notes: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now, index=True)
    updated_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)


# The workspace's tables (organisations, users, tokens) live in their own module; importing it
# here registers them on Base.metadata wherever the models are loaded (Alembic, the app).
from app import auth_models as _auth_models  # noqa: E402,F401

#: The states of a background job (product.md §13); the last three are final.
JOB_STATUSES = ("queued", "running", "done", "failed", "cancelled")
JOB_FINAL_STATUSES = ("done", "failed", "cancelled")


class Job(Base):
    """A background job: what was asked, how far it has got, and what came of it (§13).

    A job runs on the Dask engine (:mod:`app.jobs`). The worker that runs it holds a *lease*
    (``lease_token`` until ``lease_expires_at``, renewed as it reports progress); only the
    holder of the current lease may report progress or finish the job, so a job that is run
    again after a restart or a lost worker finishes once.

    Attributes
    ----------
    id : int
        Primary key.
    organisation_id : int
        The organisation that asked for it; deleting the organisation deletes its jobs.
    kind : str
        What to run (``simulation``, ``monte_carlo`` …; see :data:`app.jobs.JOB_KINDS`).
    params : dict
        What was asked: the kind's parameters, as JSON.
    status : str
        ``queued``, ``running``, ``done``, ``failed`` or ``cancelled``.
    progress : float
        How far it has got, 0–1.
    result : dict or None
        What the job produced (done only).
    result_url : str or None
        Where the result lives (``/api/simulations/7``), if it is a stored row.
    error : str or None
        Why it failed, naming the input and the problem (failed only).
    attempts : int
        How many times a worker started it.
    lease_owner : str or None
        The engine (one per server start) whose worker runs it.
    lease_token : str or None
        The current attempt's token.
    lease_expires_at : datetime or None
        When the lease lapses unless renewed; a running job past it is run again.
    created_at, started_at, updated_at, finished_at : datetime
        UTC.
    """

    __tablename__ = "jobs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    organisation_id: Mapped[int] = mapped_column(
        ForeignKey("organisations.id", ondelete="CASCADE"), index=True
    )
    kind: Mapped[str] = mapped_column(String(32))
    params: Mapped[dict[str, Any]] = mapped_column(JSON)
    status: Mapped[str] = mapped_column(String(16), default="queued", index=True)
    progress: Mapped[float] = mapped_column(Double, default=0.0)
    result: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    result_url: Mapped[str | None] = mapped_column(String(200))
    error: Mapped[str | None] = mapped_column(String(2000))
    attempts: Mapped[int] = mapped_column(Integer, default=0)
    lease_owner: Mapped[str | None] = mapped_column(String(64))
    lease_token: Mapped[str | None] = mapped_column(String(64))
    lease_expires_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime())
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)
    started_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime())
    updated_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)
    finished_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime())
