"""Moves between a plan's cells, as the vehicle drives them: curves, and lines dropped for them.

Every move between cells is the vehicle's own turn if it stays in the machine area; else,
for a vehicle with a turning radius, a curve for which the lines it joins give up some
length (:mod:`planner.move_curves`), or, failing that, for which the slivers it leaves or
joins (cells of one line shorter than the radius, where that leaves fewer moves with
corners) or up to three lines at either end of the move are dropped
(:class:`_LineDrops`), or, as a last resort, a path of
the vehicle's arcs searched for (:mod:`planner.move_search`); and otherwise the shortest
path inside the field (:mod:`planner.routing`), with corners.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from planner.cell_plans import CellPlan
from planner.line_ends import FittedLines
from planner.lines import from_sweep
from planner.move_curves import PULL_STEPS_R, drivable_moves
from planner.move_search import search_move
from planner.route_builder import densify
from planner.routing import FieldRouter
from planner.turns import STEP_M, TurnEnds, turn_range, turning_radius_m, vehicle_turns
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]

#: A move between cells leaves at least this much of each line it shortens [m].
_KEPT_LINE_M = 1.0


@dataclass(frozen=True, slots=True)
class DrivenCells:
    """A plan's cells as the vehicle drives them: fitted lines and the moves between cells.

    Attributes
    ----------
    fitted : list of FittedLines
        Every cell of the plan's order, in driving order (sweep frame): fitted, and the
        first and last lines shortened where a move between cells needs the room; with a
        turning radius, some lines at a cell's sides dropped for a move that had no curve,
        and a cell may have none left.
    moves : list of ndarray
        The moves between consecutive cells that have lines, local [m].
    """

    fitted: list[FittedLines]
    moves: list[FloatArray]


def drive_cells(
    plan: CellPlan, fitted: list[FittedLines], router: FieldRouter, *, vehicle: Vehicle
) -> DrivenCells:
    """Plan the moves between ``plan``'s fitted cells (in driving order), all at once.

    Each leaves the last line's end of one cell (driven from the line's start) for the first
    line's start of the next (:func:`moves_between_cells`), and may shorten each of the two
    lines by less than half, keeping :data:`_KEPT_LINE_M` of it (a cell of one line gives up
    length at both ends). Where a vehicle with a turning radius finds no curve for a move,
    the slivers it leaves or joins go where that leaves fewer moves with corners
    (:meth:`_LineDrops.drop_slivers`), then up to three
    lines at its ends, whole cells too (:meth:`_LineDrops.drop_for_curves`);
    a move no drop serves is searched for (:meth:`_LineDrops.search_cornered`).
    """
    driven = [fit for fit in fitted if len(fit.u)]
    if len(driven) < 2:
        return DrivenCells(list(fitted), [])
    drops = _LineDrops(plan.heading_deg, driven, router, vehicle)
    if vehicle.min_turn_radius_m > 0.0:
        drops.drop_slivers()
        drops.drop_for_curves()
        drops.search_cornered()
    kept, moves = drops.result()
    cells = iter(kept)
    return DrivenCells([next(cells) if len(fit.u) else fit for fit in fitted], moves)


#: A move between two cells: the cell it leaves and the one it joins (indices of the cells
#: with lines), and how many lines the first has lost at its end and the second at its start.
_MoveKey = tuple[int, int, int, int]


class _PlannedMove(NamedTuple):
    """A move planned between two cells (:func:`moves_between_cells`, one of its moves)."""

    points: FloatArray
    pulled_back_m: float
    pushed_on_m: float
    curved: bool


class _Drops(NamedTuple):
    """Lines a move with corners may drop: every cell's count at its start and its end."""

    length_m: float  # of the lines it adds to those dropped
    first_dropped: list[int]
    last_dropped: list[int]
    touched: set[int]  # the cells whose drops change, and the ends of the moves it adds
    new_moves: list[_MoveKey]


