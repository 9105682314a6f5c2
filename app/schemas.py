"""Pydantic schemas of the HTTP API: what comes in and what goes out.

They check types only (and that numbers are finite). The ranges of product.md §3 (interval,
angle, speed, headland passes, field size …) are the planner's to check, so that the API, the
command line and the planner give the same message for the same mistake.
"""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field

from app.models import PLAN_NAME_MAX_LENGTH
from app.track_fixes import MAX_HEADING_DEG, MAX_SPEED_MPS, MAX_TIME_TEXT, check_text


def _no_control(value: str | None) -> str | None:
    if value is not None:
        check_text(value)
    return value


#: A name as stored: no NUL or other control characters (PostgreSQL cannot store NUL).
NameText = Annotated[str | None, AfterValidator(_no_control)]

Objective = Literal["shortest_path", "fewest_lines"]
Pattern = Literal["boustrophedon", "snake", "spiral"]
ExportFormat = Literal["gpx", "geojson", "csv", "json", "kml", "waypoints", "plan", "gpkg"]

#: Largest page of ``GET /api/plans``.
MAX_PAGE_SIZE = 200

Position = tuple[float, float]


class VehicleSpec(BaseModel):
    """A vehicle as an object: a preset and the figures that differ from it (product.md §3a).

    Ranges are the planner's to check, so that every entry point gives the same message.
    """

    # Unknown fields pass through to the planner, which names them (same words as the CLI).
    model_config = ConfigDict(extra="allow", allow_inf_nan=False)

    preset: str = Field(
        default="hand_tractor",
        description="hand_tractor, paper_g1000, small_tractor or rover.",
    )
    width_m: float | None = Field(default=None, description="Body width, implement included [m].")
    length_m: float | None = Field(default=None, description="Body length [m].")
    track_m: float | None = Field(default=None, description="Distance between the wheels [m].")
    min_turn_radius_m: float | None = Field(
        default=None, description="Smallest turning radius [m]; 0: pivots about a wheel."
    )
    can_reverse: bool | None = Field(default=None, description="Whether turns may reverse.")
    turn_rate_dps: float | None = Field(default=None, description="Yaw rate turning [°/s].")

    def overrides(self) -> dict[str, Any]:
        """Return the preset and the fields that were given, for the planner."""
        return self.model_dump(exclude_none=True)


def _no_nul(value: str) -> str:
    """Refuse NUL characters: PostgreSQL text cannot hold them (it would be a 500)."""
    if "\x00" in value:
        raise ValueError("must not contain NUL characters")
    return value


#: Text a person typed that is stored: any characters but NUL.
StoredText = Annotated[str, AfterValidator(_no_nul)]


#: The paper's field (Ketewel, Bali) and its gates: the examples of the API's request bodies.
PAPER_FIELD_EXAMPLE: dict[str, Any] = {
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
}
PAPER_START_EXAMPLE: list[Any] = [115.29797264, -8.62652248]
PAPER_FINISH_EXAMPLE: list[Any] = [115.29816889, -8.62652064]


