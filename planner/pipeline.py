"""plan_coverage(): validate, project, search the heading and order, build the route.

This module only chains the stages; the geometry lives in the stage modules.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import numpy.typing as npt
import shapely
from shapely import Polygon

from planner import angles, general, validation
from planner.fitted_choice import choose_convex
from planner.heading_coverage import estimated_coverage, ring_area_m2
from planner.lines import to_sweep
from planner.ordering import VariantLengths, score_headings
from planner.projection import LocalFrame, field_frame
from planner.route_builder import RouteBuilder, add_fitted_lines
from planner.spiral import order_spiral
from planner.turns import driving_time_s
from planner.types import (
    DEFAULT_SPEED_MPS,
    CoveragePlan,
    Objective,
    PathSegments,
    Pattern,
    PlanStats,
    Vehicle,
    Waypoints,
    vehicle_dict,
)
from planner.vehicles import resolve_vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Waypoints are rounded to 1e-9° (0.1 mm), so every export carries the same numbers.
LONLAT_DECIMALS = 9


def plan_coverage(
    field_lonlat: Polygon,
    *,
    interval_m: float,
    start_lonlat: Any = None,
    finish_lonlat: Any = None,
    angle_deg: float | None = None,
    objective: str = "shortest_path",
    headland_passes: int = 0,
    speed_mps: float = DEFAULT_SPEED_MPS,
    implement_width_m: float | None = None,
    vehicle: Any = None,
    pattern: str = "boustrophedon",
) -> CoveragePlan:
    """Plan the back-and-forth tillage path over a field for a vehicle and its implement.

    Parameters
    ----------
    field_lonlat : Polygon
        Field boundary, WGS84 ``(lon, lat)``.
    interval_m : float
        Distance between tillage lines, the puddler's working width [m], 0.2–50.
    start_lonlat, finish_lonlat : (float, float), optional
        Where the tractor enters and must end (within 5 km of the field).
    angle_deg : float, optional
        Line heading, degrees clockwise from true north in [0, 180); searched if None.
    objective : {"shortest_path", "fewest_lines"}
        What the heading and order search minimises.
    headland_passes : int
        Rounds along the inside of the boundary, 0–5, driven after the lines.
    speed_mps : float
        Working speed [m/s], for the time estimate.
    implement_width_m : float, optional
        Working width of the implement [m], 0.1–50; coverage (R4) is measured with it. Wider
        than the interval: the passes overlap; narrower: strips are left. Default: the
        interval.
    vehicle : str, mapping or Vehicle, optional
        The machine (product.md §3a): a preset name, ``{"preset": …, <field>: …}`` or a
        :class:`~planner.types.Vehicle`; default ``hand_tractor``. Its body stays inside the
        field and its turns are curves it can drive (R1).
    pattern : {"boustrophedon", "snake", "spiral"}
        Line order: neighbours back and forth, skipping lines so that turns need no loops
        (:func:`planner.ordering.order_snake`), or rounds inward with the core back and forth
        (:func:`planner.spiral.order_spiral`).

    Returns
    -------
    CoveragePlan

    Raises
    ------
    PlannerError
        With the input and the problem named, for any request that cannot be planned.

    Examples
    --------
    >>> from shapely import Polygon
    >>> field = Polygon([(115.298, -8.6265), (115.29813989, -8.62649238),
    ...                  (115.29814712, -8.62631751), (115.29800448, -8.62632237)])
    >>> plan = plan_coverage(field, interval_m=4.0, angle_deg=1.0)   # a hand tractor pivots
    >>> plan.stats.line_count, [w.role for w in plan.waypoints[:3]], plan.vehicle.preset
    (4, ['line_start', 'line_end', 'turn'], 'hand_tractor')
    """
    started = time.perf_counter()
    interval = validation.validate_interval(interval_m)
    fixed_heading = validation.validate_angle(angle_deg)
    goal = validation.validate_objective(objective)
    passes = validation.validate_headland_passes(headland_passes)
    speed = validation.validate_speed(speed_mps)
    machine = resolve_vehicle(vehicle)
    implement = validation.validate_implement_width(implement_width_m, interval)
    order = validation.validate_pattern(pattern)
    field_lonlat, area_m2 = validation.validate_field(field_lonlat)

    frame = field_frame(field_lonlat)
    field_local = frame.to_local(field_lonlat)
    start_xy, finish_xy = validation.validate_points(
        start_lonlat, finish_lonlat, frame=frame, field_local=field_local
    )
    # The one pattern dispatch: spiral rounds here; boustrophedon and snake differ only in
    # the order of the lines (and so the turns), below.
    if order == "spiral":
        spiral = order_spiral(
            field_local,
            interval_m=interval,
            start_xy=start_xy,
            finish_xy=finish_xy,
            objective=goal,
            vehicle=machine,
            implement_width_m=implement,
        )
        return _assemble(
            _with_finish(spiral.route, finish_xy),
            frame=frame,
            field_lonlat=field_lonlat,
            cells_local=spiral.cells_local,
            interval_m=interval,
            heading_deg=spiral.heading_deg,
            line_count=spiral.line_count,
            coverage_ratio=spiral.coverage_ratio,
            coverage_given_up_pp=0.0,
            speed_mps=speed,
            vehicle=machine,
            implement_width_m=implement,
            area_m2=area_m2,
            started=started,
        )
    # A convex field without holes or headland passes is one cell at every heading: the
    # closed-form planner takes it (tight budgets). Everything else is decomposed.
    if passes or not general.is_convex(field_local):
        return _plan_general(
            field_local,
            frame=frame,
            field_lonlat=field_lonlat,
            interval_m=interval,
            start_xy=start_xy,
            finish_xy=finish_xy,
            fixed_heading=fixed_heading,
            objective=goal,
            passes=passes,
            speed_mps=speed,
            vehicle=machine,
            implement_width_m=implement,
            pattern=order,
            area_m2=area_m2,
            started=started,
        )

    # get_coordinates, not np.asarray(….coords): the same array at a third of the cost.
    ring_xy = shapely.get_coordinates(shapely.orient_polygons(field_local).exterior)[:-1]
    headings = angles.candidate_headings(ring_xy, fixed_heading)

    # The ring rotated to the last headings scored: the search scores the coarse candidates
    # for length and then for coverage, the same array; one rotation serves both.
    rotated: list[tuple[FloatArray, tuple[FloatArray, FloatArray]]] = []

    def sweep_of(headings: FloatArray) -> tuple[FloatArray, FloatArray]:
        if rotated and rotated[0][0] is headings:
            return rotated[0][1]
        sweep = to_sweep(ring_xy[:, 0], ring_xy[:, 1], headings[:, None])
        rotated[:] = [(headings, sweep)]
        return sweep

    def lengths_of(headings: FloatArray) -> tuple[VariantLengths, IntArray]:
        return score_headings(ring_xy, headings, interval, start_xy, finish_xy, sweep_of(headings))

    field_m2 = float(field_local.area)
    ring_m2 = ring_area_m2(ring_xy)

    def coverage_of(headings: FloatArray) -> FloatArray:
        # Closed-form coverage of straight lines, less what fitting them for the vehicle
        # will take (ends on the machine area, pulled back for the turns).
        return estimated_coverage(
            ring_xy,
            headings,
            interval,
            sweep_of(headings),
            vehicle=machine,
            field_m2=field_m2,
            ring_m2=ring_m2,
        )

    choice = angles.search_headings(
        lengths_of, coverage_of, headings, goal, interval_m=interval, refine=fixed_heading is None
    )
    # One convex cell: its lines end where the vehicle's turns fit inside the field, and
    # the coverage rule is held on those lines (the search scored straight ones).
    picked = choose_convex(
        field_local,
        choice,
        interval_m=interval,
        implement_width_m=implement,
        vehicle=machine,
        pattern=order,
        objective=goal,
        start_xy=start_xy,
        finish_xy=finish_xy,
        lengths_of=lengths_of,
        fixed_heading=fixed_heading is not None,
    )
    heading, fit = picked.chosen.heading_deg, picked.chosen.fit
    route = RouteBuilder()
    if start_xy is not None:
        route.append("transit", None, np.array([start_xy]), "start")
    add_fitted_lines(route, heading, fit)
    route = _with_finish(route, finish_xy)
    return _assemble(
        route,
        frame=frame,
        field_lonlat=field_lonlat,
        cells_local=[field_local],
        interval_m=interval,
        heading_deg=heading,
        line_count=len(fit.u),
        coverage_ratio=picked.chosen.covered_m2 / float(field_local.area),
        coverage_given_up_pp=picked.coverage_given_up_pp,
        speed_mps=speed,
        vehicle=machine,
        implement_width_m=implement,
        area_m2=area_m2,
        started=started,
    )


def _plan_general(
    field_local: Polygon,
    *,
    frame: LocalFrame,
    field_lonlat: Polygon,
    interval_m: float,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    fixed_heading: float | None,
    objective: Objective,
    passes: int,
    speed_mps: float,
    vehicle: Vehicle,
    implement_width_m: float,
    pattern: Pattern,
    area_m2: float,
    started: float,
) -> CoveragePlan:
    """Plan a non-convex field or one with holes: cells, routed moves (issue 5)."""
    plan = general.plan_general(
        field_local,
        interval_m=interval_m,
        start_xy=start_xy,
        finish_xy=finish_xy,
        fixed_heading_deg=fixed_heading,
        objective=objective,
        headland_passes=passes,
        vehicle=vehicle,
        implement_width_m=implement_width_m,
        pattern=pattern,
    )
    return _assemble(
        _with_finish(plan.route, finish_xy),
        frame=frame,
        field_lonlat=field_lonlat,
        cells_local=plan.cells_local,
        interval_m=interval_m,
        heading_deg=plan.heading_deg,
        line_count=plan.line_count,
        coverage_ratio=plan.coverage_ratio,
        coverage_given_up_pp=plan.coverage_given_up_pp,
        speed_mps=speed_mps,
        vehicle=vehicle,
        implement_width_m=implement_width_m,
        area_m2=area_m2,
        started=started,
    )


def _with_finish(route: RouteBuilder, finish_xy: tuple[float, float] | None) -> RouteBuilder:
    """Return ``route`` with the finish point last, if there is one (its leg: :func:`_assemble`)."""
    if finish_xy is not None:
        route.x.append(float(finish_xy[0]))
        route.y.append(float(finish_xy[1]))
        route.roles.append("finish")
        route.lines.append(None)
    return route


#: The kinds of segment whose lengths the plan's figures report.
_LENGTH_KINDS = ("line", "turn", "transit", "headland", "round")


def _assemble(
    route: RouteBuilder,
    *,
    frame: LocalFrame,
    field_lonlat: Polygon,
    cells_local: list[Polygon],
    interval_m: float,
    heading_deg: float,
    line_count: int,
    coverage_ratio: float,
    coverage_given_up_pp: float,
    speed_mps: float,
    vehicle: Vehicle,
    implement_width_m: float,
    area_m2: float,
    started: float,
) -> CoveragePlan:
    x = np.fromiter(route.x, dtype=float, count=len(route.x))
    y = np.fromiter(route.y, dtype=float, count=len(route.y))
    if route.segments and route.roles[-1] == "finish":
        route.segments.append(("transit", None, len(x) - 2, len(x) - 1))
    # The waypoints and the cells' vertices in one projection: one pyproj call, not one per
    # geometry (the fixed cost of a call is most of a small plan's).
    cells = np.empty(len(cells_local), dtype=object)
    cells[:] = cells_local
    cell_xy = shapely.get_coordinates(cells)
    lon_all, lat_all = frame.to_lonlat_xy(
        np.concatenate([x, cell_xy[:, 0]]), np.concatenate([y, cell_xy[:, 1]])
    )
    lon, lat = lon_all[: len(x)], lat_all[: len(x)]
    cells_lonlat = shapely.set_coordinates(
        cells, np.stack([lon_all[len(x) :], lat_all[len(x) :]], axis=1)
    )
    lon_list = np.round(lon, LONLAT_DECIMALS).tolist()
    lat_list = np.round(lat, LONLAT_DECIMALS).tolist()
    waypoints = Waypoints(lon_list, lat_list, route.roles, route.lines)
    step = np.hypot(x[1:] - x[:-1], y[1:] - y[:-1])  # np.diff, without its wrapper's cost
    distance = np.concatenate(([0.0], np.cumsum(step)))
    # Length per kind of segment: each segment runs from its first waypoint to its last,
    # added in the segments' order (as np.bincount would; plain floats: a few segments).
    at = distance.tolist()
    lengths = dict.fromkeys(_LENGTH_KINDS, 0.0)
    for kind, _, first, last in route.segments:
        if kind in lengths:
            lengths[kind] += at[last] - at[first]
    segments = PathSegments(lon_list, lat_list, route.segments)
    path_length = float(distance[-1])
    estimated_time = driving_time_s(x, y, speed_mps=speed_mps, turn_rate_dps=vehicle.turn_rate_dps)
    stats = PlanStats(
        area_m2=round(area_m2, 2),
        line_count=line_count,
        waypoint_count=len(waypoints),
        working_length_m=round(lengths["line"] + lengths["headland"] + lengths["round"], 3),
        turn_length_m=round(lengths["turn"], 3),
        transit_length_m=round(lengths["transit"], 3),
        path_length_m=round(path_length, 3),
        coverage_ratio=round(min(coverage_ratio, 1.0), 6),
        angle_deg=round(heading_deg % 180.0, 6),
        estimated_time_s=round(estimated_time, 1),
        planning_ms=round((time.perf_counter() - started) * 1000.0, 3),
        implement_width_m=implement_width_m,
        overlap_m=round(implement_width_m - interval_m, 6),
        vehicle=vehicle_dict(vehicle),
        coverage_given_up_pp=round(coverage_given_up_pp, 4),
    )
    return CoveragePlan(
        field_lonlat=field_lonlat,
        waypoints=waypoints,
        segments=segments,
        stats=stats,
        interval_m=interval_m,
        cells_lonlat=tuple(cells_lonlat.tolist()),
        vehicle=vehicle,
        implement_width_m=implement_width_m,
    )
