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

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import shapely
from shapely import LinearRing, Polygon

from planner import angles
from planner.cell_order import EXHAUSTIVE_MAX_CELLS, CellVariants, order_cells
from planner.coverage import Chains, convex_chains, covered_area
from planner.decomposition import decompose_sweep
from planner.errors import PlanTooLargeError
from planner.heading_search import score_headings
from planner.headlands import headland_ring_sets, inner_parts
from planner.lines import LineScan, from_sweep, scan_cells
from planner.ordering import ordered_line_ends, variant_ends, variant_lengths
from planner.routing import FieldRouter
from planner.types import Objective, SegmentKind, WaypointRole

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
    (3, 23, 0.97)
    """
    field_local = shapely.orient_polygons(field_local)
    d = float(interval_m)
    rings = headland_ring_sets(field_local, passes=headland_passes, interval_m=d)
    parts = inner_parts(field_local, passes=headland_passes, interval_m=d)
    router = FieldRouter(field_local)
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
            _plan_heading(parts, float(headings[a]), d, start_xy, after_lines) for a in ranked
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
    lines_covered = 0.0
    line_count = 0
    heading = 0.0 if fixed_heading_deg is None else float(fixed_heading_deg)
    if best is not None:
        heading = best.heading_deg
        line_count = best.line_count
        _add_cells(route, best, router)
        for cell_index, _ in best.order:
            cell = best.cells[cell_index]
            x, y = from_sweep(cell.u_ring, cell.v_ring, heading)
            cells_local.append(Polygon(np.stack([x, y], axis=1)))
            k = cell.lines
            lines_covered += covered_area(
                cell.chains, best.scan.u[k], best.scan.v_lo[k], best.scan.v_hi[k], d
            )
    for pass_index in reversed(range(len(rings))):
        ordered = _ring_order(rings[pass_index], route.here())
        for ring_index, ring in enumerate(ordered):
            # The last round goes on to the point nearest the finish, so the tractor leaves
            # from the headland instead of crossing the tilled field.
            last = pass_index == 0 and ring_index == len(ordered) - 1
            _add_headland(route, ring, pass_index, router, end_near=finish_xy if last else None)

    field_area = float(field_local.area)
    covered = lines_covered
    if rings:
        band = field_local.difference(shapely.union_all(parts)) if parts else field_local
        footprints = shapely.union_all(
            [
                r.buffer(d / 2.0, cap_style="flat", join_style="mitre")
                for pass_rings in rings
                for r in pass_rings
            ]
        )
        covered += float(shapely.intersection(band, footprints).area)
    return GeneralPlan(
        route=route,
        heading_deg=heading,
        line_count=line_count,
        cells_local=cells_local,
        coverage_ratio=min(covered / field_area, 1.0),
        lines_coverage_ratio=min(lines_covered / field_area, 1.0),
        coverage_given_up_pp=max(given_up_pp, 0.0),
    )


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
) -> _Candidate:
    """Decompose, scan and order the cells at one heading; turns and moves straight."""
    rings = [ring for part in parts for ring in decompose_sweep(part, heading)]
    scan = scan_cells(rings, d)
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


def _add_cells(route: RouteBuilder, plan: _Candidate, router: FieldRouter) -> None:
    """Append every cell's lines and turns, and the moves between cells, to ``route``."""
    heading = plan.heading_deg
    scan = plan.scan
    first_index = 0
    for cell_index, variant in plan.order:
        cell = plan.cells[cell_index]
        k = cell.lines
        u, v_from, v_to, index = ordered_line_ends(scan.u[k], scan.v_lo[k], scan.v_hi[k], variant)
        n = len(u)
        up = (np.arange(n) % 2 == 0) == (variant in (0, 2))
        x, y = from_sweep(np.repeat(u, 2), np.stack([v_from, v_to], axis=1).ravel(), heading)
        points = np.stack([x, y], axis=1)  # s0, e0, s1, e1, …
        turns = _cell_turns(cell, heading, u, v_from, v_to, up, points, router)
        line_of = (first_index + index).tolist()

        here = route.here()
        if here is not None:
            target = (float(points[0, 0]), float(points[0, 1]))
            if route.roles[-1] == "start":
                route.append("transit", None, np.asarray([here, target]), "turn")
            else:
                route.append("turn", None, router.path(here, target), "turn")
            route.roles[-1] = "line_start"
            route.lines[-1] = line_of[0]
        else:
            route.x.append(float(points[0, 0]))
            route.y.append(float(points[0, 1]))
            route.roles.append("line_start")
            route.lines.append(line_of[0])
        position = len(route.x) - 1
        blocks = []
        for j in range(n):
            if j > 0:
                extra = turns.get(j - 1)
                step = 1
                if extra is not None:
                    blocks.append(extra)
                    route.roles.extend(["turn"] * len(extra))
                    route.lines.extend([None] * len(extra))
                    step += len(extra)
                blocks.append(points[2 * j : 2 * j + 1])
                route.roles.append("line_start")
                route.lines.append(line_of[j])
                route.segments.append(("turn", None, position, position + step))
                position += step
            blocks.append(points[2 * j + 1 : 2 * j + 2])
            route.roles.append("line_end")
            route.lines.append(line_of[j])
            route.segments.append(("line", line_of[j], position, position + 1))
            position += 1
        new = np.concatenate(blocks)
        route.x.extend(new[:, 0].tolist())
        route.y.extend(new[:, 1].tolist())
        first_index += n


