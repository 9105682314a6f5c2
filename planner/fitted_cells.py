"""R5 on what the vehicle covers, for fields planned in cells (non-convex, holes, passes).

The cheap plan of a heading (:func:`planner.cell_plans.plan_heading`) scores straight lines
that end on the cells' chains, each an interval wide. The route then fits every cell's lines
for the vehicle (:func:`planner.cell_route.fit_cells`): ends pulled back until its turns fit,
lines it cannot reach dropped, and each line covers the implement's width. A heading's real
coverage and length can therefore differ from its cheap figures by more than the rule's
0.2 pp or the 1 % that separate headings, so the planned headings are compared on their
fitted lines, as :mod:`planner.fitted_choice` does for convex fields.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from shapely import MultiPolygon, Polygon

from planner.cell_moves import DrivenCells, drive_cells
from planner.cell_plans import CellCover, CellPlan
from planner.cell_route import CellFits, fit_cells
from planner.footprints import cell_lines, cells_and_band_m2, lines_in_cells_m2
from planner.line_ends import FittedLines
from planner.lines import from_sweep
from planner.routing import FieldRouter, path_length
from planner.turn_reach import end_reach_m
from planner.turns import TurnEnds, vehicle_turns
from planner.types import Objective, Pattern, Vehicle

FloatArray = npt.NDArray[np.float64]

#: Path lengths closer than this count as equal [m].
_TIE_M = 1e-6


@dataclass(frozen=True, slots=True)
class FittedCells:
    """One heading's cells fitted for the vehicle, with what they cover and their length.

    Attributes
    ----------
    plan : CellPlan
    fits : dict
        Each cell's fitted lines by ``(cell, variant)``, for the route to reuse.
    covered_m2 : float
        Area of the field the implement covers on the fitted lines (R4) [m²].
    length_m : float
        Fitted lines, their turns, the moves between cells and the start and finish
        legs [m].
    line_count : int
        Lines driven.
    cells_m2 : float
        Area of the cells the fitted lines cover, each an interval wide: the measure of the
        cheap plans (:func:`estimate`) [m²].
    driven : DrivenCells or None
        The lines as driven (shortened where a move between cells needs room) and the
        moves, on which the figures above are measured, for the route to reuse
        (:func:`drive_candidate`); None before that: the figures count straight moves.
    """

    plan: CellPlan
    fits: CellFits
    covered_m2: float
    length_m: float
    line_count: int
    cells_m2: float
    driven: DrivenCells | None = None


def fit_candidate(
    plan: CellPlan,
    *,
    field_local: Polygon,
    area: Polygon | MultiPolygon,
    interval_m: float,
    implement_width_m: float,
    vehicle: Vehicle,
    pattern: Pattern,
    turning_room: Polygon | MultiPolygon | None,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
) -> FittedCells:
    """Fit ``plan``'s cells for ``vehicle`` and measure coverage and length on them.

    The moves between cells count as straight; :func:`drive_candidate` plans them.

    Parameters
    ----------
    plan : CellPlan
        A heading's cells, in their driving order.
    field_local, area : Polygon or MultiPolygon
        The field and its machine area, local [m].
    interval_m, implement_width_m : float
        Line spacing and working width [m].
    vehicle : Vehicle
    pattern : {"boustrophedon", "snake"}
    turning_room : Polygon or MultiPolygon or None
        Where turns may swing out beyond the cells (with headland passes).
    start_xy, finish_xy : tuple of float or None
        Where the lines are reached from and left for, local [m].

    Returns
    -------
    FittedCells
    """
    fits: CellFits = {}
    fitted = fit_cells(
        plan,
        vehicle=vehicle,
        pattern=pattern,
        interval_m=interval_m,
        turning_room=turning_room,
        fits=fits,
    )
    return _measured(
        plan,
        fits,
        fitted,
        None,
        field_local=field_local,
        area=area,
        interval_m=interval_m,
        implement_width_m=implement_width_m,
        start_xy=start_xy,
        finish_xy=finish_xy,
    )


def drive_candidate(
    candidate: FittedCells,
    router: FieldRouter,
    *,
    field_local: Polygon,
    area: Polygon | MultiPolygon,
    interval_m: float,
    implement_width_m: float,
    vehicle: Vehicle,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
) -> FittedCells:
    """Plan a fitted heading's moves between cells and measure it again on the lines as driven.

    A vehicle with a turning radius gives up line length to those moves
    (:func:`planner.cell_moves.drive_cells`, in ``router``'s machine area): the coverage and
    the length are measured again on the shortened lines and the moves' curves. The other
    arguments are :func:`fit_candidate`'s.
    """
    fitted = [candidate.fits[key] for key in candidate.plan.order]
    driven = drive_cells(candidate.plan, fitted, router, vehicle=vehicle)
    return _measured(
        candidate.plan,
        candidate.fits,
        driven.fitted,
        driven,
        field_local=field_local,
        area=area,
        interval_m=interval_m,
        implement_width_m=implement_width_m,
        start_xy=start_xy,
        finish_xy=finish_xy,
    )


def _measured(
    plan: CellPlan,
    fits: CellFits,
    fitted: list[FittedLines],
    driven: DrivenCells | None,
    *,
    field_local: Polygon,
    area: Polygon | MultiPolygon,
    interval_m: float,
    implement_width_m: float,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
) -> FittedCells:
    """Measure coverage and length of ``fitted`` (in driving order), with ``driven``'s moves."""
    inside_m2, band_m2 = cells_and_band_m2(
        plan, fitted, field_local, area, plan.heading_deg, implement_width_m
    )
    # The cheap plans' measure: footprints an interval wide, inside the cells. With the
    # implement as wide as the interval (the default) that is the part just measured.
    if implement_width_m == interval_m:
        cells_m2 = inside_m2
    else:
        cells_m2 = cells_covered_m2(plan, fitted, interval_m)
    moves = None if driven is None else driven.moves
    return FittedCells(
        plan,
        fits,
        inside_m2 + band_m2,
        fitted_length_m(fitted, plan.heading_deg, start_xy, finish_xy, moves=moves),
        sum(len(f.u) for f in fitted),
        cells_m2,
        driven,
    )


def choose_driven(
    candidates: list[FittedCells],
    objective: Objective,
    *,
    slack_m2: float,
    drive: Callable[[FittedCells], FittedCells],
) -> tuple[FittedCells, float]:
    """Apply R5 (:func:`choose_fitted`) to fitted headings as driven, driving few of them.

    Driving a heading (``drive``: its moves between cells planned, :func:`drive_candidate`)
    only lowers its coverage. So the rule is applied with the headings not driven at their
    fitted figures, an upper bound of their coverage; the choice is driven, and so is every
    heading that covers more than the best driven one, until the choice is driven and the
    best coverage is a driven heading's. The best coverage is then exact, and so is which
    headings are within the slack of it; a heading not driven that the rule does not pick
    is compared on its fitted length (driving changes a length by its moves' curves).

    Parameters
    ----------
    candidates : list of FittedCells
        Fitted headings, driven or not (:attr:`FittedCells.driven`).
    objective : {"shortest_path", "fewest_lines"}
    slack_m2 : float
        R5's slack [m²].
    drive : callable
        Plans a fitted heading's moves between cells and measures it again.

    Returns
    -------
    chosen : FittedCells
        Driven.
    given_up_m2 : float
        Area it covers less than the best heading [m²].

    Examples
    --------
    Driven, A covers 99.0 and B 99.5: C (98.7, much shorter) is within the slack of B.

    >>> from dataclasses import replace
    >>> def fitted(covered_m2, length_m):
    ...     return FittedCells(None, {}, covered_m2, length_m, 3, 0.0)  # type: ignore[arg-type]
    >>> after = {100.0: (99.0, 50.0), 99.6: (99.5, 40.0), 98.8: (98.7, 10.0)}
    >>> def drive(c):  # a stand-in: any value but None marks a heading driven
    ...     covered_m2, length_m = after[c.covered_m2]
    ...     return replace(c, covered_m2=covered_m2, length_m=length_m, driven=True)
    >>> chosen, given_up = choose_driven(
    ...     [fitted(100.0, 50.0), fitted(99.6, 40.0), fitted(98.8, 10.0)],
    ...     "shortest_path", slack_m2=1.0, drive=drive)
    >>> chosen.covered_m2, round(given_up, 6)
    (98.7, 0.8)
    """
    pool = list(candidates)
    while True:
        chosen, given_up_m2 = choose_fitted(pool, objective, slack_m2=slack_m2)
        at = next(i for i, c in enumerate(pool) if c is chosen)
        if chosen.driven is None:
            pool[at] = drive(chosen)
            continue
        best_driven_m2 = max(c.covered_m2 for c in pool if c.driven is not None)
        above = [
            i for i, c in enumerate(pool) if c.driven is None and c.covered_m2 > best_driven_m2
        ]
        if not above:
            return chosen, given_up_m2
        for i in above:
            pool[i] = drive(pool[i])


def cells_covered_m2(plan: CellPlan, fitted: list[FittedLines], width_m: float) -> float:
    """Area of ``plan``'s cells that fitted lines ``width_m`` wide cover [m²]."""
    return lines_in_cells_m2(cell_lines(plan, fitted), width_m)


def choose_fitted(
    candidates: list[FittedCells], objective: Objective, *, slack_m2: float
) -> tuple[FittedCells, float]:
    """Apply R5 to fitted headings: the objective's best within ``slack_m2`` of the best cover.

    Returns
    -------
    chosen : FittedCells
    given_up_m2 : float
        Area the chosen heading covers less than the best-covering one [m²].

    Examples
    --------
    >>> from planner.line_ends import FittedLines
    >>> a = FittedCells(None, {}, 100.0, 50.0, 3, 0.0)  # type: ignore[arg-type]
    >>> b = FittedCells(None, {}, 99.9, 40.0, 4, 0.0)  # type: ignore[arg-type]
    >>> c = FittedCells(None, {}, 90.0, 10.0, 1, 0.0)  # type: ignore[arg-type]
    >>> chosen, given_up = choose_fitted([a, b, c], "shortest_path", slack_m2=0.2)
    >>> chosen is b, round(given_up, 3)
    (True, 0.1)
    """
    best_m2 = max(c.covered_m2 for c in candidates)
    eligible = [c for c in candidates if c.covered_m2 >= best_m2 - slack_m2]

    def key(c: FittedCells) -> tuple[float, float]:
        lines = float(c.line_count) if objective == "fewest_lines" else 0.0
        return lines, round(c.length_m / _TIE_M) * _TIE_M

    chosen = min(eligible, key=key)  # min keeps the first of equals: the search's order
    return chosen, max(best_m2 - chosen.covered_m2, 0.0)


def fitted_length_m(
    fitted: list[FittedLines],
    heading: float,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    *,
    moves: list[FloatArray] | None = None,
) -> float:
    """Length of fitted cells in driving order: lines, turns, moves, legs [m].

    The moves between cells are ``moves`` (local [m]) if given, else straight.
    """
    total = 0.0
    here = None if start_xy is None else np.asarray(start_xy, dtype=float)
    first = True
    for fit in fitted:
        if len(fit.u) == 0:
            continue
        total += float(np.abs(fit.v_end - fit.v_start).sum()) + float(fit.turns.length_m.sum())
        entry = np.asarray(from_sweep(fit.u[0], fit.v_start[0], heading), dtype=float)
        if here is not None and (first or moves is None):
            total += float(np.hypot(*(entry - here)))
        first = False
        here = np.asarray(from_sweep(fit.u[-1], fit.v_end[-1], heading), dtype=float)
    if moves is not None:
        total += sum(path_length(move) for move in moves)
    if finish_xy is not None and here is not None:
        total += float(np.hypot(*(here - np.asarray(finish_xy, dtype=float))))
    return total


#: Headings within this share of the estimated best length are fitted as well as the choice.
CLOSE_SHARE = 0.02
#: ... at most this many of them (the budget: fitting is most of a plan's time).
CLOSE_PLANS = 1
#: A heading estimated this many rule slacks beyond the best coverage may still keep the rule
#: when fitted (the estimate errs by about a slack) ...
ESTIMATE_SLACKS = 1.0
#: ... and is fitted if it is estimated this share shorter than the choice (issue 9's 1 %).
SHORTER_SHARE = 0.01
#: A fitted heading that fitting left clearly below its estimate's cover, and that would be
#: :data:`SHORTER_SHARE` shorter than the choice, has its neighbours this far either side
#: fitted too [deg]: fitted coverage jumps where whole lines come to fit or not
#: (germany_2018_2019-21 with the hand tractor: 97.74 % at its edge's 63.637°, 98.79 % at
#: 63.640°, and 4.6 % shorter than the choice there). A quarter degree: within the 1° grid,
#: not tuned.
PROBE_OFFSETS_DEG = (-0.25, 0.25)
#: A choice whose moves between cells cost more than the rule's slack has its neighbours
#: this far either side fitted and driven too [deg] (:func:`choose_cells`).
MOVE_PROBE_OFFSETS_DEG = (-1.0, 1.0)
#: ``probe(heading_deg, neighbours_deg)``: each neighbour of a heading planned cheaply, or
#: None where it is not worth fitting (:func:`choose_cells`).
Probe = Callable[[float, Sequence[float]], list[CellPlan | None]]


@functools.lru_cache(maxsize=256)
def turn_change_m(vehicle: Vehicle, spacing_m: float) -> tuple[float, float]:
    """Estimate what fitting does to each turn between lines ``spacing_m`` apart.

    Returns
    -------
    length_m : float
        The driven turn minus the straight step it replaces and the two pulled-back ends [m].
    reach_m : float
        How far each of the turn's two line ends is pulled back [m].
    """
    zero = np.zeros(1)
    ends = TurnEnds(zero, zero, zero + math.pi / 2.0, zero + spacing_m, zero, zero - math.pi / 2.0)
    curves = vehicle_turns(ends, vehicle)
    reach = end_reach_m(vehicle, spacing_m)
    return float(curves.length_m.sum()) + 2.0 * reach - spacing_m, reach


def estimate(plan: CellPlan, vehicle: Vehicle, spacing_m: float) -> tuple[float, float]:
    """Estimate ``plan``'s fitted coverage [m²] and length [m] from its cheap figures.

    Every turn (a line that is not a cell's last) is driven by the vehicle and pulls its
    two line ends back: :func:`turn_change_m` per turn on the length, and the pulled-back
    ends, one interval wide, off the coverage (:func:`planner.turn_reach.fitting_loss_m2`'s
    turn term; the cells already lie in the machine area, so its width term is not taken).
    """
    return estimate_m2(plan, vehicle, spacing_m), estimate_m(plan, vehicle, spacing_m)


def estimate_m2(plan: CellPlan | CellCover, vehicle: Vehicle, spacing_m: float) -> float:
    """:func:`estimate`'s coverage [m²]: it needs no cell order."""
    turns = _turn_count(plan)
    _, reach_m = turn_change_m(vehicle, float(spacing_m))
    return plan.covered_m2 - 2.0 * turns * reach_m * spacing_m


def estimate_m(plan: CellPlan, vehicle: Vehicle, spacing_m: float) -> float:
    """:func:`estimate`'s length [m]."""
    length_m, _ = turn_change_m(vehicle, float(spacing_m))
    return plan.length_m + _turn_count(plan) * length_m


def _turn_count(plan: CellPlan | CellCover) -> int:
    cells = sum(1 for c in plan.cells if c.lines.stop > c.lines.start)
    return max(plan.line_count - cells, 0)


def choose_cells(
    covers: list[CellCover],
    cheap: Callable[[int], CellPlan],
    objective: Objective,
    *,
    slack_m2: float,
    fit: Callable[[CellPlan], FittedCells],
    vehicle: Vehicle,
    interval_m: float,
    planned: int | None = None,
    must_fit: Sequence[int] = (),
    probe: Probe | None = None,
    drive: Callable[[FittedCells], FittedCells] | None = None,
    near: Callable[[Sequence[float]], list[CellPlan]] | None = None,
) -> tuple[FittedCells, float]:
    """R5 on fitted lines, fitting as few headings as it can.

    The cheap plans are ranked on their estimated fitted figures (:func:`estimate`); the
    choice and every eligible heading within :data:`CLOSE_SHARE` of its estimated length
    are fitted (at most :data:`CLOSE_PLANS` besides it), with the headings ``must_fit``
    (those :func:`planner.cover_picks.cover_picks` ranks best-covering over every heading),
    and the shortest heading within :data:`ESTIMATE_SLACKS` more of the best estimate that is
    :data:`SHORTER_SHARE` shorter than the choice. The rule then picks among the fitted
    ones (:func:`choose_fitted`).

    ``covers[i]`` is heading ``i`` before its cells are ordered, ``cheap(i)`` its cheap
    plan: a heading whose length the rule never asks for (one that covers too little) is
    never ordered. Only the first ``planned`` headings (default: all) are planned for length;
    the others were decomposed because they may cover more, and are fitted if in ``must_fit``.

    ``probe(heading_deg, neighbours_deg)`` plans neighbours of a heading cheaply (None for one
    not worth fitting): given, the shortest fitted heading that the estimate put
    within the slack of the best cover, that fitting left more than the slack below the best
    fitted one, and that is :data:`SHORTER_SHARE` shorter than the shortest fitted heading
    that keeps the rule, has its neighbours :data:`PROBE_OFFSETS_DEG` away fitted too (fitted
    coverage is discontinuous in the heading).

    ``drive``, given (a vehicle with a turning radius), plans a fitted heading's moves between
    cells, which shorten its lines: the rule is then held on headings as driven
    (:func:`choose_driven`). If the moves cost the choice more than the slack, its
    neighbours :data:`MOVE_PROBE_OFFSETS_DEG` away (``near(headings_deg)`` plans them
    cheaply) are fitted and driven too: what the moves cost jumps from one
    heading to the next, where a cell's last line comes to end in another corner.

    Returns
    -------
    chosen : FittedCells
    given_up_m2 : float
        Area it covers less than the best fitted heading [m²].
    """
    covered = [estimate_m2(c, vehicle, interval_m) for c in covers]
    lengths: dict[int, float] = {}

    def length(i: int) -> float:
        if i not in lengths:
            lengths[i] = estimate_m(cheap(i), vehicle, interval_m)
        return lengths[i]

    planned = len(covers) if planned is None else planned
    best_m2 = max(covered[:planned])
    eligible = [i for i, m2 in enumerate(covered[:planned]) if m2 >= best_m2 - slack_m2]

    def lines(i: int) -> float:
        return float(covers[i].line_count) if objective == "fewest_lines" else 0.0

    def key(i: int) -> tuple[float, float]:
        return lines(i), length(i)

    eligible.sort(key=key)
    first = eligible[0]
    close = [
        i
        for i in eligible
        if lines(i) == lines(first) and length(i) <= length(first) * (1 + CLOSE_SHARE)
    ][: 1 + CLOSE_PLANS]
    fitted = {i: fit(cheap(i)) for i in dict.fromkeys([*close, *must_fit])}
    # The estimate's error is about the rule's slack: the shortest heading that it puts up
    # to one more slack below the best and that would save over 1 % is fitted too.
    shorter = [
        i
        for i in range(planned)
        if i not in fitted
        and lines(i) <= lines(first)
        and covered[i] >= best_m2 - (1.0 + ESTIMATE_SLACKS) * slack_m2
        and length(i) < length(first) * (1.0 - SHORTER_SHARE)
    ]
    if shorter:
        shortest = min(shorter, key=length)
        fitted[shortest] = fit(cheap(shortest))
    candidates = [fitted[i] for i in sorted(fitted, key=key)]
    if probe is not None:
        candidates += _probed(fitted, covers, covered, best_m2, slack_m2, probe, fit, objective)
    if drive is None:
        return choose_fitted(candidates, objective, slack_m2=slack_m2)
    drove: dict[int, FittedCells] = {}  # by id of the fitted heading: each driven once

    def drive_once(candidate: FittedCells) -> FittedCells:
        if id(candidate) not in drove:
            drove[id(candidate)] = drive(candidate)
        return drove[id(candidate)]

    chosen, given_up_m2 = choose_driven(candidates, objective, slack_m2=slack_m2, drive=drive_once)
    before = next((c for c in candidates if c.plan is chosen.plan), chosen)
    if near is not None and before.covered_m2 - chosen.covered_m2 > slack_m2:
        heading = chosen.plan.heading_deg
        around = near([heading + offset for offset in MOVE_PROBE_OFFSETS_DEG])
        candidates += [fit(plan) for plan in around]
        chosen, given_up_m2 = choose_driven(
            candidates, objective, slack_m2=slack_m2, drive=drive_once
        )
    return chosen, given_up_m2


def _probed(
    fitted: dict[int, FittedCells],
    covers: list[CellCover],
    estimated_m2: list[float],
    best_estimate_m2: float,
    slack_m2: float,
    probe: Probe,
    fit: Callable[[CellPlan], FittedCells],
    objective: Objective,
) -> list[FittedCells]:
    """Fit the neighbours of a fitted heading that fitting cost its cover (:func:`choose_cells`).

    Only headings whose fitted length would save :data:`SHORTER_SHARE` over the shortest
    fitted heading that keeps the rule, and only for the length objective (fewer lines are
    not bought by a neighbour: it drives the same lines).
    """
    if objective != "shortest_path":
        return []
    best_m2 = max(f.covered_m2 for f in fitted.values())
    # The rule's own choice among the fitted ones; a neighbour must save 1 % on it.
    choice, _ = choose_fitted(list(fitted.values()), objective, slack_m2=slack_m2)
    saving_m = choice.length_m * (1.0 - SHORTER_SHARE)
    surprised = [
        i
        for i, f in fitted.items()
        if f.covered_m2 < best_m2 - slack_m2
        and estimated_m2[i] >= best_estimate_m2 - slack_m2
        and f.length_m < saving_m
    ]
    if not surprised:
        return []
    # One heading's neighbours, the shortest's: fitting is most of a plan's time.
    heading = covers[min(surprised, key=lambda i: (fitted[i].length_m, i))].heading_deg
    plans = probe(heading, [heading + offset for offset in PROBE_OFFSETS_DEG])
    probed = [fit(plan) for plan in plans if plan is not None]
    # A neighbour is a candidate if R5 asks for it (it covers clearly more) or if it saves
    # the 1 %: fitted lengths move cells in straight lines, and around holes the
    # route's are longer (germany_2018_2019-42: a neighbour 0.7 % shorter fitted, 9 % longer
    # routed).
    return [
        f
        for f in probed
        if f.covered_m2 > best_m2 + slack_m2
        or (f.covered_m2 >= best_m2 - slack_m2 and f.length_m < saving_m)
    ]
