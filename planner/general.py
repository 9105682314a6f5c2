"""Plan any field, convex or not, with or without holes: cells, lines, order, routed moves.

The stages, one module each: headland passes (around the exterior and every hole) leave
an inner area; the best few headings by :mod:`planner.heading_search` are decomposed into cells
(:mod:`planner.decomposition`); each cell gets its lines (:func:`planner.lines.scan_cells`:
R2 and R3 per cell) and its four variants
(:mod:`planner.ordering`); and the cells are ordered (:mod:`planner.cell_order`). The winning
heading's route is then built: turns that would cut a corner follow the boundary, and every
move between cells, and to and between headland passes, is routed inside the field around the
holes (:mod:`planner.routing`). Everything here is in local metres;
:func:`planner.pipeline.plan_coverage` projects and exports.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
import shapely
from shapely import Polygon

from planner import angles
from planner.cell_order import EXHAUSTIVE_MAX_CELLS
from planner.cell_plans import (
    CellCover,
    CellPlan,
    cover_heading,
    cover_screened,
    order_heading,
    reach_headland,
    reorder,
)
from planner.cell_route import CellFits, add_cells
from planner.cover_picks import cover_picks, excluded_variants
from planner.decomposition import sweep_rings
from planner.edge_estimates import edge_headings
from planner.errors import PlanTooLargeError
from planner.fit_screen import turn_table
from planner.fitted_cells import FittedCells, choose_cells, drive_candidate, fit_candidate
from planner.footprints import UNION_GRID_M, line_footprints, lines_covered
from planner.heading_search import score_headings
from planner.headland_route import add_headland, first_ring_point, ring_order
from planner.headlands import headland_ring_sets, inner_parts
from planner.line_ends import FittedLines, machine_area
from planner.lines import from_sweep
from planner.parity_kernels import PARITY_SLACK_SHARE
from planner.route_builder import RouteBuilder, add_fitted_lines, densify
from planner.routing import FieldRouter
from planner.turns import turning_radius_m
from planner.types import Objective, Pattern, Vehicle
from planner.vehicles import resolve_vehicle

if TYPE_CHECKING:
    from planner.heading_screen import ScreenedCovers

__all__ = [
    "GeneralPlan",
    "RouteBuilder",
    "add_fitted_lines",
    "densify",
    "inner_parts",
    "is_convex",
    "line_footprints",
    "plan_general",
]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: A vertex within this distance of the convex hull does not make a field non-convex [m].
CONVEXITY_TOLERANCE_M = 1e-3
#: Headings planned in full after the cheap scoring.
FULL_PLANS = 6
#: ... plus this many of the best headings by the other ranking (line count or estimate).
EXTRA_PLANS = 1
#: ... plus the headings nearest the directions of this many of the longest edges.
EDGE_PLANS = 3
#: Beyond this many turn-backs (about as many cells) only the best heading is planned in full.
MANY_TURN_BACKS = 200
#: Covered areas closer than this count as equal [m²].
_SAME_COVER_M2 = 1e-6
#: Inner-area parts smaller than this are dropped (slivers between headland passes) [m²].
_SLIVER_M2 = 1e-6


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
    after_lines = first_ring_point(rings[-1]) if rings else finish_xy

    best: CellPlan | None = None
    fits: CellFits = {}
    chosen: FittedCells | None = None
    turning_room = area if headland_passes else None
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
        if len(ranked) > 1:
            # The cheap figures misjudge fitted lines most along the long edges (their
            # lines end square): those directions are planned in full too.
            near = np.abs(
                (headings[:, None] - edge_headings(exterior)[None, :] + 90.0) % 180.0 - 90.0
            )
            ranked = list(dict.fromkeys([*ranked, *np.argmin(near, axis=0)[:EDGE_PLANS].tolist()]))
        if scores.turn_backs[ranked[0]] > MANY_TURN_BACKS:
            ranked = ranked[:1]  # a jagged boundary: hundreds of cells per heading
        prepared = [sweep_rings(p) for p in parts]
        planned = len(ranked)
        slack_m2 = angles.COVERAGE_SLACK * float(field_local.area) + 1e-9
        # With a radius, fitted coverage depends on the heading and on which ends each cell
        # turns at by more than the rule's slack: both are screened, turn by turn, from a
        # table of the vehicle's turns (not with passes: turns swing over the headland).
        table = None
        if machine.min_turn_radius_m > 0.0 and not headland_passes and pattern != "snake":
            table = turn_table(machine, d)
        parity_slack_m2 = PARITY_SLACK_SHARE * float(field_local.area)
        must_fit: list[int] = []
        screen: ScreenedCovers | None = None
        cell_losses_m2: dict[int, npt.NDArray[np.float64]] = {}
        if len(ranked) > 1:
            # R5: the headings that the decomposed estimate of fitted coverage, at every
            # heading, ranks best-covering are fitted too (with a radius, its best are
            # screened fitted).
            picks, screen, cell_losses_m2 = cover_picks(
                prepared, headings, d, edge, machine, table, parity_slack_m2=parity_slack_m2
            )
            ranked += [a for a in picks if a not in ranked]
            must_fit = [ranked.index(a) for a in picks]

        def cover_at(a: int) -> CellCover:
            # The screen decomposed and scanned every heading already, as cover_heading would.
            from planner.heading_screen import screened_cells  # numba: compiled on first use

            cells = None if screen is None else screened_cells(screen, a)
            if cells is None:
                return cover_heading(prepared, float(headings[a]), d, edge)
            return cover_screened(*cells, float(headings[a]), d)

        covers = [cover_at(a) for a in ranked]
        orders: dict[int, CellPlan] = {}

        def order_cover(cover: CellCover, losses_m2: FloatArray | None) -> CellPlan:
            # R5 within the heading: no cell turns at the ends that cost it clearly more
            # cover, to save length.
            excluded = None
            if table is not None:
                excluded = excluded_variants(cover, table, d, parity_slack_m2, losses_m2)
            plan = order_heading(cover, start_xy, after_lines, excluded=excluded)
            return reach_headland(plan, d) if rings else plan

        def cheap(i: int) -> CellPlan:
            # Ordered only when the rule asks for its length (most headings are).
            if i not in orders:
                orders[i] = order_cover(covers[i], cell_losses_m2.get(ranked[i]))
            return orders[i]

        def probe(heading_deg: float, neighbours_deg: Sequence[float]) -> list[CellPlan | None]:
            from planner.heading_screen import screen_fitted  # numba: compiled on first use

            around = [h % 180.0 for h in neighbours_deg]
            worth = [True] * len(around)
            if table is not None:
                # With a radius fitting costs most; the screen first, all in one call: is a
                # neighbour's jump in cover there at all?
                screened = screen_fitted(
                    prepared, [heading_deg, *around], d, edge, table,
                    parity_slack_m2=parity_slack_m2,
                )  # fmt: skip
                worth = [bool(m2 > screened[0] + slack_m2) for m2 in screened[1:]]
            return [
                order_cover(cover_heading(prepared, h, d, edge), None) if ok else None
                for h, ok in zip(around, worth, strict=True)
            ]

        # R5 on what the vehicle covers: the headings ranked on estimated fitted figures,
        # the close ones fitted (ends pulled back, lines dropped, the implement's width)
        # and the rule applied to those (planner.fitted_cells).

        def fit(plan: CellPlan) -> FittedCells:
            # Beyond a few cells the cheap plans order them greedily; a heading fitted is a
            # candidate for the route, so its order is improved first (as the winner's would
            # be), and headings are compared on the lengths they will really have.
            if len(plan.cells) > EXHAUSTIVE_MAX_CELLS:
                plan = reorder(plan, start_xy, after_lines, None)
            return fit_candidate(
                plan,
                field_local=field_local,
                area=area,
                interval_m=d,
                implement_width_m=implement,
                vehicle=machine,
                pattern=pattern,
                turning_room=turning_room,
                start_xy=start_xy,
                finish_xy=after_lines,
            )

        def drive(candidate: FittedCells) -> FittedCells:
            # The moves between cells of a vehicle with a turning radius shorten its lines.
            return drive_candidate(
                candidate,
                router,
                field_local=field_local,
                area=area,
                interval_m=d,
                implement_width_m=implement,
                vehicle=machine,
                start_xy=start_xy,
                finish_xy=after_lines,
            )

        def neighbours(headings_deg: Sequence[float]) -> list[CellPlan]:
            return [
                order_cover(cover_heading(prepared, h % 180.0, d, edge), None) for h in headings_deg
            ]

        drives = machine.min_turn_radius_m > 0.0

        chosen, given_up_m2 = choose_cells(
            covers,
            cheap,
            objective,
            slack_m2=slack_m2,
            fit=fit,
            vehicle=machine,
            interval_m=d,
            planned=planned,
            must_fit=must_fit,
            probe=probe,
            drive=drive if drives else None,
            near=neighbours if fixed_heading_deg is None else None,
        )
        fits = chosen.fits
        best = chosen.plan
        given_up_pp = given_up_m2 / float(field_local.area) * 100.0
        # Round holes a straight line is a poor guess of a move between cells: the
        # winner's few cells are reordered with routed moves (many cells cost too much).
        routed = bool(field_local.interiors) and len(best.cells) <= EXHAUSTIVE_MAX_CELLS
        if routed:  # (straight moves: its order was improved before it was fitted)
            reordered = reorder(best, start_xy, after_lines, router.distances)
            if reordered.order != best.order:
                # Another order drives other line directions, whose fitted ends differ: it
                # is kept only if it covers as much as the heading R5 was held on.
                refit = drive(fit(reordered)) if drives else fit(reordered)
                if refit.covered_m2 >= chosen.covered_m2 - _SAME_COVER_M2:
                    best, chosen, fits = reordered, refit, refit.fits

    route = RouteBuilder()
    if start_xy is not None:
        route.append("transit", None, np.array([start_xy]), "start")
    cells_local: list[Polygon] = []
    line_count = 0
    heading = 0.0 if fixed_heading_deg is None else float(fixed_heading_deg)
    fitted: list[FittedLines] = []
    if best is not None:
        heading = best.heading_deg
        fitted = add_cells(
            route,
            best,
            router,
            vehicle=machine,
            pattern=pattern,
            interval_m=d,
            turning_room=turning_room,
            fits=fits,
            driven=chosen.driven if chosen is not None and chosen.plan is best else None,
        )
        line_count = sum(len(fit.u) for fit in fitted)
        for cell_index, _ in best.order:
            cell = best.cells[cell_index]
            x, y = from_sweep(cell.u_ring, cell.v_ring, heading)
            cells_local.append(Polygon(np.stack([x, y], axis=1)))
    for pass_index in reversed(range(len(rings))):
        ordered = ring_order(rings[pass_index], route.here())
        for ring_index, ring in enumerate(ordered):
            # The last round goes on to the point nearest the finish, so the tractor leaves
            # from the headland instead of crossing the tilled field.
            last = pass_index == 0 and ring_index == len(ordered) - 1
            add_headland(route, ring, pass_index, router, end_near=finish_xy if last else None)

    field_area = float(field_local.area)
    if chosen is not None and _drives_fitted_lines(chosen, best, fitted):
        lines_m2 = chosen.covered_m2  # measured by the fit, on these very lines
    else:
        lines_m2 = lines_covered(best, fitted, field_local, area, heading, implement)
    covered = lines_m2
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
        lines_coverage_ratio=min(lines_m2 / field_area, 1.0),
        coverage_given_up_pp=max(given_up_pp, 0.0),
    )


def _drives_fitted_lines(
    chosen: FittedCells, best: CellPlan | None, fitted: list[FittedLines]
) -> bool:
    """Whether the route drives the chosen heading's fitted lines as fitted (same cell order)."""
    if best is not chosen.plan or len(fitted) != len(best.order):
        return False
    measured: list[FittedLines | None] = [chosen.fits.get(key) for key in best.order]
    if chosen.driven is not None:
        measured = list(chosen.driven.fitted)  # as driven: shortened for moves between cells
    for f, g in zip(fitted, measured, strict=True):
        if g is None or not (f.u is g.u and f.v_start is g.v_start and f.v_end is g.v_end):
            return False
    return True


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
