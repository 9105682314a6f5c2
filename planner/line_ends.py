"""Line ends where the turn fits: the paper's Algorithm 1 pull-back, generalised to a vehicle.

The paper pulls each line end back from the bund so that the tractor can pivot without
leaving the field. Here the whole machine must stay in (R1): the path buffered by half the
vehicle's width lies inside the field, so the path itself lies inside the *machine area*, the
field eroded by that half-width. A turn joins the end of one line to the start of the next; it
depends only on where the two ends are relative to each other, so pulling both ends back
along their lines by the same distance slides the turn back unchanged. For every turn that
distance is the smallest that brings the whole driven curve inside the machine area, read
off the area's upper (or lower) chain in the sweep frame, in closed form for all turns at once.
An Ω whose slide would be long, or that cannot fit, is tried with one end further back
(:mod:`planner.lopsided_turns`). A turn that cannot fit at any distance (it swings out beyond
the side of the area), a line that the pull-back eats up, or a line at the side whose turn
costs its neighbour more than the line runs removes that line, and the cell is fitted again.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
import numpy.typing as npt
import shapely
from shapely import MultiPolygon, Polygon

from planner.coverage import Chains
from planner.errors import InvalidParameterError
from planner.lopsided_turns import (
    LopsidedPairs,
    lopsided_turn_groups,
    lopsided_turns,
    pair_ends,
    tried_lopsided,
)
from planner.turn_slides import slide_turn_groups, slide_turns
from planner.turns import (
    TurnCurves,
    TurnEnds,
    concat_turns,
    no_turns,
    take_turns,
    turn_range,
    turning_radius_m,
    vehicle_turns,
)
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: Points this close outside the machine area count as inside (R1 allows 1 cm) [m].
FIT_TOLERANCE_M = 1e-6
#: Pieces of the machine area smaller than this share of the largest are left out.
MIN_PART_SHARE = 0.01
#: Refits of a cell at most (each removes at least one line; the first half from the sides).
_MAX_ROUNDS = 40


@dataclass(frozen=True, slots=True)
class FittedLines:
    """A cell's lines in driving order, with their ends pulled back and the turns between them.

    Everything is in the cell's sweep frame [m]: ``u`` across the lines, ``v`` along them.

    Attributes
    ----------
    u, v_start, v_end : ndarray, shape (n,)
        Each driven line, from ``v_start`` to ``v_end``.
    index : ndarray of int, shape (n,)
        Position of each driven line in the input (left to right).
    turns : TurnCurves
        The ``n - 1`` turns, sweep frame.
    """

    u: FloatArray
    v_start: FloatArray
    v_end: FloatArray
    index: IntArray
    turns: TurnCurves


def fit_lines(
    u: FloatArray,
    v_start: FloatArray,
    v_end: FloatArray,
    index: IntArray,
    *,
    machine: Chains,
    vehicle: Vehicle,
    planned: TurnCurves | None = None,
    first_turns: FirstTurns | None = None,
) -> FittedLines:
    """Pull line ends back until every turn between consecutive lines fits the machine area.

    Parameters
    ----------
    u, v_start, v_end : ndarray, shape (n,)
        The lines in driving order (directions alternate), sweep frame [m]; their ends lie
        on the machine area's chains.
    index : ndarray of int, shape (n,)
        Each line's left-to-right index, carried through.
    machine : Chains
        The machine area of the cell (the field eroded by half the vehicle's width), convex
        or sweep-monotone, in the same sweep frame.
    vehicle : Vehicle
    planned : TurnCurves, optional
        The ``n - 1`` turns between consecutive lines as given, if planned already (many
        cells at once: :func:`planner.cell_route.fit_cells`).
    first_turns : FirstTurns, optional
        Those turns fitted already (many headings at once: :func:`fit_line_turns`).

    Returns
    -------
    FittedLines
        Possibly fewer lines: those the turns cannot reach are left out.

    Examples
    --------
    A 20 m × 30 m machine area, hand tractor, lines 4 m apart: each end moves back by the
    pivot's reach, half the track.

    >>> from planner.coverage import convex_chains
    >>> from planner.vehicles import resolve_vehicle
    >>> area = convex_chains(np.array([0.0, 20, 20, 0]), np.array([0.0, 0, 30, 30]))
    >>> u = np.array([2.0, 6.0, 10.0])
    >>> fit = fit_lines(u, np.array([0.0, 30, 0]), np.array([30.0, 0, 30]), np.arange(3),
    ...                 machine=area, vehicle=resolve_vehicle("hand_tractor"))
    >>> fit.v_start.round(3).tolist(), fit.v_end.round(3).tolist()
    ([0.0, 29.65, 0.35], [29.65, 0.35, 30.0])
    """
    keep = np.ones(len(u), dtype=bool)
    up = v_end >= v_start
    first_drop = None
    if first_turns is not None and len(u) > 1:
        # The first round's turns are fitted already: a cell that drops no line is done.
        curves, shift_end_m, shift_start_m, fits = first_turns
        a2, b2, first_drop = _pulled_back(
            u, v_start, v_end, up, shift_end_m, shift_start_m, fits, machine
        )
        if not first_drop.any():
            return FittedLines(u.copy(), a2, b2, index.copy(), curves)  # not the caller's
    # A turn depends only on the two line ends it joins, as given (the pull-back is its own
    # output), so a refit round reuses every turn whose pair of lines is still adjacent and
    # plans only the turns of the pairs that dropping a line made.
    lines = _Lines(u, v_start, v_end, up, index)
    turns = _TurnStore(lines, machine, vehicle, planned, first_turns)
    if first_drop is not None:
        every = np.arange(len(u))
        turns.ids(every[:-1], every[1:])  # the first round's turns, for the next rounds
    for round_ in range(_MAX_ROUNDS):
        k = np.nonzero(keep)[0]
        if round_ == 0 and first_drop is not None:
            drop = first_drop
        else:
            fit, drop = _fit_once(k, turns)
            if not drop.any():
                return fit
        if round_ < _MAX_ROUNDS // 2:
            # Lines drop from the sides inwards, so the rest stay an interval apart (R2):
            # a problem left of the middle drops the leftmost line, right of it the rightmost.
            uk = u[k]
            middle = _median(uk)
            side_drop = np.zeros(len(k), dtype=bool)
            if (drop & (uk <= middle)).any():
                side_drop[int(np.argmin(uk))] = True
            if (drop & (uk > middle)).any():
                side_drop[int(np.argmax(uk))] = True
            drop = side_drop
        keep[k[drop]] = False
    k = np.nonzero(keep)[0]
    fit, _ = _fit_once(k[:1], turns)
    return fit


def plan_line_turns(
    ordered: Sequence[tuple[FloatArray, FloatArray, FloatArray, IntArray]],
    vehicle: Vehicle,
) -> list[TurnCurves | None]:
    """Plan the turns between consecutive lines of many line sets at once (sweep frame).

    ``ordered`` holds ``(u, v_start, v_end, index)`` per set, in driving order (cells of a
    plan, or one field at many headings); each set's turns come back as :func:`fit_lines`'
    ``planned``, None for a set of one line. One call for all: a set has a few lines, and
    planning them set by set was mostly call overhead.
    """
    curves = _all_line_turns(ordered, vehicle)
    out: list[TurnCurves | None] = []
    first = 0
    for u, _, _, _ in ordered:
        count = len(u) - 1 if len(u) > 1 else 0
        out.append(turn_range(curves, first, first + count) if count else None)
        first += count
    return out


def _all_line_turns(
    ordered: Sequence[tuple[FloatArray, FloatArray, FloatArray, IntArray]], vehicle: Vehicle
) -> TurnCurves:
    """Plan the turns between consecutive lines of every set of ``ordered``, set after set."""
    # The six columns of TurnEnds, set by set (one set, the usual case: its slices as they are).
    columns: list[list[FloatArray]] = [[], [], [], [], [], []]
    for u, a, b, _ in ordered:
        if len(u) > 1:
            yaw = np.where(b >= a, math.pi / 2.0, -math.pi / 2.0)
            for column, values in zip(
                columns, (u[:-1], b[:-1], yaw[:-1], u[1:], a[1:], yaw[1:]), strict=True
            ):
                column.append(values)
    if not columns[0]:
        return no_turns(vehicle)
    x0, y0, yaw0, x1, y1, yaw1 = (c[0] if len(c) == 1 else np.concatenate(c) for c in columns)
    return vehicle_turns(TurnEnds(x0, y0, yaw0, x1, y1, yaw1), vehicle)


def _median(values: FloatArray) -> float:
    """``np.median`` of a few values, without its overhead (the same value, 20 times faster)."""
    ordered = np.sort(values)
    half = len(ordered) // 2
    if len(ordered) % 2:
        return float(ordered[half])
    return float((ordered[half - 1] + ordered[half]) / 2.0)


class _Lines(NamedTuple):
    """The lines :func:`fit_lines` fits, in driving order (sweep frame [m])."""

    u: FloatArray
    v_start: FloatArray
    v_end: FloatArray
    up: BoolArray  # whether it runs towards +v
    line_index: IntArray  # its left-to-right index, carried through


def _fit_once(k: IntArray, turns: _TurnStore) -> tuple[FittedLines, BoolArray]:
    """One fitting round on the lines ``k``: the fitted lines, and which to drop before the next."""
    lines, machine = turns.lines, turns.machine
    u, a, b, up, index = (
        lines.u[k],
        lines.v_start[k],
        lines.v_end[k],
        lines.up[k],
        lines.line_index[k],
    )
    n = len(u)
    if n < 2:
        return FittedLines(u, a, b, index, turns.empty), np.zeros(n, dtype=bool)
    ids = turns.ids(k[:-1], k[1:])
    a2, b2, drop = _pulled_back(
        u, a, b, up, turns.shift_end_m[ids], turns.shift_start_m[ids], turns.fits[ids], machine
    )
    if drop.any():
        return FittedLines(u, a2, b2, index, turns.empty), drop
    return FittedLines(u, a2, b2, index, turns.take(ids)), drop


def _pulled_back(
    u: FloatArray,
    a: FloatArray,
    b: FloatArray,
    up: BoolArray,
    shift_end_m: FloatArray,
    shift_start_m: FloatArray,
    fits: BoolArray,
    machine: Chains,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Move the ends of the lines ``u`` (from ``a`` to ``b``) by their turns' shifts.

    ``shift_end_m``, ``shift_start_m`` and ``fits``: each turn's, between consecutive lines
    (:func:`_fit_turns`). Returns the new starts and ends, and which lines to drop.
    """
    n = len(u)
    a2, b2 = a.copy(), b.copy()
    b2[:-1] += shift_end_m
    a2[1:] += shift_start_m
    length = np.where(up, b2 - a2, a2 - b2)
    drop = length < 0.0
    # A line at a side of the cell and an end of the route, whose one turn pulls its
    # neighbour's end back further than the line itself runs, costs more than it tills.
    ends = ((0, abs(shift_start_m[0])), (n - 1, abs(shift_end_m[-1])))
    for e, pulled in ends:
        if pulled > length[e] and u[e] in (u.min(), u.max()):
            drop[e] = True
    # A turn that cannot fit drops the outer of its two lines (nearer the side of the area),
    # so that the lines left stay an interval apart.
    bad = np.nonzero(~fits)[0]
    if len(bad):
        inset = np.minimum(u - machine.u_min, machine.u_max - u)
        for t in bad.tolist():
            outer = t if inset[t] <= inset[t + 1] else t + 1
            drop[outer] = True
    if drop.all():  # one line needs no turn: keep the longest
        drop[int(np.argmax(np.abs(b - a)))] = False
    return a2, b2, drop


class _TurnStore:
    """Every turn fitted so far, by the pair of lines it joins (:func:`fit_lines`' rounds)."""

    def __init__(
        self,
        lines: _Lines,
        machine: Chains,
        vehicle: Vehicle,
        planned: TurnCurves | None = None,
        first_turns: FirstTurns | None = None,
    ) -> None:
        self.lines, self.machine = lines, machine
        self._planned = planned  # the turns of the first round, if given
        self._first_turns = first_turns  # ... or those turns fitted, if given
        self._vehicle = vehicle
        self._n = len(lines.u)
        self._slot: dict[int, int] = {}
        self.empty = no_turns(vehicle)
        self.curves = self.empty
        self.shift_end_m = np.zeros(0)  # of the first line's end
        self.shift_start_m = np.zeros(0)  # of the second line's start
        self.fits = np.zeros(0, dtype=bool)

    def ids(self, first: IntArray, second: IntArray) -> IntArray:
        """Slots of the turns from line ``first`` to line ``second``, fitting any new ones."""
        keys = (first * self._n + second).tolist()
        slot = self._slot
        # The first round's pairs (each line and its next) are distinct and all new: their
        # slots are 0, 1, ... without a look-up per pair.
        everything_new = not slot
        new = (
            list(range(len(keys)))
            if everything_new
            else [i for i, key in enumerate(keys) if key not in slot]
        )
        if new:
            pick = np.asarray(new, dtype=np.int64)
            planned = None
            first_round = not slot and len(new) == self._n - 1  # every line and its next
            if first_round and self._first_turns is not None:
                curves, shift_end_m, shift_start_m, fits = self._first_turns
            else:
                if first_round:
                    planned = self._planned
                curves, shift_end_m, shift_start_m, fits = _fit_turns(
                    first[pick], second[pick], self.lines, self.machine, self._vehicle, planned
                )
            base = len(self.fits)
            for j, i in enumerate(new):
                slot[keys[i]] = base + j
            self.curves = concat_turns(self.curves, curves) if base else curves
            self.shift_end_m = np.concatenate([self.shift_end_m, shift_end_m])
            self.shift_start_m = np.concatenate([self.shift_start_m, shift_start_m])
            self.fits = np.concatenate([self.fits, fits])
        if everything_new:
            return np.arange(len(keys), dtype=np.int64)
        return np.fromiter((slot[key] for key in keys), dtype=np.int64, count=len(keys))

    def take(self, ids: IntArray) -> TurnCurves:
        """Return the turns in slots ``ids``, as one ragged array."""
        curves = self.curves
        if len(ids) == len(curves) and (ids == np.arange(len(ids))).all():
            return curves
        return take_turns(curves, ids)


def _fit_turns(
    first: IntArray,
    second: IntArray,
    lines: _Lines,
    machine: Chains,
    vehicle: Vehicle,
    planned: TurnCurves | None = None,
) -> tuple[TurnCurves, FloatArray, FloatArray, BoolArray]:
    """Plan and fit the turns from the end of each line ``first`` to the start of ``second``.

    ``planned``: those turns, if they are planned already.

    Returns
    -------
    curves : TurnCurves
        The turns slid back along the lines so that they fit.
    shift_end_m, shift_start_m : ndarray
        How far the end of line ``first`` and the start of line ``second`` move along ``v``
        (down at the top, up at the bottom) [m]: the same unless the turn is lopsided
        (:func:`planner.lopsided_turns.lopsided_turns`).
    fits : ndarray of bool
        Whether it fits the machine area at all.
    """
    if planned is None:
        ends = pair_ends(lines.u, lines.up, lines.v_end, lines.v_start, first, second)
        planned = vehicle_turns(ends, vehicle)
    level, tried = _level_turns(lines.u, lines.up, first, second, machine, planned)
    if not tried.any():
        return level[0], level[1], level[1].copy(), level[2]
    pairs = LopsidedPairs(lines.u, lines.up, lines.v_end, lines.v_start, first, second)
    return lopsided_turns(pairs, machine, vehicle, level, tried, tolerance_m=FIT_TOLERANCE_M)


def _level_turns(
    u: FloatArray,
    up: BoolArray,
    first: IntArray,
    second: IntArray,
    machine: Chains,
    curves: TurnCurves,
) -> tuple[tuple[TurnCurves, FloatArray, BoolArray], BoolArray]:
    """Slide the turns ``curves`` from line ``first`` to ``second`` level until they fit.

    Also returns which of them to try lopsided.
    """
    top = up[first]
    fitted, shift, fits = slide_turns(curves, top, machine, tolerance_m=FIT_TOLERANCE_M)
    # An Ω (lines closer than two radii) swings out beyond both lines: slid back as a whole
    # it can follow a boundary nearly parallel to the lines, or down a step, for tens of
    # metres, or not fit beside it at all. Such a turn is tried lopsided.
    spacing_m = np.abs(u[second] - u[first])
    return (fitted, shift, fits), tried_lopsided(curves, top, spacing_m, shift, fits)


#: The first fitting round's turns of a line set: the turns, how far the end of each turn's
#: first line and the start of its second move [m], and whether each fits
#: (:func:`_fit_turns`).
FirstTurns = tuple[TurnCurves, FloatArray, FloatArray, BoolArray]


def fit_line_turns(
    ordered: Sequence[tuple[FloatArray, FloatArray, FloatArray, IntArray]],
    machines: Sequence[Chains],
    vehicle: Vehicle,
) -> list[FirstTurns | None]:
    """Fit the turns between consecutive lines of many line sets at once (sweep frame).

    :func:`fit_lines`' first round for each set of ``ordered`` (as :func:`plan_line_turns`
    takes them) on its machine area, as its ``first_turns``; None for a set of one line. The
    turns are planned, slid level (:func:`planner.turn_slides.slide_turn_groups`) and tried
    lopsided (:func:`planner.lopsided_turns.lopsided_turn_groups`) in one call each for all
    sets: a turn depends only on its own ends (:func:`planner.turns.vehicle_turns`), and each
    set's are slid as :func:`fit_lines` would slide them alone, so each set's figures are
    those it would have alone, to the last bit.
    """
    out: list[FirstTurns | None] = [None] * len(ordered)
    sets = [i for i, (u, _, _, _) in enumerate(ordered) if len(u) > 1]
    if not sets:
        return out
    # Every set's lines end to end; each turn joins a line to the next of its set.
    line_at = np.zeros(len(sets) + 1, dtype=np.int64)
    np.cumsum([len(ordered[i][0]) for i in sets], out=line_at[1:])
    turn_at = line_at - np.arange(len(sets) + 1)
    u, v_start, v_end = (np.concatenate([ordered[i][c] for i in sets]) for c in (0, 1, 2))
    # Each line but a set's last turns to the next; no turn joins one set to the next.
    first = np.delete(np.arange(line_at[-1] - 1), line_at[1:-1] - 1)
    pairs = LopsidedPairs(u, v_end >= v_start, v_end, v_start, first, first + 1)
    areas = [machines[i] for i in sets]
    planned = _all_line_turns(ordered, vehicle)
    top = pairs.up[first]
    level = slide_turn_groups(planned, top, turn_at, areas, tolerance_m=FIT_TOLERANCE_M)
    tried = tried_lopsided(planned, top, np.abs(u[first + 1] - u[first]), level[1], level[2])
    if tried.any():
        curves, shift_end_m, shift_start_m, fits = lopsided_turn_groups(
            pairs, areas, turn_at, vehicle, level, tried, tolerance_m=FIT_TOLERANCE_M
        )
    else:
        curves, shift_end_m, fits = level
        shift_start_m = shift_end_m.copy()
    for g, i in enumerate(sets):
        t0, t1 = int(turn_at[g]), int(turn_at[g + 1])
        out[i] = (
            turn_range(curves, t0, t1),
            shift_end_m[t0:t1],
            shift_start_m[t0:t1],
            fits[t0:t1],
        )
    return out


def machine_area(field_local: Polygon, vehicle: Vehicle) -> Polygon | MultiPolygon:
    """Erode the field by half the vehicle's width: where the path may run (R1).

    For a convex field the mitred erosion is exact; round joins (the default) are the exact
    erosion of any field, with arcs round its inner corners.

    Raises
    ------
    InvalidParameterError
        If nothing is left: the vehicle is wider than the field.
    """
    join: Literal["mitre", "round"] = "mitre" if _convex(field_local) else "round"
    eroded = field_local.buffer(-vehicle.width_m / 2.0, join_style=join)
    pieces = [eroded] if isinstance(eroded, Polygon) else shapely.get_parts(eroded)  # no copy
    parts = [p for p in pieces if isinstance(p, Polygon) and p.area > 1e-9]
    if parts:
        # Slivers cut off where the bund bends sharply hold no line worth a trip.
        largest = max(p.area for p in parts)
        parts = [p for p in parts if p.area >= MIN_PART_SHARE * largest]
    if not parts:
        raise InvalidParameterError(
            "vehicle", f"a {vehicle.width_m:g} m-wide vehicle does not fit in this field"
        )
    if len(parts) == 1:
        return shapely.orient_polygons(parts[0])
    multi: MultiPolygon = shapely.orient_polygons(MultiPolygon(parts))
    return multi


def snake_skip(vehicle: Vehicle, interval_m: float) -> int:
    """Lines to skip from one driven line to the next so that turns need no loop.

    A U-turn of two arcs needs the lines two turning radii apart.

    Examples
    --------
    >>> from planner.vehicles import resolve_vehicle
    >>> snake_skip(resolve_vehicle("small_tractor"), 4.0), snake_skip(
    ...     resolve_vehicle("hand_tractor"), 4.0)
    (2, 1)
    """
    return max(1, math.ceil(2.0 * turning_radius_m(vehicle) / interval_m - 1e-9))


def _convex(polygon: Polygon) -> bool:
    hull = polygon.convex_hull
    return not polygon.interiors and bool(hull.area - polygon.area <= 1e-9 * max(hull.area, 1.0))