class _LineDrops:
    """A plan's cells with some of their side lines dropped, and the moves between them.

    A move for which a vehicle with a turning radius finds no curve (the shortest path,
    with corners) mostly leaves or joins a line too short to give up the length a curve
    needs: a sliver of a cell, most often a cell of one line. :meth:`drop_for_curves`
    drops such lines, and cells, where the moves then planned are curves, trading their
    coverage for a path the vehicle can drive (R1). Moves are planned in batches and kept
    by what they depend on (:data:`_MoveKey`).
    """

    #: The most lines one choice drops for a move, before it and after it together (a
    #: cell may lose more over several moves).
    MOST_DROPPED = 3

    def __init__(
        self, heading_deg: float, cells: list[FittedLines], router: FieldRouter, vehicle: Vehicle
    ) -> None:
        self.heading_deg = heading_deg
        self.cells = cells
        self.line_m = [np.abs(fit.v_end - fit.v_start) for fit in cells]
        self.router = router
        self.vehicle = vehicle
        self.first_dropped = [0] * len(cells)
        self.last_dropped = [0] * len(cells)
        self.planned: dict[_MoveKey, _PlannedMove] = {}
        self._plan(self._keys(self.first_dropped, self.last_dropped))

    def _alive(self, first: list[int], last: list[int]) -> list[int]:
        return [c for c, lines in enumerate(self.line_m) if first[c] + last[c] < len(lines)]

    def _keys(self, first: list[int], last: list[int]) -> list[_MoveKey]:
        alive = self._alive(first, last)
        return [(i, j, last[i], first[j]) for i, j in zip(alive[:-1], alive[1:], strict=True)]

    def _plan(self, keys: list[_MoveKey]) -> None:
        todo = list(dict.fromkeys(key for key in keys if key not in self.planned))
        if not todo:
            return
        moves, back_m, on_m, curved = _moves_from_to(
            self.heading_deg,
            [_without_lines(self.cells[i], 0, last) for i, _, last, _ in todo],
            [_without_lines(self.cells[j], first, 0) for _, j, _, first in todo],
            self.router,
            self.vehicle,
        )
        for t, key in enumerate(todo):
            self.planned[key] = _PlannedMove(
                moves[t], float(back_m[t]), float(on_m[t]), bool(curved[t])
            )

    def _proposed(self, move: _MoveKey, back: int, on: int, now: set[_MoveKey]) -> _Drops | None:
        """Drop ``back`` more lines before ``move`` and ``on`` more after it, if that can be.

        Lines go from the end of the cell the move leaves, then, once it has none, from the
        end of the cell before it; and from the start of the cell it joins, then the next.
        Only a line at its cell's side goes (a snake's last line may lie inside the cell:
        dropping it would leave a gap), and a line must be left in the plan. None if not.
        ``now``: the moves of the cells as they are.
        """
        first, last = list(self.first_dropped), list(self.last_dropped)
        changed: set[int] = set()
        length_m = 0.0
        for count, cell, step in ((back, move[0], -1), (on, move[1], 1)):
            for _ in range(count):
                while 0 <= cell < len(self.cells) and first[cell] + last[cell] >= len(
                    self.line_m[cell]
                ):
                    cell += step
                if not 0 <= cell < len(self.cells):
                    return None
                index = self.cells[cell].index[first[cell] : len(self.line_m[cell]) - last[cell]]
                k = len(index) - 1 if step < 0 else 0  # the line dropped, among those left
                if index[k] != index.min() and index[k] != index.max():
                    return None
                length_m += float(self.line_m[cell][first[cell] + k])
                changed.add(cell)
                if step < 0:
                    last[cell] += 1
                else:
                    first[cell] += 1
        if not self._alive(first, last):
            return None
        new_moves = [key for key in self._keys(first, last) if key not in now]
        touched = changed | {key[0] for key in new_moves} | {key[1] for key in new_moves}
        return _Drops(length_m, first, last, touched, new_moves)

    def drop_slivers(self) -> None:
        """Drop the slivers that moves with corners leave or join, while that helps.

        A sliver is a cell left with one line shorter than the turning radius: a stub in a
        pocket of the boundary, often one of a row of them along a scalloped edge (a
        spiral's core inside rounds that loop round a wavy bund). Driving it takes a loop of
        half a turning circle or more for less than a radius of line. Between two stubs of
        a row no move has a curve, and dropping up to :data:`MOST_DROPPED` lines at a time
        (:meth:`drop_for_curves`) leaves a stub at one end or the other: it would try every
        split of the row in turn, each move routed anew along the scallops. So every sliver
        that a move with corners leaves or joins goes at once, and again for the moves then
        planned, as long as each round leaves fewer moves with corners than before (else
        the round is undone and the drops stop: a move may have corners for the other cell's
        sake, and its sliver would go for nothing). A round that would drop every cell left
        is not made. The test is on the round's total: a sliver between two moves that
        have corners for their other cells' sake goes too (two moves with corners become
        one), and a round that clears a row keeps whatever else it dropped; judging each
        run of slivers by the move that replaces it would be stricter.
        """
        limit_m = turning_radius_m(self.vehicle)
        while True:
            now = self._keys(self.first_dropped, self.last_dropped)
            cornered = self._cornered(now)
            slivers = {c for key in cornered for c in key[:2] if self._is_sliver(c, limit_m)}
            alive = self._alive(self.first_dropped, self.last_dropped)
            if not slivers or len(slivers) >= len(alive):
                return
            before = list(self.first_dropped)
            for c in slivers:
                self.first_dropped[c] = len(self.line_m[c]) - self.last_dropped[c]
            after = self._keys(self.first_dropped, self.last_dropped)
            self._plan(after)
            if len(self._cornered(after)) >= len(cornered):
                self.first_dropped = before
                return

    def _cornered(self, keys: list[_MoveKey]) -> list[_MoveKey]:
        """Return the moves of ``keys`` (planned) that have corners."""
        return [key for key in keys if not self.planned[key].curved]

    def _is_sliver(self, cell: int, limit_m: float) -> bool:
        """Whether ``cell`` has one line left, shorter than ``limit_m`` [m]."""
        first, last = self.first_dropped[cell], self.last_dropped[cell]
        left = len(self.line_m[cell]) - first - last
        return left == 1 and float(self.line_m[cell][first]) < limit_m

    def drop_for_curves(self) -> None:
        """Drop lines where that turns a move with corners into curves.

        One line, then two, up to :data:`MOST_DROPPED`: every move with corners tries the
        splits of that many lines before and after it, cheapest first (least length
        dropped), and takes the first whose moves are all curves, unless a move taken
        before it changed one of the cells its moves join; such moves try again once the
        others are taken. A cell whose every line goes is dropped, and its neighbours are
        joined by a move.
        """
        for count in range(1, self.MOST_DROPPED + 1):
            while self._drop_round(count):
                pass

    def search_cornered(self) -> None:
        """Search for a path of the vehicle's arcs for each move that still has corners.

        The last resort, once no drop serves (:func:`planner.move_search.search_move`): the
        move may shorten its lines by the steps :func:`planner.move_curves.drivable_moves`
        tries, within their room. A move the search does not find keeps its corners.
        """
        steps_m = np.asarray(PULL_STEPS_R) * turning_radius_m(self.vehicle)
        for key in self._keys(self.first_dropped, self.last_dropped):
            if self.planned[key].curved:
                continue
            i, j, last, first = key
            ends, back_room_m, on_room_m = _move_ends(
                self.heading_deg,
                [_without_lines(self.cells[i], 0, last)],
                [_without_lines(self.cells[j], first, 0)],
            )
            found = search_move(
                ends,
                steps_m[steps_m <= back_room_m[0] + 1e-9],
                steps_m[steps_m <= on_room_m[0] + 1e-9],
                router=self.router,
                vehicle=self.vehicle,
            )
            if found is not None:
                self.planned[key] = _PlannedMove(
                    found.points, found.pulled_back_m, found.pushed_on_m, True
                )

    def _drop_round(self, count: int) -> bool:
        """One round of :meth:`drop_for_curves` at ``count`` lines; whether it dropped any."""
        now = self._keys(self.first_dropped, self.last_dropped)
        cornered = self._cornered(now)
        current = set(now)
        options: list[list[_Drops]] = []
        for move in cornered:
            splits = [
                self._proposed(move, back, count - back, current) for back in range(count + 1)
            ]
            options.append(sorted((s for s in splits if s is not None), key=lambda s: s.length_m))
        # The cheapest split of every move first, in one batch; the next cheapest of the
        # moves it leaves with corners; and so on: most moves take their first. A split
        # that clashes with one taken this round waits for the next round.
        taken: set[int] = set()
        open_moves = list(range(len(options)))
        for rank in range(count + 1):
            open_moves = [
                m
                for m in open_moves
                if rank < len(options[m]) and not options[m][rank].touched & taken
            ]
            self._plan([key for m in open_moves for key in options[m][rank].new_moves])
            still = []
            for m in open_moves:
                drops = options[m][rank]
                if not all(self.planned[key].curved for key in drops.new_moves):
                    still.append(m)
                elif not drops.touched & taken:
                    taken |= drops.touched
                    for c in drops.touched:
                        self.first_dropped[c] = drops.first_dropped[c]
                        self.last_dropped[c] = drops.last_dropped[c]
            open_moves = still
        return bool(taken)

    def result(self) -> tuple[list[FittedLines], list[FloatArray]]:
        """Return the cells, less the lines dropped and shortened by the moves, and the moves.

        A cell whose every line is dropped has none left.
        """
        first, last = self.first_dropped, self.last_dropped
        cells = [_without_lines(fit, first[c], last[c]) for c, fit in enumerate(self.cells)]
        alive = self._alive(first, last)
        moves = [self.planned[key] for key in self._keys(first, last)]
        shortened = _shortened(
            [cells[c] for c in alive],
            np.array([move.pulled_back_m for move in moves]),
            np.array([move.pushed_on_m for move in moves]),
        )
        for c, fit in zip(alive, shortened, strict=True):
            cells[c] = fit
        return cells, [move.points for move in moves]


