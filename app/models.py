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

from sqlalchemy import JSON, DateTime, Dialect, Integer, String
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
    """

    __tablename__ = "plans"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str | None] = mapped_column(String(PLAN_NAME_MAX_LENGTH))
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now, index=True)
    request: Mapped[dict[str, Any]] = mapped_column(JSON)
    stats: Mapped[dict[str, Any]] = mapped_column(JSON)
    waypoints: Mapped[list[dict[str, Any]]] = mapped_column(JSON)
    geojson: Mapped[dict[str, Any]] = mapped_column(JSON)
