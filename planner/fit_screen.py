"""Fitted coverage screened at many headings: each cell's lines fitted from a table of turns.

R5 compares headings on what the vehicle covers once its line ends are pulled back until
the turns fit (:func:`planner.line_ends.fit_lines`). With a turning radius that differs from
a heading's cheap coverage by several percentage points, and by different amounts at
headings a degree apart (the small tractor at 4 m: a median spread of 4.6 pp), so no
estimate from the cheap figures ranks headings to the rule's 0.2 pp; fitting a heading for
real costs about 3 ms, too much to do at every one.

Here the fit is repeated in the screen's compiled loop, cheaply: a turn between two lines
depends only on where its end lies relative to its start, so the vehicle's turns are planned
once, for every end offset along the lines on a grid (:func:`turn_table`), and each turn of
a cell is looked up, placed on its line end and slid back until it lies inside the cell
(:func:`_slide`), tried lopsided as :mod:`planner.lopsided_turns` does, and lines are dropped
from the sides as :func:`planner.line_ends.fit_lines` drops them. The figure is an estimate,
not the fit: the end offset is rounded to :data:`TABLE_STEP_M`, spacings to a
:data:`SPACING_CLASSES`-th of the interval, a curve's chords are not checked against the
chain's vertices between its points, and lines left after the sides' rounds stay. Each cell
is fitted with its first line driven up and with it down, and counted the way the plan will
drive it (:mod:`planner.parity_kernels`: on one real field the two differ by 22 pp of its
area).
The planner fits the headings it ranks best for real (:func:`planner.cover_picks.cover_picks`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from planner.kernel_helpers import _jit_counted_by_caller, _right
from planner.lopsided_turns import LOPSIDED_RADII, RETRY_RADII
from planner.turns import TurnEnds, turning_radius_m, vehicle_turns
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Grid of the turns' end offsets along the lines [m].
TABLE_STEP_M = 0.2
#: ... from minus to plus this much [m]; a turn beyond is the last one moved along the lines.
TABLE_REACH_M = 30.0
#: Spacings between a turn's two lines tabled: the interval and these many fractions of it
#: (a cell's last line may lie closer to the one before).
SPACING_CLASSES = 8
#: Every this many points of a turn are checked (and its last).
SUBSAMPLE = 3
#: Points this close outside the cell count as inside [m] (planner.line_ends.FIT_TOLERANCE_M).
_TOLERANCE_M = 1e-6
#: Rounds of dropping lines from the sides (planner.line_ends._MAX_ROUNDS // 2).
_SIDE_ROUNDS = 20

#: A cell in the sweep frame: its lower and upper chains ``lo_u, lo_v, hi_u, hi_v`` and its
#: extent across the lines ``u_min, u_max`` [m] (:class:`planner.coverage.Chains`).
_Cell = tuple[FloatArray, FloatArray, FloatArray, FloatArray, float, float]


@dataclass(frozen=True, slots=True)
class TurnTable:
    """The vehicle's turns from a line end to the start of the next line, every offset.

    Turn ``c * K + k`` (``K`` offsets) leaves ``(0, 0)`` heading +v and ends at
    ``((c + 1) / SPACING_CLASSES * spacing_m, -reach_m + k * step_m)`` heading -v: a turn
    at the top of the lines towards +u. Others are its mirror images.

    Attributes
    ----------
    offsets : ndarray of int
        Turn ``s`` is points ``offsets[s]:offsets[s + 1]``.
    u, v : ndarray
        The points, relative to the turn's start [m].
    beyond_m : ndarray
        How far each turn runs beyond the farther of its two ends [m].
    u_lo, u_hi : ndarray
        Each turn's extent across the lines [m].
    scalars : ndarray
        ``step_m, reach_m, spacing_m, classes, radius_m, lopsided back [m], retry radii``.
    """

    offsets: IntArray
    u: FloatArray
    v: FloatArray
    beyond_m: FloatArray
    u_lo: FloatArray
    u_hi: FloatArray
    scalars: FloatArray


@functools.lru_cache(maxsize=16)
def turn_table(vehicle: Vehicle, spacing_m: float) -> TurnTable:
    """Plan ``vehicle``'s turns between lines up to ``spacing_m`` apart at every end offset.

    Examples
    --------
    >>> from planner.vehicles import resolve_vehicle
    >>> table = turn_table(resolve_vehicle("small_tractor"), 4.0)
    >>> len(table.offsets) - 1 == SPACING_CLASSES * (2 * round(TABLE_REACH_M / TABLE_STEP_M) + 1)
    True
    """
    half = round(TABLE_REACH_M / TABLE_STEP_M)
    offsets_m = np.arange(-half, half + 1) * TABLE_STEP_M
    spacings = float(spacing_m) * np.arange(1, SPACING_CLASSES + 1) / SPACING_CLASSES
    x1 = np.repeat(spacings, len(offsets_m))
    y1 = np.tile(offsets_m, SPACING_CLASSES)
    zero = np.zeros(len(x1))
    curves = vehicle_turns(
        TurnEnds(zero, zero, zero + math.pi / 2.0, x1, y1, zero - math.pi / 2.0), vehicle
    )
    starts = curves.offsets[:-1]
    highest = np.maximum.reduceat(curves.xy[:, 1], starts)
    # Every SUBSAMPLE-th point and each turn's last: chords of about 1.5 m stray some 9 cm
    # from a 3 m arc, a screen's error; the slide costs a third.
    index = np.arange(len(curves.xy))
    last = np.zeros(len(index), dtype=bool)
    last[curves.offsets[1:] - 1] = True
    owner = np.repeat(np.arange(len(starts)), curves.point_counts())
    kept = ((index - curves.offsets[owner]) % SUBSAMPLE == 0) | last
    counts = np.bincount(owner[kept], minlength=len(starts))
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    radius = turning_radius_m(vehicle)
    scalars = np.array(
        [
            TABLE_STEP_M,
            half * TABLE_STEP_M,
            float(spacing_m),
            float(SPACING_CLASSES),
            radius,
            LOPSIDED_RADII[0] * radius,
            RETRY_RADII,
        ]
    )
    return TurnTable(
        offsets,
        np.ascontiguousarray(curves.xy[kept, 0]),
        np.ascontiguousarray(curves.xy[kept, 1]),
        highest - np.maximum(y1, 0.0),
        np.minimum.reduceat(curves.xy[:, 0], starts),
        np.maximum.reduceat(curves.xy[:, 0], starts),
        scalars,
    )


@_jit_counted_by_caller
def _slide(
    cell: _Cell,
    u0: float,
    v0: float,
    mirror_u: float,
    top: bool,
    table_u: FloatArray,
    table_v: FloatArray,
    start: int,
    stop: int,
) -> tuple[float, bool]:
    """Slide one tabled turn, placed at ``(u0, v0)``, back along ``v`` until it fits ``cell``.

    ``mirror_u`` 1 or -1 (towards -u); ``top``: at the upper chain (else mirrored in ``v``,
    at the lower one). Returns the slide [m] and whether the turn fits at all
    (:func:`planner.turn_slides.slide_turns`).
    """
    lo_u, lo_v, hi_u, hi_v, u_min, u_max = cell
    delta = 0.0
    lowest = math.inf  # the least height above the far chain, before the slide
    j_lo = j_hi = -1
    for i in range(start, stop):
        u = u0 + mirror_u * table_u[i]
        if u < u_min - _TOLERANCE_M or u > u_max + _TOLERANCE_M:
            return math.inf, False  # beyond the side of the cell: slid back, still out
        lo, j_lo = _walk(u, lo_u, lo_v, j_lo)
        hi, j_hi = _walk(u, hi_u, hi_v, j_hi)
        v = v0 + table_v[i] if top else v0 - table_v[i]
        need, height = (v - hi, v - lo) if top else (lo - v, hi - v)
        delta = max(delta, need)
        lowest = min(lowest, height)
    # Slid back by delta, no point may cross the other chain.
    return delta, lowest - delta >= -_TOLERANCE_M


@_jit_counted_by_caller
def _walk(u: float, chain_u: FloatArray, chain_v: FloatArray, j: int) -> tuple[float, int]:
    """Return the chain's ``v`` at ``u`` (``np.interp``: level beyond its ends), and its piece.

    ``j``: the piece of the point before (-1: none); a turn's points lie close together,
    so the piece is found by stepping from there instead of by bisection.
    """
    n = len(chain_u)
    if n == 1 or u <= chain_u[0]:
        return chain_v[0], 0
    if u >= chain_u[n - 1]:
        return chain_v[n - 1], n - 2
    if j < 0:
        j = _right(chain_u, 0, n, u) - 1
    while j + 1 < n - 1 and chain_u[j + 1] < u:
        j += 1
    while j > 0 and chain_u[j] > u:
        j -= 1
    span = chain_u[j + 1] - chain_u[j]
    if span <= 0.0:
        return chain_v[j + 1], j
    return chain_v[j] + (u - chain_u[j]) * (chain_v[j + 1] - chain_v[j]) / span, j


#: Slides remembered per cell (:func:`_placed`).
CACHED_SLIDES = 16


@_jit_counted_by_caller
def _placed(
    cell: _Cell,
    u0: float,
    v0: float,
    mirror_u: float,
    top: bool,
    shape: int,
    table: tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray],
    cache_keys: IntArray,
    cache_values: FloatArray,
) -> tuple[float, bool]:
    """:func:`_slide`, in closed form where each chain is straight across the turn.

    Along a straight piece of the boundary every turn of a cell at that end is the same
    shape in the same place relative to the chain, so its slide is the same: the shape's
    extremes against the chains' slopes are computed once a cell (``cache_*``, cleared by
    the caller) and each turn then costs a few operations.
    """
    lo_u, lo_v, hi_u, hi_v, u_min, u_max = cell
    offsets, table_u, table_v, u_lo, u_hi = table
    start, stop = offsets[shape], offsets[shape + 1]
    ua = u0 + (u_lo[shape] if mirror_u > 0.0 else -u_hi[shape])
    ub = u0 + (u_hi[shape] if mirror_u > 0.0 else -u_lo[shape])
    # The chain the turn slides against, and the one it must not cross.
    near_u, near_v = (hi_u, hi_v) if top else (lo_u, lo_v)
    far_u, far_v = (lo_u, lo_v) if top else (hi_u, hi_v)
    j_near = _right(near_u, 0, len(near_u), ua) - 1
    j_far = _right(far_u, 0, len(far_u), ua) - 1
    inside = u_min - _TOLERANCE_M <= ua and ub <= u_max + _TOLERANCE_M
    straight = (
        inside
        and 0 <= j_near < len(near_u) - 1
        and ub <= near_u[j_near + 1]
        and 0 <= j_far < len(far_u) - 1
        and ub <= far_u[j_far + 1]
    )
    if not straight:
        return _slide(cell, u0, v0, mirror_u, top, table_u, table_v, start, stop)
    slope_near = (near_v[j_near + 1] - near_v[j_near]) / (near_u[j_near + 1] - near_u[j_near])
    slope_far = (far_v[j_far + 1] - far_v[j_far]) / (far_u[j_far + 1] - far_u[j_far])
    # The turn in the frame where it lies at the top: v (and the chains' slopes) flipped.
    flip = 1.0 if top else -1.0
    slot = -1
    for c in range(len(cache_keys) // 5):
        k = 5 * c
        if (
            cache_keys[k] == shape
            and cache_keys[k + 1] == (1 if mirror_u > 0.0 else 0)
            and cache_keys[k + 2] == (1 if top else 0)
            and cache_keys[k + 3] == j_near
            and cache_keys[k + 4] == j_far
        ):
            slot = c
            break
    if slot < 0:
        # Highest point above the near chain's line, and lowest above the far chain's.
        above_near = -math.inf
        above_far = math.inf
        for i in range(start, stop):
            du = mirror_u * table_u[i]
            above_near = max(above_near, table_v[i] - flip * slope_near * du)
            above_far = min(above_far, table_v[i] - flip * slope_far * du)
        slot = _free_slot(cache_keys)
        k = 5 * slot
        cache_keys[k], cache_keys[k + 1] = shape, (1 if mirror_u > 0.0 else 0)
        cache_keys[k + 2], cache_keys[k + 3], cache_keys[k + 4] = (1 if top else 0), j_near, j_far
        cache_values[2 * slot], cache_values[2 * slot + 1] = above_near, above_far
    above_near, above_far = cache_values[2 * slot], cache_values[2 * slot + 1]
    near_at = near_v[j_near] + slope_near * (u0 - near_u[j_near])
    far_at = far_v[j_far] + slope_far * (u0 - far_u[j_far])
    delta = max(0.0, flip * (v0 - near_at) + above_near)
    # Slid back by delta, its lowest point must stay above the far chain.
    fits = flip * (v0 - far_at) + above_far - delta >= -_TOLERANCE_M
    return delta, fits


@_jit_counted_by_caller
def _free_slot(cache_keys: IntArray) -> int:
    """Return an empty slot of the cache, else the first (its keys are then overwritten)."""
    for c in range(len(cache_keys) // 5):
        if cache_keys[5 * c] < 0:
            return c
    return 0


@_jit_counted_by_caller
def _turn(
    cell: _Cell,
    u_from: float,
    v_from: float,
    u_to: float,
    v_to: float,
    top: bool,
    table: tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray],
    beyond_m: FloatArray,
    scalars: FloatArray,
    cache_keys: IntArray,
    cache_values: FloatArray,
) -> tuple[float, float, bool]:
    """Fit the turn from a line's end ``(u_from, v_from)`` to the next's start ``(u_to, v_to)``.

    Returns how far the first line's end and the second line's start are pulled back [m],
    and whether it fits (:func:`planner.line_ends._fit_turns`).
    """
    step, reach, spacing_m, classes = scalars[0], scalars[1], scalars[2], scalars[3]
    radius, back_m, retry = scalars[4], scalars[5], scalars[6]
    per_class = round(2.0 * reach / step) + 1
    spacing = abs(u_to - u_from)
    c = round(spacing / spacing_m * classes)
    c = min(max(c, 1), int(classes)) - 1
    mirror_u = 1.0 if u_to >= u_from else -1.0
    offset = v_to - v_from if top else v_from - v_to
    s, v0 = _tabled(offset, v_from, top, c, per_class, step, reach)
    delta, fits = _placed(cell, u_from, v0, mirror_u, top, s, table, cache_keys, cache_values)
    if not fits:
        delta = 0.0 if delta == math.inf else delta
    pull_end = pull_start = delta
    # planner.lopsided_turns: an Ω that does not fit, or slides far, with one end further back.
    if spacing < 2.0 * radius and (not fits or delta > beyond_m[s] + retry * radius):
        level_loss = 2.0 * delta if fits else math.inf
        best_loss = math.inf
        inward = -1.0 if top else 1.0
        for side in range(2):
            back_end = back_m if side == 0 else 0.0
            s2, v0 = _tabled(
                offset + (back_m if side == 0 else -back_m),
                v_from + inward * back_end, top, c, per_class, step, reach,
            )  # fmt: skip
            d2, f2 = _placed(cell, u_from, v0, mirror_u, top, s2, table, cache_keys, cache_values)
            loss = 2.0 * d2 + back_m if f2 else math.inf
            if loss < best_loss:
                best_loss = loss
                if loss < level_loss - 1e-9:
                    pull_end = d2 + back_m if side == 0 else d2
                    pull_start = d2 if side == 0 else d2 + back_m
                    fits = True
    return pull_end, pull_start, fits


@_jit_counted_by_caller
def _tabled(
    offset: float,
    v_from: float,
    top: bool,
    spacing_class: int,
    per_class: int,
    step: float,
    reach: float,
) -> tuple[int, float]:
    """Return the table's turn for an end ``offset`` [m] along the lines, and its start [m].

    Beyond the table the turn is its last one moved along the lines: the rest is a straight
    along one of the two lines (a Dubins CSC), which runs inside the cell.
    """
    k = round((offset + reach) / step)
    lift = 0.0
    if k >= per_class:
        k = per_class - 1
        lift = offset - reach
    k = max(k, 0)
    return spacing_class * per_class + k, v_from + lift if top else v_from - lift


@_jit_counted_by_caller
def _fit_cell(
    chains: FloatArray,
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    first_up: bool,
    table: tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray],
    beyond_m: FloatArray,
    scalars: FloatArray,
    cache_keys: IntArray,
    cache_values: FloatArray,
    work: FloatArray,
    flags: npt.NDArray[np.bool_],
    d: float,
) -> float:
    """Fit one cell's lines (left to right) driven back and forth, the first up if ``first_up``.

    Returns the area the fit takes off what the lines cover unfitted, footprints ``d`` wide
    [m²]: the ends pulled back (:func:`_end_loss_m2`), the lines dropped whole
    (:func:`_line_m2`; lines drop from the sides, as :func:`planner.line_ends.fit_lines`
    drops them in its first rounds). ``work`` (8 rows) and ``flags`` (3 rows) are scratch,
    a column a line.
    """
    n = len(u)
    n_lo, n_hi = int(chains[0]), int(chains[1])
    lo_u, lo_v = chains[2 : 2 + n_lo], chains[2 + n_lo : 2 + 2 * n_lo]
    hi_u = chains[2 + 2 * n_lo : 2 + 2 * n_lo + n_hi]
    hi_v = chains[2 + 2 * n_lo + n_hi :]
    u_min = hi_u[0] if hi_u[0] < lo_u[0] else lo_u[0]  # Chains.u_min and u_max
    u_max = hi_u[-1] if hi_u[-1] > lo_u[-1] else lo_u[-1]
    cell = (lo_u, lo_v, hi_u, hi_v, u_min, u_max)
    start, end = work[2], work[3]
    pull_end, pull_start, a, b = work[4], work[5], work[6], work[7]
    up, fits, drop = flags[0], flags[1], flags[2]
    for i in range(n):
        up[i] = (i % 2 == 0) == first_up
        start[i] = v_lo[i] if up[i] else v_hi[i]
        end[i] = v_hi[i] if up[i] else v_lo[i]
    # A turn depends on its two line ends as scanned: the rounds only drop lines.
    cache_keys[:] = -1
    for t in range(n - 1):
        pull_end[t], pull_start[t], fits[t] = _turn(
            cell, u[t], end[t], u[t + 1], start[t + 1], up[t],
            table, beyond_m, scalars, cache_keys, cache_values,
        )  # fmt: skip
    first, last = 0, n - 1
    for _ in range(_SIDE_ROUNDS):
        for i in range(first, last + 1):
            a[i], b[i] = start[i], end[i]
        for t in range(first, last):
            inward = -1.0 if up[t] else 1.0
            b[t] += inward * pull_end[t]
            a[t + 1] += inward * pull_start[t]
        if last == first:
            break
        any_drop = False
        for i in range(first, last + 1):
            drop[i] = (b[i] - a[i] if up[i] else a[i] - b[i]) < 0.0
        # A side line whose one turn pulls its neighbour back further than it runs.
        if pull_start[first] > abs(b[first] - a[first]):
            drop[first] = True
        if pull_end[last - 1] > abs(b[last] - a[last]):
            drop[last] = True
        for t in range(first, last):
            if not fits[t]:
                inset_t = min(u[t] - u_min, u_max - u[t])
                inset_next = min(u[t + 1] - u_min, u_max - u[t + 1])
                drop[t if inset_t <= inset_next else t + 1] = True
        every = True
        for i in range(first, last + 1):
            every = every and drop[i]
        if every:  # one line needs no turn: the longest stays
            longest = first
            for i in range(first, last + 1):
                if abs(end[i] - start[i]) > abs(end[longest] - start[longest]):
                    longest = i
            drop[longest] = False
        for i in range(first, last + 1):
            any_drop = any_drop or drop[i]
        if not any_drop:
            break
        middle = _middle(u, first, last)
        left = right = False
        for i in range(first, last + 1):
            if drop[i]:
                left = left or u[i] <= middle
                right = right or u[i] > middle
        first += 1 if left else 0
        last -= 1 if right and last >= first else 0
        if last < first:
            break
    # Each line's fitted span (its ends pulled back; dropped: empty), into start and end.
    for i in range(n):
        kept = first <= i <= last
        start[i] = min(a[i], b[i]) if kept else math.inf
        end[i] = max(a[i], b[i]) if kept else -math.inf
    # Footprints are strips a line wide; the last two overlap where the last line lies
    # closer (planner.lines.scan_cells): there the two spans are taken together.
    overlap = n >= 2 and u[n - 1] - u[n - 2] < d
    loss_m2 = 0.0
    for i in range(n):
        x0, x1 = max(u[i] - d / 2.0, u_min), min(u[i] + d / 2.0, u_max)
        if overlap and i == n - 2:
            x1 = min(x1, u[n - 1] - d / 2.0)
        if overlap and i == n - 1:
            x0 = max(x0, u[n - 2] + d / 2.0)
        loss_m2 += _span_loss_m2(x0, x1, v_lo[i], v_hi[i], start[i], end[i], cell)
    if overlap:
        x0 = max(u[n - 1] - d / 2.0, u_min)
        x1 = min(u[n - 2] + d / 2.0, u_max)
        loss_m2 += _span_loss_m2(
            x0, x1, min(v_lo[n - 2], v_lo[n - 1]), max(v_hi[n - 2], v_hi[n - 1]),
            min(start[n - 2], start[n - 1]), max(end[n - 2], end[n - 1]), cell,
        )  # fmt: skip
    return loss_m2


@_jit_counted_by_caller
def _span_loss_m2(
    x0: float, x1: float, v_lo: float, v_hi: float, fitted_lo: float, fitted_hi: float,
    cell: _Cell,
) -> float:  # fmt: skip
    """Area of ``cell`` a footprint over ``x0..x1`` loses from ``v_lo..v_hi`` to its fitted span.

    An empty fitted span (``fitted_lo > fitted_hi``) loses all it covered; otherwise the two
    ends' losses lie apart, within what it covered.
    """
    if fitted_lo > fitted_hi:
        return _line_m2(x0, x1, v_lo, v_hi, cell)
    lo_u, lo_v, hi_u, hi_v, _, _ = cell
    top = max(v_hi - fitted_hi, 0.0)
    bottom = max(fitted_lo - v_lo, 0.0)
    lost_m2 = _under_chain_m2(hi_u, hi_v, x0, x1, v_hi - top, top, 1.0)
    return lost_m2 + _under_chain_m2(lo_u, lo_v, x0, x1, v_lo + bottom, bottom, -1.0)


@_jit_counted_by_caller
def _line_m2(x0: float, x1: float, v_lo: float, v_hi: float, cell: _Cell) -> float:
    """Area of ``cell`` a line's footprint (strip ``x0..x1``, flat ends) covers [m²]."""
    lo_u, lo_v, hi_u, hi_v, _, _ = cell
    length = v_hi - v_lo
    if length <= 0.0 or x1 <= x0:
        return 0.0
    beyond_top = _under_chain_m2(hi_u, hi_v, x0, x1, v_hi, length, -1.0)
    beyond_bottom = _under_chain_m2(lo_u, lo_v, x0, x1, v_lo, length, 1.0)
    return max((x1 - x0) * length - beyond_top - beyond_bottom, 0.0)