def _moves_from_to(
    heading_deg: float,
    leaving: list[FittedLines],
    joining: list[FittedLines],
    router: FieldRouter,
    vehicle: Vehicle,
) -> tuple[list[FloatArray], FloatArray, FloatArray, npt.NDArray[np.bool_]]:
    """Plan the moves from ``leaving[k]`` to ``joining[k]``, for every ``k``.

    Move ``k`` leaves the end of ``leaving[k]``'s last line for the start of ``joining[k]``'s
    first (:func:`moves_between_cells`, which gives the result).
    """
    ends, back_room_m, on_room_m = _move_ends(heading_deg, leaving, joining)
    return moves_between_cells(
        np.stack([ends.x0, ends.y0], axis=1),
        ends.yaw0,
        np.stack([ends.x1, ends.y1], axis=1),
        ends.yaw1,
        router=router,
        vehicle=vehicle,
        back_room_m=back_room_m,
        on_room_m=on_room_m,
    )


def _move_ends(
    heading_deg: float, leaving: list[FittedLines], joining: list[FittedLines]
) -> tuple[TurnEnds, FloatArray, FloatArray]:
    """Return the moves from ``leaving[k]``'s last line's end to ``joining[k]``'s first start.

    Returns their ends (local [m], headings [rad]) and the most each may shorten the line
    it leaves and the line it joins [m] (less than half, keeping :data:`_KEPT_LINE_M`).
    """
    first_u = np.array([fit.u[0] for fit in joining])
    first_v = np.array([fit.v_start[0] for fit in joining])
    last_u = np.array([fit.u[-1] for fit in leaving])
    x_on, y_on = from_sweep(first_u, first_v, heading_deg)
    x_off, y_off = from_sweep(last_u, np.array([fit.v_end[-1] for fit in leaving]), heading_deg)
    first_m = np.array([abs(fit.v_end[0] - fit.v_start[0]) for fit in joining])
    last_m = np.array([abs(fit.v_end[-1] - fit.v_start[-1]) for fit in leaving])
    xb, yb = from_sweep(last_u, np.array([fit.v_start[-1] for fit in leaving]), heading_deg)
    # Lines run along the heading (+v is (sin h, cos h) in local x, y) or against it; a
    # move leaves its line in the direction from the line's start to its end.
    theta = math.radians(heading_deg)
    along = math.atan2(math.cos(theta), math.sin(theta))
    leaves_up = np.array([fit.v_end[-1] >= fit.v_start[-1] for fit in leaving], dtype=bool)
    joins_up = np.array([fit.v_end[0] >= fit.v_start[0] for fit in joining], dtype=bool)
    here_yaw = np.where(
        last_m > 1e-9,
        np.arctan2(y_off - yb, x_off - xb),
        np.where(leaves_up, along, along + math.pi),
    )
    ends = TurnEnds(x_off, y_off, here_yaw, x_on, y_on, np.where(joins_up, along, along + math.pi))
    return (
        ends,
        np.maximum((last_m - _KEPT_LINE_M) / 2.0, 0.0),
        np.maximum((first_m - _KEPT_LINE_M) / 2.0, 0.0),
    )


