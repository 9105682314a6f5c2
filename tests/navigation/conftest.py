"""Plans for the navigation tests: the paper's field (real planner) and hand-built ones."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import shapely

from planner import CoveragePlan, PathSegment, PlanStats, Waypoint, local_frame, plan_coverage
from planner.fields import parse_field_geojson

ROOT = Path(__file__).resolve().parents[2]
PAPER_FIELD = ROOT / "tests" / "data" / "paper_ketewel.geojson"
#: Near the paper's trial field in Bali.
BALI = (115.298, -8.6265)


def plan_paper_field(**options: object) -> CoveragePlan:
    """The paper's scenario planned for real: Ketewel field, 4 m, its start and finish."""
    spec = parse_field_geojson(json.loads(PAPER_FIELD.read_text(encoding="utf-8")))
    return plan_coverage(
        spec.field_lonlat,
        interval_m=4.0,
        start_lonlat=spec.start_lonlat,
        finish_lonlat=spec.finish_lonlat,
        **options,  # type: ignore[arg-type]
    )


def hand_plan(
    points_m: list[tuple[float, float]],
    roles: list[str],
    lines: list[int | None],
    *,
    field_m: list[tuple[float, float]],
    interval_m: float = 4.0,
    at: tuple[float, float] = BALI,
) -> CoveragePlan:
    """A plan built by hand in local metres (x east, y north) around ``at``."""
    frame = local_frame(*at)
    lon, lat = frame.to_lonlat_xy([p[0] for p in points_m], [p[1] for p in points_m])
    waypoints = tuple(
        Waypoint(seq=i, lon=float(lon[i]), lat=float(lat[i]), role=roles[i], line=lines[i])  # type: ignore[arg-type]
        for i in range(len(points_m))
    )
    segments = []
    for a, b in zip(waypoints[:-1], waypoints[1:], strict=True):
        is_line = a.role == "line_start" and b.role == "line_end" and a.line == b.line
        kind = (
            "line"
            if is_line
            else ("transit" if "start" == a.role or b.role == "finish" else "turn")
        )
        segments.append(
            PathSegment(
                kind=kind,
                index=a.line if is_line else None,
                lonlat=((a.lon, a.lat), (b.lon, b.lat)),
            )  # type: ignore[arg-type]
        )
    field = frame.to_lonlat(shapely.Polygon(field_m))
    stats = PlanStats(
        area_m2=float(shapely.Polygon(field_m).area),
        line_count=len({x for x in lines if x is not None}),
        waypoint_count=len(waypoints),
        working_length_m=0.0,
        turn_length_m=0.0,
        transit_length_m=0.0,
        path_length_m=0.0,
        coverage_ratio=0.0,
        angle_deg=0.0,
        estimated_time_s=0.0,
        planning_ms=0.0,
    )
    return CoveragePlan(
        field_lonlat=field,
        waypoints=waypoints,
        segments=tuple(segments),
        stats=stats,
        interval_m=interval_m,
    )


@pytest.fixture(scope="session")
def paper_plan() -> CoveragePlan:
    """The paper's scenario: Ketewel field, 4 m, with its start and finish, along its rows.

    The paper's plan has 4 lines along the rows (1°); the searched heading puts coverage
    first (R5) and may add a fifth line beside the last.
    """
    return plan_paper_field(angle_deg=1.0)


@pytest.fixture(scope="session")
def straight_plan() -> CoveragePlan:
    """One 100 m tillage line due north in a 4 m × 100 m strip."""
    return hand_plan(
        [(0.0, 0.0), (0.0, 100.0)],
        ["line_start", "line_end"],
        [0, 0],
        field_m=[(-2.0, 0.0), (2.0, 0.0), (2.0, 100.0), (-2.0, 100.0)],
    )


@pytest.fixture(scope="session")
def two_line_plan() -> CoveragePlan:
    """Start, two 30 m lines 4 m apart joined by a turn, finish: a 8 m × 30 m field."""
    return hand_plan(
        [(-2.0, -4.0), (-2.0, 0.0), (-2.0, 30.0), (2.0, 30.0), (2.0, 0.0), (2.0, -4.0)],
        ["start", "line_start", "line_end", "line_start", "line_end", "finish"],
        [None, 0, 0, 1, 1, None],
        field_m=[(-4.0, 0.0), (4.0, 0.0), (4.0, 30.0), (-4.0, 30.0)],
    )


@pytest.fixture(scope="session")
def make_plan():  # type: ignore[no-untyped-def]
    """The :func:`hand_plan` builder, for tests that need their own shapes."""
    return hand_plan


@pytest.fixture(scope="session")
def paper_spiral() -> CoveragePlan:
    """The paper's field at 4 m as a spiral: two rounds, a corner loop at each right angle."""
    return plan_paper_field(pattern="spiral")