def _cell_turns(
    cell: _Cell,
    heading: float,
    u: FloatArray,
    v_from: FloatArray,
    v_to: FloatArray,
    up: npt.NDArray[np.bool_],
    points: FloatArray,
    router: FieldRouter,
) -> dict[int, FloatArray]:
    """Bends of the turns that cannot go straight, by turn index (turn j: line j to j + 1).

    A turn joins two line ends on one chain of the cell. It goes straight unless the chain
    dips between them; then it follows the chain taut (:func:`_turn_path`), and if even that
    leaves the field, the shortest path inside the field.
    """
    n = len(u)
    if n < 2:
        return {}
    bends: dict[int, FloatArray] = {}
    lo_u, hi_u = np.minimum(u[:-1], u[1:]), np.maximum(u[:-1], u[1:])
    top = up[:-1]
    for at_top, chain_u in ((True, cell.chains.hi_u), (False, cell.chains.lo_u)):
        between = np.searchsorted(chain_u, hi_u, side="left") - np.searchsorted(
            chain_u, lo_u, side="right"
        )
        for j in np.nonzero((between > 0) & (top == at_top))[0].tolist():
            path = _turn_path(cell, heading, u[j], v_to[j], u[j + 1], v_from[j + 1], at_top)
            if len(path) > 2:
                bends[j] = path[1:-1]
    # Check every turn against the field in one call; route the few that still leave it.
    if bends:
        a_list, b_list, owner = [], [], []
        for j in range(n - 1):
            chain = [points[2 * j + 1], *bends.get(j, ()), points[2 * j + 2]]
            a_list.extend(chain[:-1])
            b_list.extend(chain[1:])
            owner.extend([j] * (len(chain) - 1))
        a_arr, b_arr, owner_arr = np.asarray(a_list), np.asarray(b_list), np.asarray(owner)
    else:
        a_arr, b_arr, owner_arr = points[1:-1:2], points[2::2], np.arange(n - 1)
    ok = router.inside(a_arr, b_arr)
    for j in sorted(set(owner_arr[~ok].tolist())):
        a, b = points[2 * j + 1], points[2 * j + 2]
        path = router.path((float(a[0]), float(a[1])), (float(b[0]), float(b[1])))
        if len(path) > 2:
            bends[j] = path[1:-1]
        else:
            bends.pop(j, None)
    return bends


def _turn_path(
    cell: _Cell, heading: float, u_a: float, v_a: float, u_b: float, v_b: float, at_top: bool
) -> FloatArray:
    """Join two line ends on one chain of a cell, taut along that chain.

    Lines are ``interval`` apart, but a notch in the chain between them would make the
    straight move leave the cell: the shortest move inside bends round the chain's vertices,
    the lower convex hull of the upper chain (or the upper hull of the lower chain).
    """
    chain_u = cell.chains.hi_u if at_top else cell.chains.lo_u
    chain_v = cell.chains.hi_v if at_top else cell.chains.lo_v
    lo, hi = min(u_a, u_b), max(u_a, u_b)
    i0 = int(np.searchsorted(chain_u, lo, side="right"))
    i1 = int(np.searchsorted(chain_u, hi, side="left"))
    points = [(u_a, v_a), (u_b, v_b)]
    if i1 > i0:
        inner = list(zip(chain_u[i0:i1].tolist(), chain_v[i0:i1].tolist(), strict=True))
        ordered = [(lo, v_a if u_a <= u_b else v_b), *inner, (hi, v_b if u_a <= u_b else v_a)]
        sign = 1.0 if at_top else -1.0  # lower hull under a ceiling, upper hull over a floor
        hull: list[tuple[float, float]] = []
        for p in ordered:
            while len(hull) >= 2:
                (ox, oy), (ax, ay) = hull[-2], hull[-1]
                cross = (ax - ox) * (p[1] - oy) - (ay - oy) * (p[0] - ox)
                if sign * cross <= 0.0:
                    hull.pop()
                else:
                    break
            hull.append(p)
        points = hull if u_a <= u_b else hull[::-1]
    uv = np.asarray(points)
    x, y = from_sweep(uv[:, 0], uv[:, 1], heading)
    return np.stack([x, y], axis=1)


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