def _without_lines(fit: FittedLines, first: int, last: int) -> FittedLines:
    """Return ``fit`` without its ``first`` first and ``last`` last lines, and their turns."""
    if first == 0 and last == 0:
        return fit
    stop = max(len(fit.u) - last, first)
    # The turns between the lines kept: lines first … stop - 1 have turns first … stop - 2.
    turns = turn_range(fit.turns, 0, 0) if stop == first else turn_range(fit.turns, first, stop - 1)
    return replace(
        fit,
        u=fit.u[first:stop],
        v_start=fit.v_start[first:stop],
        v_end=fit.v_end[first:stop],
        index=fit.index[first:stop],
        turns=turns,
    )


def _shortened(
    driven: list[FittedLines], pulled_back_m: FloatArray, pushed_on_m: FloatArray
) -> list[FittedLines]:
    """Return ``driven`` with the first and last lines shortened by the moves' pulls.

    Move ``k`` leaves cell ``k`` and joins cell ``k + 1`` (of the cells with lines). New
    arrays: a fit may be cached for other plans.
    """
    changed = list(driven)
    for k, (back, on) in enumerate(zip(pulled_back_m.tolist(), pushed_on_m.tolist(), strict=True)):
        if back > 0.0:
            fit = changed[k]
            v_end = fit.v_end.copy()
            v_end[-1] -= back if v_end[-1] >= fit.v_start[-1] else -back
            changed[k] = replace(fit, v_end=v_end)
        if on > 0.0:
            fit = changed[k + 1]
            v_start = fit.v_start.copy()
            v_start[0] += on if fit.v_end[0] >= v_start[0] else -on
            changed[k + 1] = replace(fit, v_start=v_start)
    return changed