class PlanCreate(BaseModel):
    """Body of ``POST /api/plans`` and ``POST /api/plans/preview`` (product.md §3 inputs)."""

    model_config = ConfigDict(
        extra="forbid",
        allow_inf_nan=False,
        json_schema_extra={
            "examples": [
                {
                    "name": "Ketewel",
                    "field": PAPER_FIELD_EXAMPLE,
                    "interval_m": 4,
                    "start": PAPER_START_EXAMPLE,
                    "finish": PAPER_FINISH_EXAMPLE,
                }
            ]
        },
    )

    name: NameText = Field(
        default=None,
        max_length=PLAN_NAME_MAX_LENGTH,
        description="Plan name; default: the field's `name` property, if any.",
    )
    field: dict[str, Any] | None = Field(
        default=None,
        description=(
            "GeoJSON Polygon, Feature or one-polygon FeatureCollection, WGS84 [lon, lat]; holes "
            "are obstacles. Points with role start/finish in a FeatureCollection are used when "
            "`start`/`finish` are absent. Give this or `field_id`."
        ),
    )
    field_id: int | None = Field(
        default=None,
        ge=1,
        le=2**31 - 1,
        description="A field of the registry (`GET /api/fields`) to plan instead of `field`; "
        "its gates are the default start and finish, its name the default plan name.",
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
    implement_width_m: float | None = Field(
        default=None,
        description=(
            "Working width of the implement [m], 0.1–50: what one pass tills; coverage is "
            "measured with it. Default: `interval_m`."
        ),
    )
    vehicle: str | VehicleSpec = Field(
        default="hand_tractor",
        description=(
            "The machine that drives the path: a preset name (hand_tractor, paper_g1000, "
            "small_tractor, rover) or an object whose fields override its preset "
            "(product.md §3a)."
        ),
        examples=["hand_tractor", {"preset": "small_tractor", "min_turn_radius_m": 4.0}],
    )
    pattern: Pattern = Field(
        default="boustrophedon",
        description="boustrophedon (lines back and forth), snake (skipping lines so that "
        "turns need no loops) or spiral (rounds inward, the core back and forth).",
    )


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
    implement_width_m: float | None = None
    overlap_m: float | None = None
    vehicle: dict[str, Any] | None = None
    coverage_given_up_pp: float = Field(
        0.0, description="How far below the best heading's coverage the plan is, in points"
    )


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
    field_id: int | None = Field(default=None, description="The registry's field planned.")
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
    field_id: int | None = None
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


# --- Simulations (product.md §7) ---------------------------------------------------------

GpsPreset = Literal["m8n", "rtk"]
GuidanceMode = Literal["waypoint", "line"]

#: Largest seed accepted (numpy takes any non-negative integer; this keeps it in a JSON int).
MAX_SEED = 2**63 - 1
#: Most Monte Carlo runs one web request may ask for (a background job, product.md §13).
MAX_WEB_RUNS = 500


class SimulationCreate(BaseModel):
    """Body of ``POST /api/plans/{id}/simulations``: which tractor to simulate."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={"examples": [{"seed": 0, "gps": "m8n", "guidance": "waypoint"}]},
    )

    seed: int = Field(default=0, ge=0, le=MAX_SEED, description="Random seed; same seed, same run.")
    gps: GpsPreset = Field(
        default="m8n", description="GPS receiver: `m8n` (u-blox NEO-M8N, 2.5 m CEP) or `rtk`."
    )
    guidance: GuidanceMode = Field(
        default="waypoint",
        description="`waypoint` (the paper's law) or `line` (pure pursuit along the plan).",
    )
    runs: int = Field(
        default=1,
        ge=1,
        le=MAX_WEB_RUNS,
        description="Monte Carlo runs over seeds `seed … seed+runs-1`; more than one gives a "
        "summary of each metric and stores the run of median cross-track RMS.",
    )


class StretchRead(BaseModel):
    """A stretch of tillage line driven with the cross-track error over the threshold."""

    start_s: float
    end_s: float
    duration_s: float
    max_error_m: float
    line: int


class MetricsRead(BaseModel):
    """How well a track followed its plan (:class:`navigation.TrackMetrics`)."""

    completed: bool
    time_s: float
    distance_m: float
    fix_count: int
    on_line_share: float
    cross_track_max_m: float | None
    cross_track_rms_m: float | None
    cross_track_p95_m: float | None
    turn_cross_track_max_m: float | None = None
    turn_cross_track_rms_m: float | None = None
    waypoint_error_max_m: float | None
    waypoint_error_mean_m: float | None
    line_waypoint_error_max_m: float | None = None
    waypoint_errors_m: list[float | None]
    waypoints_reached: int | None = None
    plan_progress: float | None = None
    coverage_ratio: float
    coverage_of_driven_ratio: float | None = None
    implement_width_m: float | None = None
    threshold_m: float
    stretches: list[StretchRead]
    filter_rms_m: float | None = None
    gps_rms_m: float | None = None
    waypoint_error_estimate_max_m: float | None = None
    waypoint_error_estimate_mean_m: float | None = None
    line_waypoint_error_estimate_max_m: float | None = None
    waypoint_errors_estimate_m: list[float | None] | None = None
    nees_mean: float | None = None
    nees_dof: int | None = None
    nees_bounds_95: list[float] | None = None
    nees_within_bounds: bool | None = None
    nis_mean: float | None = None
    nis_dof: int | None = None
    nis_bounds_95: list[float] | None = None
    nis_within_bounds: bool | None = None
    compass_bias_estimate_deg: float | None = None
    compass_bias_true_deg: float | None = None


class SimulationRead(BaseModel):
    """A stored simulation: its configuration, the true track's metrics and the tracks."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    plan_id: int
    created_at: dt.datetime
    config: dict[str, Any]
    metrics: MetricsRead
    tracks: dict[str, Any] = Field(
        description="GeoJSON FeatureCollection: LineStrings `source` true, estimated, gps, "
        "with `time_s` per vertex."
    )


class SimulationSummary(BaseModel):
    """A simulation in a plan's list: its configuration and metrics, no tracks."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    plan_id: int
    created_at: dt.datetime
    config: dict[str, Any]
    metrics: MetricsRead


class SimulationList(BaseModel):
    """A plan's simulations, newest first."""

    items: list[SimulationSummary]
    total: int


# --- Field runs (product.md §8) ----------------------------------------------------------

RunSource = Literal["gpx", "csv", "nmea", "unicsv", "pos", "ubx", "kml", "live"]

#: Most fixes accepted in one ``POST /api/runs/{id}/fixes`` batch.
MAX_FIXES_PER_BATCH = 10_000


class FixIn(BaseModel):
    """One fix posted by the tractor's logger. Unknown keys (``hdop``, ``alt`` …) are ignored."""

    model_config = ConfigDict(
        extra="ignore",
        allow_inf_nan=False,
        json_schema_extra={
            "examples": [
                {"t": "2026-11-22T03:14:15.2Z", "lat": -8.62652, "lon": 115.29797},
                {"t": 1795318455.4, "lat": -8.62651, "lon": 115.29798, "heading_deg": 12.5},
            ]
        },
    )

    t: float | str = Field(
        description=(
            "Time: ISO 8601 (UTC if no offset) or Unix epoch seconds, 1980–2100; text of at "
            f"most {MAX_TIME_TEXT} characters."
        )
    )
    lat: float = Field(ge=-90, le=90, description="Latitude, WGS84 [deg].")
    lon: float = Field(ge=-180, le=180, description="Longitude, WGS84 [deg].")
    heading_deg: float | None = Field(
        default=None,
        ge=-MAX_HEADING_DEG,
        le=MAX_HEADING_DEG,
        description="Heading from true north [deg], -360 to 360.",
    )
    speed_mps: float | None = Field(
        default=None, ge=0, le=MAX_SPEED_MPS, description="Speed over ground [m/s], 0–100."
    )
    quality: Literal["rtk_fixed", "rtk_float", "dgps", "single", "dead_reckoning"] | None = Field(
        default=None, description="Fix quality, as the receiver reported it."
    )
    hdop: float | None = Field(default=None, ge=0, description="Horizontal dilution of precision.")
    satellites: int | None = Field(default=None, ge=0, le=255, description="Satellites used.")


class FixesAdded(BaseModel):
    """Answer to a batch of fixes: what was new, and how many the run now has."""

    run_id: int
    received: int = Field(description="Fixes in the batch.")
    stored: int = Field(description="New fixes stored (repeated timestamps are not stored again).")
    fix_count: int = Field(description="Fixes of the run after this batch.")


class LastFix(BaseModel):
    """The run's latest fix: where the tractor was last seen."""

    t: dt.datetime
    lat: float
    lon: float
    heading_deg: float | None
    speed_mps: float | None


class RunSummary(BaseModel):
    """A run in a plan's list: no track, no metrics."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    plan_id: int
    name: str | None
    source: RunSource
    created_at: dt.datetime
    fix_count: int


class RunList(BaseModel):
    """A plan's runs, newest first."""

    items: list[RunSummary]
    total: int


class RunRead(RunSummary):
    """A run with its metrics against the plan, its track and its error stretches."""

    import_report: dict[str, Any] = Field(
        description="What the file parser kept and dropped (empty for a live run)."
    )
    started_at: dt.datetime | None = Field(description="Time of the first fix.")
    last_fix: LastFix | None
    metrics: MetricsRead | None = Field(description="Null while the run has no fix.")
    metrics_fix_count: int | None = Field(
        default=None,
        description="Fixes that `metrics` and `stretches` cover: a read with `since` answers "
        "the last figures computed, which may lag a live run by a few seconds.",
    )
    track: dict[str, Any] | None = Field(
        description="GeoJSON LineString Feature of the fixes (thinned to at most 20,000 "
        "vertices for display), `time_s` per vertex from the first fix."
    )
    stretches: dict[str, Any] = Field(
        description="GeoJSON FeatureCollection: a LineString per stretch over the threshold."
    )
    receiver: dict[str, Any] = Field(
        default_factory=dict,
        description="How good the fixes were: `shares` of each fix quality (rtk_fixed, "
        "rtk_float, dgps, single, dead_reckoning, unknown), `hdop_median`, "
        "`satellites_median`, `accuracy` (centimetre, decimetre, metre, unknown), "
        "`metre_level` and a `note` saying what the figures are worth.",
    )
    missed: dict[str, Any] = Field(
        default_factory=dict,
        description="GeoJSON FeatureCollection: a Polygon per piece of the field the run's "
        "implement footprint did not cover (`kind: missed`, `area_m2`).",
    )
