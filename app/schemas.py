"""Pydantic schemas of the HTTP API: what comes in and what goes out.

They check types only (and that numbers are finite). The ranges of product.md §3 (interval,
angle, speed, headland passes, field size …) are the planner's to check, so that the API, the
command line and the planner give the same message for the same mistake.
"""

from __future__ import annotations

import datetime as dt
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from app.models import PLAN_NAME_MAX_LENGTH

Objective = Literal["shortest_path", "fewest_lines"]
ExportFormat = Literal["gpx", "geojson", "csv", "json"]

#: Largest page of ``GET /api/plans``.
MAX_PAGE_SIZE = 200

Position = tuple[float, float]


class PlanCreate(BaseModel):
    """Body of ``POST /api/plans`` and ``POST /api/plans/preview`` (product.md §3 inputs)."""

    model_config = ConfigDict(
        extra="forbid",
        allow_inf_nan=False,
        json_schema_extra={
            "examples": [
                {
                    "name": "Ketewel",
                    "field": {
                        "type": "Polygon",
                        "coordinates": [
                            [
                                [115.298, -8.6265],
                                [115.29813989, -8.62649238],
                                [115.29814712, -8.62631751],
                                [115.29800448, -8.62632237],
                                [115.298, -8.6265],
                            ]
                        ],
                    },
                    "interval_m": 4,
                    "start": [115.29797264, -8.62652248],
                    "finish": [115.29816889, -8.62652064],
                }
            ]
        },
    )

    name: str | None = Field(
        default=None,
        max_length=PLAN_NAME_MAX_LENGTH,
        description="Plan name; default: the field's `name` property, if any.",
    )
    field: dict[str, Any] = Field(
        description=(
            "GeoJSON Polygon, Feature or one-polygon FeatureCollection, WGS84 [lon, lat]; holes "
            "are obstacles. Points with role start/finish in a FeatureCollection are used when "
            "`start`/`finish` are absent."
        )
    )
    interval_m: float = Field(description="Distance between tillage lines [m], 0.2–50.")
    start: Position | None = Field(default=None, description="[lon, lat] where the tractor enters.")
    finish: Position | None = Field(
        default=None, description="[lon, lat] where the tractor must end."
    )
    angle_deg: float | None = Field(
        default=None,
        description="Line heading, degrees clockwise from north, [0, 180); null: optimised.",
    )
    objective: Objective = "shortest_path"
    headland_passes: int = Field(default=0, description="Passes around the boundary, 0–5.")
    speed_mps: float = Field(default=0.56, description="Working speed [m/s], 0.05–10.")


class PlanStatsRead(BaseModel):
    """A plan's figures (product.md §3, "Output")."""

    model_config = ConfigDict(extra="allow")

    area_m2: float
    line_count: int
    waypoint_count: int
    working_length_m: float
    turn_length_m: float
    transit_length_m: float
    path_length_m: float
    coverage_ratio: float
    angle_deg: float
    estimated_time_s: float
    planning_ms: float


class WaypointRead(BaseModel):
    """One waypoint of the route, in driving order."""

    seq: int
    lon: float
    lat: float
    role: str
    line: int | None


class PlanRead(BaseModel):
    """A plan: stored (``id`` and ``created_at`` set) or previewed (both null)."""

    model_config = ConfigDict(from_attributes=True)

    id: int | None
    name: str | None
    created_at: dt.datetime | None
    request: dict[str, Any]
    stats: PlanStatsRead
    waypoints: list[WaypointRead]
    geojson: dict[str, Any]


class PlanSummary(BaseModel):
    """A stored plan in the list: no geometry."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    name: str | None
    created_at: dt.datetime
    stats: PlanStatsRead


class PlanList(BaseModel):
    """A page of stored plans, newest first, and how many there are in all."""

    items: list[PlanSummary]
    total: int


class Health(BaseModel):
    """Answer of ``GET /api/health``."""

    status: str
    database: str


class ErrorRead(BaseModel):
    """Every error answer: one sentence naming the input and the problem."""

    detail: str