def moves_between_cells(
    here_xy: FloatArray,
    here_yaw_rad: FloatArray,
    target_xy: FloatArray,
    target_yaw_rad: FloatArray,
    *,
    router: FieldRouter,
    vehicle: Vehicle,
    back_room_m: FloatArray,
    on_room_m: FloatArray,
) -> tuple[list[FloatArray], FloatArray, FloatArray, npt.NDArray[np.bool_]]:
    """Plan the moves from line ends to other cells' first line starts.

    Move ``k`` leaves ``here_xy[k]``, the end of a line driven at ``here_yaw_rad[k]``, for
    ``target_xy[k]``, the start of a line driven at ``target_yaw_rad[k]``. Each is the
    vehicle's own turn (a Dubins or pivot curve from pose to pose) if it stays inside the
    machine area; the turns are planned in one call and tested in another. Else a vehicle
    that pivots takes the shortest path inside it (:meth:`planner.routing.FieldRouter.paths`),
    with points at most 0.5 m apart, and turns its corners on the spot; one with a turning
    radius takes a curve that gives up some of the lines' length
    (:func:`planner.move_curves.drivable_moves`, at most ``back_room_m[k]`` off the line it
    leaves and ``on_room_m[k]`` off the one it joins), or, if none is found, that shortest
    path, whose corners it cannot turn (:func:`drive_cells` then drops lines or searches for a
    path; ``bench.move_corners`` counts the moves left with corners).

    Parameters
    ----------
    here_xy, target_xy : ndarray, shape (k, 2)
        Local [m].
    here_yaw_rad, target_yaw_rad : ndarray, shape (k,)
        Headings, from local x [rad].
    router : FieldRouter
    vehicle : Vehicle
    back_room_m, on_room_m : ndarray, shape (k,)
        The most each move may shorten the line it leaves and the line it joins [m].

    Returns
    -------
    moves : list of ndarray
        Each move's points, from ``here_xy[k]`` (less its pull-back) to ``target_xy[k]``
        (plus its push-on), local [m].
    pulled_back_m, pushed_on_m : ndarray, shape (k,)
        How much earlier the line move ``k`` leaves now ends, and how much later the line it
        joins starts [m].
    curved : ndarray of bool, shape (k,)
        Whether the vehicle drives move ``k`` as planned: False for a vehicle with a turning
        radius that has no curve for it (the shortest path, with corners).
    """
    count = len(here_xy)
    ends = TurnEnds(
        here_xy[:, 0], here_xy[:, 1], here_yaw_rad,
        target_xy[:, 0], target_xy[:, 1], target_yaw_rad,
    )  # fmt: skip
    moves: list[FloatArray | None] = [None] * count
    if count:
        curves = vehicle_turns(ends, vehicle)
        tried = [(k, curves.curve(k)) for k in range(count)]
        tried = [(k, curve) for k, curve in tried if len(curve) >= 2]
        inside = router.inside_paths([curve for _, curve in tried]).tolist()
        for (k, curve), ok in zip(tried, inside, strict=True):
            if ok:
                moves[k] = curve
    pulled_back, pushed_on = np.zeros(count), np.zeros(count)
    routes: dict[int, FloatArray] = {}
    curving = np.array([k for k in range(count) if moves[k] is None], dtype=np.int64)
    if vehicle.min_turn_radius_m > 0.0 and len(curving):
        found = drivable_moves(
            ends.take(curving),
            back_room_m=back_room_m[curving],
            on_room_m=on_room_m[curving],
            router=router,
            vehicle=vehicle,
        )
        for j, k in enumerate(curving.tolist()):
            moves[k] = found.curves[j]
            route = found.routes[j]
            if route is not None:
                routes[k] = route
        pulled_back[curving] = found.pulled_back_m
        pushed_on[curving] = found.pushed_on_m
    routed = [k for k in range(count) if moves[k] is None and k not in routes]
    for k, path in zip(routed, router.paths(here_xy[routed], target_xy[routed]), strict=True):
        routes[k] = path
    driven = [densify(routes[k], STEP_M) if move is None else move for k, move in enumerate(moves)]
    curved = np.array([move is not None for move in moves], dtype=bool)
    if vehicle.min_turn_radius_m <= 0.0:
        curved[:] = True  # it turns the routes' corners on the spot
    return driven, pulled_back, pushed_on, curved