@_jit_counted_by_caller
def _under_chain_m2(
    chain_u: FloatArray, chain_v: FloatArray, x0: float, x1: float, base: float, cap: float,
    sign: float,
) -> float:  # fmt: skip
    """Integral over ``x0..x1`` of ``sign * (chain - base)``, clipped to ``0..cap`` [m²].

    The chain is level beyond its ends (``np.interp``); the integral is exact piece by piece.
    """
    n = len(chain_u)
    if x1 <= x0 or cap <= 0.0:
        return 0.0
    total = 0.0
    xa = x0
    j = _right(chain_u, 0, n, x0) - 1  # the piece at x0 (-1: before the chain)
    while xa < x1:
        if j < 0:
            xb = min(x1, chain_u[0])
            ga = gb = sign * (chain_v[0] - base)
        elif j >= n - 1:
            xb = x1
            ga = gb = sign * (chain_v[n - 1] - base)
        else:
            xb = min(x1, chain_u[j + 1])
            span = chain_u[j + 1] - chain_u[j]
            slope = (chain_v[j + 1] - chain_v[j]) / span if span > 0.0 else 0.0
            ga = sign * (chain_v[j] + (xa - chain_u[j]) * slope - base)
            gb = sign * (chain_v[j] + (xb - chain_u[j]) * slope - base)
        total += _clipped_linear_m2(ga, gb, xb - xa, cap)
        xa = xb
        j += 1
    return total


@_jit_counted_by_caller
def _clipped_linear_m2(ga: float, gb: float, width: float, cap: float) -> float:
    """Integral over ``width`` of a linear function from ``ga`` to ``gb``, clipped to 0..cap."""
    if width <= 0.0:
        return 0.0
    if ga == gb:
        return width * min(max(ga, 0.0), cap)
    return width * (_clipped_antiderivative(gb, cap) - _clipped_antiderivative(ga, cap)) / (gb - ga)


@_jit_counted_by_caller
def _clipped_antiderivative(g: float, cap: float) -> float:
    """Integral from 0 to ``g`` of ``clip(s, 0, cap)`` ds."""
    if g <= 0.0:
        return 0.0
    if g <= cap:
        return g * g / 2.0
    return cap * cap / 2.0 + cap * (g - cap)


@_jit_counted_by_caller
def _middle(u: FloatArray, first: int, last: int) -> float:
    """Median of ``u[first:last + 1]``, sorted ascending (planner.line_ends._median)."""
    m = last - first + 1
    half = m // 2
    if m % 2:
        return float(u[first + half])
    return float((u[first + half - 1] + u[first + half]) / 2.0)
