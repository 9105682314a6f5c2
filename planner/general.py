"""Plan any field, convex or not, with or without holes: cells, lines, order, routed moves.

The stages: headland passes (around the exterior and every hole) leave an inner area; the
best few headings by :mod:`planner.heading_search` are decomposed into cells
(:mod:`planner.decomposition`); each cell gets its lines (:func:`planner.lines.scan_cells`:
R2 and R3 per cell) and its four variants
(:mod:`planner.ordering`); and the cells are ordered (:mod:`planner.cell_order`). The winning
heading's route is then built: turns that would cut a corner follow the boundary, and every
move between cells, and to and between headland passes, is routed inside the field around the
holes (:mod:`planner.routing`). Everything here is in local metres;
:func:`planner.pipeline.plan_coverage` projects and exports.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt
import shapely
from shapely import LinearRing, MultiPolygon, Polygon

from planner import angles
from planner.cell_order import EXHAUSTIVE_MAX_CELLS, CellVariants, order_cells
from planner.coverage import Chains, cell_area, convex_chains, covered_area
from planner.decomposition import decompose_sweep
from planner.errors import PlanTooLargeError
from planner.heading_search import score_headings
from planner.headlands import headland_ring_sets, inner_parts
from planner.line_ends import FittedLines, fit_lines, machine_area, snake_skip
from planner.lines import LineScan, from_sweep, scan_cells
from planner.ordering import (
    order_boustrophedon,
    order_snake,
    variant_ends,
    variant_lengths,
)
from planner.routing import FieldRouter
from planner.turns import STEP_M, TurnEnds, turning_radius_m, vehicle_turns
from planner.types import Objective, Pattern, SegmentKind, Vehicle, WaypointRole
from planner.vehicles import resolve_vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: A vertex within this distance of the convex hull does not make a field non-convex [m].
CONVEXITY_TOLERANCE_M = 1e-3
#: Headings planned in full after the cheap scoring.
FULL_PLANS = 6
#: ... plus this many of the best headings by the other ranking (line count or estimate).
EXTRA_PLANS = 1
#: Beyond this many turn-backs (about as many cells) only the best heading is planned in full.
MANY_TURN_BACKS = 200
#: ``move_m(exits, entries)``: lengths [m] of the moves from every exit to every entry.
MoveCost = Callable[[FloatArray, FloatArray], FloatArray]
#: Grid that footprint unions snap to [m] (see :func:`plan_general`).
UNION_GRID_M = 1e-6
#: Inner-area parts smaller than this are dropped (slivers between headland passes) [m²].
_SLIVER_M2 = 1e-6


@dataclass
class RouteBuilder:
    """A route under construction, local [m], with the role and line of every point.

    ``segments`` holds ``(kind, index, first waypoint, last waypoint)``; a segment shares its
    end points with its neighbours.
    """

    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    roles: list[WaypointRole] = field(default_factory=list)
    lines: list[int | None] = field(default_factory=list)
    segments: list[tuple[SegmentKind, int | None, int, int]] = field(default_factory=list)

    def here(self) -> tuple[float, float] | None:
        """Return the last point, or None if the route is empty."""
        return (self.x[-1], self.y[-1]) if self.x else None

    def append(
        self,
        kind: SegmentKind,
        index: int | None,
        points: FloatArray,
        role: WaypointRole,
        line: int | None = None,
        *,
        last_role: WaypointRole | None = None,
    ) -> None:
        """Add a segment through ``points``, joined to the route's last point if any.

        If the route is not empty, ``points[0]`` must be its last point (it is not repeated).
        """
        first = len(self.x) - 1 if self.x else 0
        new = points[1:] if self.x else points
        roles = [role] * len(new)
        if last_role is not None and roles:
            roles[-1] = last_role
        self.x.extend(new[:, 0].tolist())
        self.y.extend(new[:, 1].tolist())
        self.roles.extend(roles)
        self.lines.extend([line] * len(new))
        if len(self.x) - 1 > first:
            self.segments.append((kind, index, first, len(self.x) - 1))


@dataclass(frozen=True, slots=True)
class GeneralPlan:
    """A planned route in local metres.

    Attributes
    ----------
    route : RouteBuilder
        Waypoints, roles, lines and segments; the finish leg is not in it yet.
    heading_deg : float
    line_count : int
    cells_local : list of Polygon
        The cells in driving order.
    coverage_ratio : float
        R4 with the headland passes.
    lines_coverage_ratio : float
        R4 of the tillage lines alone.
    """

    route: RouteBuilder
    heading_deg: float
    line_count: int
    cells_local: list[Polygon]
    coverage_ratio: float
    lines_coverage_ratio: float
    coverage_given_up_pp: float = 0.0


@dataclass(frozen=True, slots=True)
class _Cell:
    u_ring: FloatArray
    v_ring: FloatArray
    chains: Chains
    lines: slice


@dataclass(frozen=True, slots=True)
class _Candidate:
    heading_deg: float
    cells: list[_Cell]
    scan: LineScan
    variants: CellVariants
    working_m: float
    order: list[tuple[int, int]]
    length_m: float
    line_count: int
    covered_m2: float


def plan_general(
    field_local: Polygon,
    *,
    interval_m: float,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    fixed_heading_deg: float | None,
    objective: Objective,
    headland_passes: int,
    vehicle: Vehicle | None = None,
    implement_width_m: float | None = None,
    pattern: Pattern = "boustrophedon",
) -> GeneralPlan:
    """Plan a field of any shape: headland passes, cells, lines, order and routed moves.

    Parameters
    ----------
    field_local : Polygon
        Valid field, local frame [m], holes allowed.
    interval_m : float
        Distance between lines [m].
    start_xy, finish_xy : tuple of float or None
        Where the tractor comes from and must end, local [m].
    fixed_heading_deg : float or None
        Line heading [deg]; searched if None.
    objective : {"shortest_path", "fewest_lines"}
    headland_passes : int
        Rounds around the exterior and every hole, driven after the lines.

    Returns
    -------
    GeneralPlan

    Raises
    ------
    InvalidParameterError
        If the field is too narrow for the headland passes.
    PlanTooLargeError
        If every heading needs more than :data:`planner.angles.MAX_LINES` lines.

    Examples
    --------
    >>> from shapely import Polygon
    >>> ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    >>> plan = plan_general(ell, interval_m=4.0, start_xy=None, finish_xy=None,
    ...                     fixed_heading_deg=135.0, objective="shortest_path", headland_passes=0)
    >>> len(plan.cells_local), plan.line_count, round(plan.lines_coverage_ratio, 3)
    (3, 23, 0.911)
    """
    field_local = shapely.orient_polygons(field_local)
    d = float(interval_m)
    machine = resolve_vehicle(vehicle)
    implement = d if implement_width_m is None else float(implement_width_m)
    width = machine.width_m
    rings = headland_ring_sets(
        field_local,
        passes=headland_passes,
        interval_m=d,
        vehicle_width_m=width,
        turning_radius_m=turning_radius_m(machine),
    )
    area = machine_area(field_local, machine)
    if headland_passes:
        parts = inner_parts(
            field_local, passes=headland_passes, interval_m=d, vehicle_width_m=width
        )
    else:
        parts = list(shapely.get_parts(area))
        parts.sort(key=lambda p: (-p.area, p.bounds))
    # Moves between cells stay in the machine area; if a neck splits it, in the field.
    router = FieldRouter(area if isinstance(area, Polygon) else field_local)
    # Lines half an interval inside the field: less than that inside the machine area.
    edge = d / 2.0 if headland_passes else max((d - width) / 2.0, d / 4.0)
    after_lines = _first_ring_point(rings[-1]) if rings else finish_xy

    best: _Candidate | None = None
    given_up_pp = 0.0
    if parts:
        exterior = np.asarray(field_local.exterior.coords)[:-1]
        headings = angles.candidate_headings(exterior, fixed_heading_deg)
        scores = score_headings(parts, headings, d)
        affordable = scores.pieces <= angles.MAX_LINES
        if not affordable.any():
            raise PlanTooLargeError(
                "interval_m",
                f"at {d:g} m the field needs at least {int(scores.pieces.min()):,} tillage "
                f"lines; tillpath plans at most {angles.MAX_LINES:,}: choose a wider interval "
                "or a smaller field",
            )
        headings, scores = headings[affordable], scores.subset(affordable)
        estimate = np.round(scores.path_estimate_m(d), 6)
        # Coverage first (R5): headings the estimate puts well below the best are not
        # planned; the planned ones are then held to the rule exactly.
        missed = np.round(scores.missed_m2, 6)
        hopeful = missed <= missed.min() + 2.0 * angles.COVERAGE_SLACK * float(
            sum(p.area for p in parts)
        )
        by_estimate = np.lexsort((headings, np.where(hopeful, estimate, np.inf)))[:FULL_PLANS]
        by_lines = np.lexsort((headings, estimate, np.where(hopeful, scores.pieces, 2**62)))
        by_coverage = np.lexsort((headings, estimate, missed))[:1]
        # Both lists for either objective: the estimate misjudges some fields (turns that
        # climb a slanted end), and the fewest-lines heading is often the shortest too.
        first, second = by_estimate, by_lines[:FULL_PLANS]
        if objective == "fewest_lines":
            first, second = by_lines[:FULL_PLANS], by_estimate
        ranked = list(
            dict.fromkeys([*first.tolist(), *second[:EXTRA_PLANS].tolist(), *by_coverage.tolist()])
        )
        if scores.turn_backs[ranked[0]] > MANY_TURN_BACKS:
            ranked = ranked[:1]  # a jagged boundary: hundreds of cells per heading
        candidates = [
            _plan_heading(parts, float(headings[a]), d, start_xy, after_lines, edge) for a in ranked
        ]
        best_covered = max(c.covered_m2 for c in candidates)
        slack_m2 = angles.COVERAGE_SLACK * float(field_local.area) + 1e-9
        for candidate in candidates:
            if candidate.covered_m2 < best_covered - slack_m2:
                continue
            if best is None or _better(candidate, best, objective):
                best = candidate
        if best is not None:
            given_up_pp = (best_covered - best.covered_m2) / float(field_local.area) * 100.0
            # Round holes a straight line is a poor guess of a move between cells: the
            # winner's few cells are reordered with routed moves (many cells cost too much).
            routed = bool(field_local.interiors) and len(best.cells) <= EXHAUSTIVE_MAX_CELLS
            best = _reorder(best, start_xy, after_lines, router.distances if routed else None)
            if rings:
                best = _reach_headland(best, d)

    route = RouteBuilder()
    if start_xy is not None:
        route.append("transit", None, np.array([start_xy]), "start")
    cells_local: list[Polygon] = []
    line_count = 0
    heading = 0.0 if fixed_heading_deg is None else float(fixed_heading_deg)
    fitted: list[FittedLines] = []
    if best is not None:
        heading = best.heading_deg
        fitted = _add_cells(
            route,
            best,
            router,
            vehicle=machine,
            pattern=pattern,
            interval_m=d,
            turning_room=area if headland_passes else None,
        )
        line_count = sum(len(fit.u) for fit in fitted)
        for cell_index, _ in best.order:
            cell = best.cells[cell_index]
            x, y = from_sweep(cell.u_ring, cell.v_ring, heading)
            cells_local.append(Polygon(np.stack([x, y], axis=1)))
    for pass_index in reversed(range(len(rings))):
        ordered = _ring_order(rings[pass_index], route.here())
        for ring_index, ring in enumerate(ordered):
            # The last round goes on to the point nearest the finish, so the tractor leaves
            # from the headland instead of crossing the tilled field.
            last = pass_index == 0 and ring_index == len(ordered) - 1
            _add_headland(route, ring, pass_index, router, end_near=finish_xy if last else None)

    field_area = float(field_local.area)
    lines_covered = _lines_covered(best, fitted, field_local, area, heading, implement)
    covered = lines_covered
    if rings:
        # Headland passes: the whole union, exactly (a few rings and the lines' boxes).
        passes_union = shapely.union_all(
            [
                r.buffer(implement / 2.0, cap_style="flat", join_style="mitre")
                for pass_rings in rings
                for r in pass_rings
            ]
        )
        boxes = line_footprints(fitted, heading, implement)
        # GEOS's cascaded union loses area where boxes share edges to within rounding (a
        # 7 % loss seen on a random field): a 1 µm grid makes the shared edges exact.
        everything = shapely.union_all([passes_union, *boxes], grid_size=UNION_GRID_M)
        covered = float(shapely.intersection(field_local, everything).area)
    return GeneralPlan(
        route=route,
        heading_deg=heading,
        line_count=line_count,
        cells_local=cells_local,
        coverage_ratio=min(covered / field_area, 1.0),
        lines_coverage_ratio=min(lines_covered / field_area, 1.0),
        coverage_given_up_pp=max(given_up_pp, 0.0),
    )


def _lines_covered(
    plan: _Candidate | None,
    fitted: list[FittedLines],
    field_local: Polygon,
    area: Polygon | MultiPolygon,
    heading: float,
    width_m: float,
) -> float:
    """Area of the field the lines' footprints cover (R4) [m²].

    Inside each cell (a piece of the machine area) exactly, by its chains. Beyond the cells
    lies the band half a vehicle wide along the boundary: the outermost line of a cell may
    till a strip of it, which is added with shapely (two boxes per cell). The corners of
    footprints that poke past a slanted line end are not counted (a slight underestimate).
    """
    if plan is None or not fitted:
        return 0.0
    total = 0.0
    outer: list[FittedLines] = []
    for (cell_index, _), fit in zip(plan.order, fitted, strict=True):
        if len(fit.u) == 0:
            continue
        cell = plan.cells[cell_index]
        order = np.argsort(fit.u, kind="stable")
        u, a, b = fit.u[order], fit.v_start[order], fit.v_end[order]
        total += covered_area(cell.chains, u, np.minimum(a, b), np.maximum(a, b), width_m)
        ends = order[[0, -1]]
        outer.append(replace(fit, u=fit.u[ends], v_start=fit.v_start[ends], v_end=fit.v_end[ends]))
    boxes = np.asarray(line_footprints(outer, heading, width_m))
    if len(boxes):
        shapely.prepare(area)
        out = boxes[~shapely.contains(area, boxes)]
        if len(out):
            reach = shapely.union_all(out, grid_size=UNION_GRID_M)
            band = shapely.intersection(field_local, reach).area
            total += float(band - shapely.intersection(area, reach).area)
    return total


def line_footprints(fitted: list[FittedLines], heading: float, width_m: float) -> list[Polygon]:
    """Footprints of the fitted lines (R4): rectangles ``width_m`` wide, flat ends, local."""
    if not fitted:
        return []
    u = np.concatenate([f.u for f in fitted])
    a = np.concatenate([f.v_start for f in fitted])
    b = np.concatenate([f.v_end for f in fitted])
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    half = width_m / 2.0
    cu = np.stack([u - half, u + half, u + half, u - half], axis=1)
    cv = np.stack([lo, lo, hi, hi], axis=1)
    x, y = from_sweep(cu, cv, heading)
    boxes = np.asarray(shapely.polygons(np.stack([x, y], axis=2)))
    return list(boxes[hi > lo])


def is_convex(field_local: Polygon) -> bool:
    """Whether ``field_local`` has no holes and no vertex more than 1 mm inside its hull.

    Such a field is one cell at every heading, and the convex planner takes it.

    Examples
    --------
    >>> from shapely import Polygon, box
    >>> is_convex(box(0, 0, 10, 10)), is_convex(Polygon([(0, 0), (9, 0), (9, 9), (5, 2)]))
    (True, False)
    """
    if field_local.interiors:
        return False
    hull = field_local.convex_hull
    if not isinstance(hull, Polygon):
        return False
    depth_m = shapely.hausdorff_distance(field_local.exterior, hull.exterior)
    return bool(depth_m <= CONVEXITY_TOLERANCE_M)


def _better(candidate: _Candidate, best: _Candidate, objective: Objective) -> bool:
    if objective == "fewest_lines" and candidate.line_count != best.line_count:
        return candidate.line_count < best.line_count
    return candidate.length_m < best.length_m - 1e-6


def _plan_heading(
    parts: list[Polygon],
    heading: float,
    d: float,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    edge_m: float,
) -> _Candidate:
    """Decompose, scan and order the cells at one heading; turns and moves straight."""
    rings = [ring for part in parts for ring in decompose_sweep(part, heading)]
    scan = scan_cells(rings, d, edge_m=edge_m)
    cells = [
        _Cell(
            u_ring,
            v_ring,
            convex_chains(u_ring, v_ring),
            slice(scan.offsets[c], scan.offsets[c + 1]),
        )
        for c, (u_ring, v_ring) in enumerate(rings)
    ]
    lengths = variant_lengths(scan, None, None)
    eu, ev, xu, xv = variant_ends(scan)
    entry = np.stack(from_sweep(eu, ev, heading), axis=2)
    exit_ = np.stack(from_sweep(xu, xv, heading), axis=2)
    variants = CellVariants(entry, exit_, lengths.turns)
    working = float(lengths.working.sum())
    order = order_cells(variants, start_xy, finish_xy, improve=False)
    length = working + _order_length(variants, order, start_xy, finish_xy, None)
    covered = sum(
        covered_area(c.chains, scan.u[c.lines], scan.v_lo[c.lines], scan.v_hi[c.lines], d)
        for c in cells
    )
    return _Candidate(heading, cells, scan, variants, working, order, length, len(scan.u), covered)


def _reach_headland(plan: _Candidate, d: float) -> _Candidate:
    """Lengthen each line so that its whole footprint reaches the headland's inner edge.

    A line ends where it meets the cell's chain, but a slanted chain leaves an untilled
    triangle beside that end. With headland passes, every point within ``d / 2`` of the
    inner area lies in the headland band, inside the field; so each end moves out to the
    farthest the chain reaches across the footprint's width (``u ± d / 2``), and the
    footprint covers the inner area up to its edge. Turns and coverage follow the new ends.
    """
    scan = plan.scan
    v_lo, v_hi = scan.v_lo.copy(), scan.v_hi.copy()
    half = d / 2.0
    for cell in plan.cells:
        k = cell.lines
        u = scan.u[k]
        left = np.maximum(u - half, cell.chains.u_min)
        right = np.minimum(u + half, cell.chains.u_max)
        c = cell.chains
        top = np.maximum(np.interp(left, c.hi_u, c.hi_v), np.interp(right, c.hi_u, c.hi_v))
        bottom = np.minimum(np.interp(left, c.lo_u, c.lo_v), np.interp(right, c.lo_u, c.lo_v))
        for chain_u, chain_v, target, pick in (
            (c.hi_u, c.hi_v, top, np.maximum),
            (c.lo_u, c.lo_v, bottom, np.minimum),
        ):
            first = np.searchsorted(u, chain_u - half, side="left")
            stop = np.searchsorted(u, chain_u + half, side="right")
            for shift in range(3):
                line = first + shift
                ok = line < stop
                pick.at(target, line[ok], chain_v[ok])
        v_hi[k] = np.maximum(v_hi[k], top)
        v_lo[k] = np.minimum(v_lo[k], bottom)
    longer = LineScan(scan.headings_deg, scan.offsets, scan.u, v_lo, v_hi)
    return _Candidate(
        plan.heading_deg,
        plan.cells,
        longer,
        plan.variants,
        plan.working_m,
        plan.order,
        plan.length_m,
        plan.line_count,
        plan.covered_m2,
    )


def _reorder(
    plan: _Candidate,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    move_m: MoveCost | None,
) -> _Candidate:
    """Return the winning heading with its cell order improved (by ``move_m`` if given)."""
    order = order_cells(plan.variants, start_xy, finish_xy, improve=True, move_m=move_m)
    length = plan.working_m + _order_length(plan.variants, order, start_xy, finish_xy, move_m)
    before = plan.working_m + _order_length(plan.variants, plan.order, start_xy, finish_xy, move_m)
    if length >= before:
        return plan
    return _Candidate(
        plan.heading_deg,
        plan.cells,
        plan.scan,
        plan.variants,
        plan.working_m,
        order,
        length,
        plan.line_count,
        plan.covered_m2,
    )


def _order_length(
    cells: CellVariants,
    order: list[tuple[int, int]],
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    move_m: MoveCost | None,
) -> float:
    total = sum(float(cells.inner_m[c, w]) for c, w in order)
    points = [cells.entry_xy[c, w] for c, w in order]
    if len(order) > 1:
        exits = np.asarray([cells.exit_xy[c, w] for c, w in order[:-1]])
        entries = np.asarray([cells.entry_xy[c, w] for c, w in order[1:]])
        if move_m is None:
            total += float(np.hypot(*(entries - exits).T).sum())
        else:
            total += float(np.trace(move_m(exits, entries)))
    if start_xy is not None:
        total += float(np.hypot(*(points[0] - np.asarray(start_xy))))
    if finish_xy is not None:
        c, w = order[-1]
        total += float(np.hypot(*(cells.exit_xy[c, w] - np.asarray(finish_xy))))
    return total


def _add_cells(
    route: RouteBuilder,
    plan: _Candidate,
    router: FieldRouter,
    *,
    vehicle: Vehicle,
    pattern: Pattern,
    interval_m: float,
    turning_room: Polygon | MultiPolygon | None = None,
) -> list[FittedLines]:
    """Append every cell's lines and turns, and the moves between cells, to ``route``.

    Each cell's lines are ordered (back and forth, or snake), then their ends are pulled
    back until the vehicle's turns fit the cell (:func:`planner.line_ends.fit_lines`), or,
    with headland passes, the machine area beyond the cell (``turning_room``): the turns
    swing out over the headland, as a tractor turns on the headland it then tills.
    Returns the fitted lines of every cell, in driving order (sweep frame of the heading).
    """
    heading = plan.heading_deg
    scan = plan.scan
    skip = snake_skip(vehicle, interval_m) if pattern == "snake" else 1
    first_index = 0
    fitted: list[FittedLines] = []
    for cell_index, variant in plan.order:
        cell = plan.cells[cell_index]
        k = cell.lines
        u, lo, hi = scan.u[k], scan.v_lo[k], scan.v_hi[k]
        n = len(u)
        if skip > 1:
            index, up = order_snake(n, variant, skip=skip)
        else:
            index, up = order_boustrophedon(n, variant)
        fit = fit_lines(
            u[index],
            np.where(up, lo[index], hi[index]),
            np.where(up, hi[index], lo[index]),
            index,
            machine=_room_chains(cell, heading, turning_room),
            vehicle=vehicle,
        )
        if len(fit.u) == 0:
            fitted.append(fit)  # one entry per cell, in driving order
            continue
        # Lines the turns could not reach are gone: number the rest left to right.
        rank = np.argsort(np.argsort(fit.index, kind="stable"), kind="stable")
        fit = replace(fit, index=(first_index + rank).astype(np.int64))
        fitted.append(fit)
        x0, y0 = from_sweep(fit.u[0], fit.v_start[0], heading)
        target = (float(x0), float(y0))
        here = route.here()
        joined = False
        if here is not None and route.roles[-1] != "start":
            rising = bool(fit.v_end[0] >= fit.v_start[0])
            move = _move(route, target, rising, heading, router, vehicle)
            route.append("turn", None, move, "turn")
            joined = True
        add_fitted_lines(route, heading, fit, joined=joined)
        first_index += len(fit.u)
    return fitted


def _room_chains(
    cell: _Cell, heading: float, turning_room: Polygon | MultiPolygon | None
) -> Chains:
    """Return the chains a cell's turns must stay within: the machine area over its span.

    The piece of ``turning_room`` over the cell's ``u``-range that holds the cell, if it is
    one simple sweep-monotone polygon; else (or without ``turning_room``) the cell itself.
    """
    if turning_room is None:
        return cell.chains
    c = cell.chains
    theta = math.radians(heading)
    cos_t, sin_t = math.cos(theta), math.sin(theta)

    def to_uv(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        return x * cos_t - y * sin_t, x * sin_t + y * cos_t

    room = shapely.transform(turning_room, lambda xy: np.stack(to_uv(xy[:, 0], xy[:, 1]), 1))
    big = 1e7
    strip = shapely.box(c.u_min, -big, c.u_max, big)
    middle = shapely.Point(
        (c.u_min + c.u_max) / 2.0,
        (
            float(np.interp((c.u_min + c.u_max) / 2.0, c.lo_u, c.lo_v))
            + float(np.interp((c.u_min + c.u_max) / 2.0, c.hi_u, c.hi_v))
        )
        / 2.0,
    )
    for piece in shapely.get_parts(shapely.intersection(room, strip)):
        if not isinstance(piece, Polygon) or piece.interiors or not piece.covers(middle):
            continue
        ring = np.asarray(shapely.orient_polygons(piece).exterior.coords)[:-1]
        chains = convex_chains(ring[:, 0], ring[:, 1])
        # Sweep-monotone exactly when the area between the two chains is the piece's area.
        if abs(cell_area(chains) - piece.area) <= 1e-6 * piece.area + 1e-6:
            return chains
    return cell.chains


def _move(
    route: RouteBuilder,
    target: tuple[float, float],
    up: bool,
    heading: float,
    router: FieldRouter,
    vehicle: Vehicle,
) -> FloatArray:
    """Plan the move from the route's last line end to another cell's first line start.

    The vehicle's own turn (a Dubins or pivot curve from pose to pose) if it stays inside the
    machine area, else the shortest path inside it, with points at most 0.5 m apart (its
    corners are turned on the spot or as tight as the vehicle can).
    """
    here = np.array([route.x[-1], route.y[-1]])
    before = np.array([route.x[-2], route.y[-2]]) if len(route.x) > 1 else here
    if route.roles[-1] == "line_end" and np.hypot(*(here - before)) > 1e-9:
        yaw0 = math.atan2(here[1] - before[1], here[0] - before[0])
        # Lines run along the heading: +v is (sin h, cos h) in local x, y.
        theta = math.radians(heading)
        along = math.atan2(math.cos(theta), math.sin(theta))
        yaw1 = along if up else along + math.pi
        ends = TurnEnds(
            np.array([here[0]]),
            np.array([here[1]]),
            np.array([yaw0]),
            np.array([target[0]]),
            np.array([target[1]]),
            np.array([yaw1]),
        )
        curve = vehicle_turns(ends, vehicle).curve(0)
        if len(curve) >= 2 and router.inside(curve[:-1], curve[1:]).all():
            return curve
    return densify(router.path((float(here[0]), float(here[1])), target), STEP_M)


def densify(points: FloatArray, step_m: float) -> FloatArray:
    """Insert points along a polyline so that none are more than ``step_m`` apart."""
    if len(points) < 2:
        return points
    gaps = np.hypot(*np.diff(points, axis=0).T)
    pieces = np.maximum(np.ceil(gaps / step_m), 1).astype(np.int64)
    start = np.repeat(points[:-1], pieces, axis=0)
    delta = np.repeat(np.diff(points, axis=0) / pieces[:, None], pieces, axis=0)
    within = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces)
    dense = start + delta * within[:, None]
    return np.vstack([dense, points[-1:]])


def add_fitted_lines(
    route: RouteBuilder, heading: float, fit: FittedLines, *, joined: bool = False
) -> None:
    """Append a cell's fitted lines and the driven turns between them to ``route``.

    If the route's last point is the start point, a transit leg joins it to the first line.
    With ``joined``, the route already ends at the first line's start (a routed move).
    """
    n = len(fit.u)
    if n == 0:
        return
    offsets = fit.turns.offsets
    # A turn's curve holds its two ends and the points between; a degenerate curve of one
    # point (the next line starts where this one ends) has none between.
    inner = np.maximum(np.diff(offsets) - 2, 0) if n > 1 else np.zeros(0, dtype=np.int64)
    # Driving order: s0 e0 (turn 0) s1 e1 (turn 1) … as blocks of 2 + inner points.
    sizes = np.full(n, 2, dtype=np.int64)
    sizes[:-1] += inner
    block = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    total = int(sizes.sum())
    u = np.empty(total)
    v = np.empty(total)
    u[block], v[block] = fit.u, fit.v_start
    u[block + 1], v[block + 1] = fit.u, fit.v_end
    if n > 1:
        keep = np.ones(len(fit.turns.xy), dtype=bool)
        keep[offsets[:-1]] = False
        keep[offsets[1:] - 1] = False
        slots = np.ones(total, dtype=bool)
        slots[block] = False
        slots[block + 1] = False
        u[slots], v[slots] = fit.turns.xy[keep, 0], fit.turns.xy[keep, 1]
    x, y = from_sweep(u, v, heading)
    roles: list[WaypointRole] = ["turn"] * total
    lines: list[int | None] = [None] * total
    line_of = fit.index.tolist()
    starts = block.tolist()
    for k in range(n):
        roles[starts[k]] = "line_start"
        roles[starts[k] + 1] = "line_end"
        lines[starts[k]] = lines[starts[k] + 1] = line_of[k]
    skip = 1 if joined else 0
    if joined:
        route.roles[-1] = "line_start"
        route.lines[-1] = line_of[0]
    base = len(route.x) - skip
    if not joined and base and route.roles[-1] == "start":
        route.segments.append(("transit", None, base - 1, base))
    for k in range(n):
        first = base + starts[k]
        route.segments.append(("line", line_of[k], first, first + 1))
        if k + 1 < n:
            route.segments.append(("turn", None, first + 1, base + starts[k + 1]))
    route.x.extend(x[skip:].tolist())
    route.y.extend(y[skip:].tolist())
    route.roles.extend(roles[skip:])
    route.lines.extend(lines[skip:])


def _first_ring_point(rings: list[LinearRing]) -> tuple[float, float]:
    x0, y0 = rings[0].coords[0]
    return float(x0), float(y0)


def _ring_order(rings: list[LinearRing], here: tuple[float, float] | None) -> list[LinearRing]:
    """Rings of one pass, nearest first from ``here`` (given order if None)."""
    left = list(rings)
    ordered = []
    while left:
        if here is None:
            ring = left.pop(0)
        else:
            point = shapely.Point(here)
            k = min(range(len(left)), key=lambda i: left[i].distance(point))
            ring = left.pop(k)
        ordered.append(ring)
        entry = _ring_entry(ring, here)
        here = entry
    return ordered


def _ring_entry(ring: LinearRing, from_xy: tuple[float, float] | None) -> tuple[float, float]:
    if from_xy is None:
        x0, y0 = ring.coords[0]
        return float(x0), float(y0)
    point = ring.interpolate(ring.project(shapely.Point(from_xy)))
    return float(point.x), float(point.y)


def _add_headland(
    route: RouteBuilder,
    ring: LinearRing,
    pass_index: int,
    router: FieldRouter,
    *,
    end_near: tuple[float, float] | None = None,
) -> None:
    """Drive ``ring`` once round, entering where it is nearest the tractor.

    With ``end_near``, the round goes on along the ring to its point nearest ``end_near``.
    """
    here = route.here()
    entry = _ring_entry(ring, here)
    coords = np.asarray(ring.coords)[:-1]
    distance_along = shapely.line_locate_point(ring, shapely.points(coords))
    at = float(ring.project(shapely.Point(entry)))
    ahead = np.asarray((distance_along - at) % ring.length, dtype=float)
    order = np.argsort(ahead, kind="stable")
    points: list[tuple[float, float]] = [
        entry,
        *[(float(c[0]), float(c[1])) for c in coords[order] if np.hypot(*(c - entry)) > 1e-9],
        entry,
    ]
    if end_near is not None:
        exit_at = float(ring.project(shapely.Point(end_near)))
        further = (exit_at - at) % ring.length
        exit_point = ring.interpolate(exit_at)
        points += [
            (float(coords[i, 0]), float(coords[i, 1]))
            for i in order
            if 1e-9 < ahead[i] < further - 1e-9
        ]
        if further > 1e-9:
            points.append((float(exit_point.x), float(exit_point.y)))
    loop = np.asarray(points)
    if here is not None:
        if route.roles[-1] == "start":
            route.append("transit", None, np.asarray([here, entry]), "headland")
        else:
            route.append("turn", None, router.path(here, entry), "turn", last_role="headland")
    route.append("headland", pass_index, loop, "headland")
