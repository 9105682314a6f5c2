"""The Ω tried lopsided where sliding it back level costs too much.

:func:`planner.line_ends.fit_lines` slides every turn back along its two lines until it fits
the machine area (:func:`planner.turn_slides.slide_turns`). An Ω, the turn between lines
closer than two turning radii, swings out beyond *both* lines by ``radius - spacing / 2``;
beside a boundary nearly parallel to the lines, or a step of it, that bulge makes the level Ω
slide down the boundary for tens of metres, and both lines lose it (a 4 m interval with a 3 m
radius: 1 m each side). With one of its two ends further back, the Ω's loop leans towards
that line and no longer swings out beyond the other (:func:`lopsided_turns`). Each variant is
the vehicle's own turn slid until it fits, as every turn is, so the body stays in (R1) and
the curvature bound holds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from planner.coverage import Chains
from planner.turn_slides import slide_turn_groups, slide_turns
from planner.turns import TurnCurves, TurnEnds, vehicle_turns
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: A bulging turn slid back this many turning radii beyond its own reach past the line ends
#: (or not fitting at all) is tried lopsided ...
RETRY_RADII = 2.0
#: ... with one of its two line ends further back by these many turning radii. One pull-back
#: on each side; (2, 4, 6) gained 0.3 pp more on the real fields at 4 m with the small
#: tractor but cost half a second of their 4 s (6 variants per turn tried instead of 2).
LOPSIDED_RADII = (4.0,)


class LopsidedPairs(NamedTuple):
    """Lines in driving order (sweep frame [m]) and the pairs joined by the turns tried."""

    u: FloatArray
    up: BoolArray  # whether each line runs towards +v
    v_end: FloatArray
    v_start: FloatArray
    first: IntArray  # the line each turn leaves ...
    second: IntArray  # ... and the one it joins


def pair_ends(
    u: FloatArray,
    up: BoolArray,
    v_end: FloatArray,
    v_start: FloatArray,
    first: IntArray,
    second: IntArray,
    back_end_m: FloatArray | float = 0.0,
    back_start_m: FloatArray | float = 0.0,
) -> TurnEnds:
    """Return the ends of the turns from line ``first`` to ``second``, pulled back as given [m].

    ``back_end_m`` moves the end of line ``first`` and ``back_start_m`` the start of ``second``
    back along their lines (down at the top, up at the bottom).
    """
    inward = np.where(up[first], -1.0, 1.0)
    yaw = np.where(up, math.pi / 2.0, -math.pi / 2.0)
    return TurnEnds(
        u[first],
        v_end[first] + inward * back_end_m,
        yaw[first],
        u[second],
        v_start[second] + inward * back_start_m,
        yaw[second],
    )


def tried_lopsided(
    curves: TurnCurves, top: BoolArray, spacing_m: FloatArray, shift: FloatArray, fits: BoolArray
) -> BoolArray:
    """Which turns to try lopsided: Ωs that do not fit, or slid well beyond their own reach.

    ``curves`` as planned (before sliding), ``spacing_m`` the distance between each turn's
    two lines, ``shift`` and ``fits`` as :func:`slide_turns` gave them.
    """
    radius = curves.radius_m
    v = curves.xy[:, 1]
    starts, lasts = curves.offsets[:-1], curves.offsets[1:] - 1
    if len(starts) == 0:
        return np.zeros(0, dtype=bool)
    # How far each turn runs beyond the farther of its two ends, away from the lines.
    beyond = np.where(
        top,
        np.maximum.reduceat(v, starts) - np.maximum(v[starts], v[lasts]),
        np.minimum(v[starts], v[lasts]) - np.minimum.reduceat(v, starts),
    )
    bulging = spacing_m < 2.0 * radius
    return np.asarray(bulging & (~fits | (np.abs(shift) > beyond + RETRY_RADII * radius)))


def lopsided_turns(
    pairs: LopsidedPairs,
    machine: Chains,
    vehicle: Vehicle,
    level: tuple[TurnCurves, FloatArray, BoolArray],
    tried: BoolArray,
    *,
    tolerance_m: float,
    planned: TurnCurves | None = None,
) -> tuple[TurnCurves, FloatArray, FloatArray, BoolArray]:
    """Try the ``tried`` turns with one line end further back; keep what loses least.

    ``level``: the turns as :func:`slide_turns` fitted them. Each tried turn is planned
    again with the end of its first line, or the start of its second, further back by each
    of :data:`LOPSIDED_RADII`, and slid until it fits; the one that pulls its two line ends
    back least in total replaces the level turn, if it pulls them back less (or the level
    turn does not fit).

    ``planned``: the variants' turns as :func:`lopsided_ends` gives their ends, if they are
    planned already (many headings at once: :func:`planner.line_ends.fit_line_turns`).

    Returns
    -------
    curves : TurnCurves
        The turns, fitted.
    shift_end_m, shift_start_m : ndarray
        How far the first line's end and the second line's start move along ``v`` [m].
    fits : ndarray of bool
    """
    t = np.nonzero(tried)[0]
    k, back_end_m, back_start_m = _variants(t, level[0].radius_m)
    if planned is None:
        planned = vehicle_turns(lopsided_ends(pairs, level[0].radius_m, tried), vehicle)
    top = pairs.up[pairs.first[k]]
    slid = slide_turns(planned, top, machine, tolerance_m=tolerance_m)
    return _least_loss(level, t, back_end_m, back_start_m, top, slid)


def lopsided_turn_groups(
    pairs: LopsidedPairs,
    machines: Sequence[Chains],
    turn_at: IntArray,
    vehicle: Vehicle,
    level: tuple[TurnCurves, FloatArray, BoolArray],
    tried: BoolArray,
    *,
    tolerance_m: float,
) -> tuple[TurnCurves, FloatArray, FloatArray, BoolArray]:
    """:func:`lopsided_turns` of many groups of turns, each on its own machine area, at once.

    Group ``g`` is the turns ``turn_at[g]:turn_at[g + 1]`` (``pairs.first`` and ``second``
    index lines of all groups laid end to end), fitted on ``machines[g]``; each group's
    turns are those :func:`lopsided_turns` gives it alone, to the last bit.
    """
    t = np.nonzero(tried)[0]
    k, back_end_m, back_start_m = _variants(t, level[0].radius_m)
    planned = vehicle_turns(lopsided_ends(pairs, level[0].radius_m, tried), vehicle)
    top = pairs.up[pairs.first[k]]
    variant_at = np.searchsorted(k, turn_at)
    slid = slide_turn_groups(planned, top, variant_at, machines, tolerance_m=tolerance_m)
    return _least_loss(level, t, back_end_m, back_start_m, top, slid)


def _least_loss(
    level: tuple[TurnCurves, FloatArray, BoolArray],
    t: IntArray,
    back_end_m: FloatArray,
    back_start_m: FloatArray,
    top: BoolArray,
    slid: tuple[TurnCurves, FloatArray, BoolArray],
) -> tuple[TurnCurves, FloatArray, FloatArray, BoolArray]:
    """Replace each level turn ``t`` by its variant that pulls its ends back least, if less.

    ``slid``: every variant (:func:`_variants` of ``t``) slid until it fits; ``top``: each
    variant's side. Returns :func:`lopsided_turns`' figures.
    """
    fitted, shift, fits = level
    moved, v_shift, v_fits = slid
    m = 2 * len(LOPSIDED_RADII)
    loss = np.where(v_fits, 2.0 * np.abs(v_shift) + back_end_m + back_start_m, np.inf)
    best = np.argmin(loss.reshape(len(t), m), axis=1) + np.arange(len(t)) * m
    better = loss[best] < np.where(fits[t], 2.0 * np.abs(shift[t]), np.inf) - 1e-9
    shift_end_m, shift_start_m = shift.copy(), shift.copy()
    if not better.any():
        return fitted, shift_end_m, shift_start_m, fits
    t, best = t[better], best[better]
    inward = np.where(top[best], -1.0, 1.0)
    shift_end_m[t] = v_shift[best] + inward * back_end_m[best]
    shift_start_m[t] = v_shift[best] + inward * back_start_m[best]
    fits = fits.copy()
    fits[t] = True
    return _replaced(fitted, moved, t, best), shift_end_m, shift_start_m, fits


def _replaced(fitted: TurnCurves, moved: TurnCurves, t: IntArray, best: IntArray) -> TurnCurves:
    """Return ``fitted`` with turns ``t`` replaced by the variants ``best`` of ``moved``.

    One gather of the points (``take_turns`` of the variants, appended, then of the whole
    made two copies and a concatenation of every point).
    """
    n = len(fitted)
    sizes = fitted.point_counts()
    starts = fitted.offsets[:-1].copy()
    sizes[t] = moved.point_counts()[best]
    starts[t] = moved.offsets[best] + len(fitted.xy)
    offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    point = np.repeat(starts - offsets[:-1], sizes) + np.arange(offsets[-1])
    length_m, turn_rad = fitted.length_m.copy(), fitted.turn_rad.copy()
    length_m[t], turn_rad[t] = moved.length_m[best], moved.turn_rad[best]
    xy = np.concatenate([fitted.xy, moved.xy])[point]
    return TurnCurves(xy, offsets, length_m, turn_rad, fitted.radius_m)


def lopsided_ends(pairs: LopsidedPairs, radius_m: float, tried: BoolArray) -> TurnEnds:
    """Return the ends of every variant :func:`lopsided_turns` plans for the ``tried`` turns."""
    k, back_end_m, back_start_m = _variants(np.nonzero(tried)[0], radius_m)
    return pair_ends(
        pairs.u,
        pairs.up,
        pairs.v_end,
        pairs.v_start,
        pairs.first[k],
        pairs.second[k],
        back_end_m,
        back_start_m,
    )


def _variants(t: IntArray, radius_m: float) -> tuple[IntArray, FloatArray, FloatArray]:
    """Each variant's turn of ``t`` and how far it pulls the two line ends back [m]."""
    backs_m = np.array(LOPSIDED_RADII) * radius_m
    m = len(backs_m)
    # Variants turn by turn: the first line's end pulled back by each, then the second's start.
    k = np.repeat(t, 2 * m)
    # np.tile's values, written into zeros without its overhead (a few turns, at every
    # heading of a field).
    back_end_m = np.zeros((len(t), 2 * m))
    back_start_m = np.zeros((len(t), 2 * m))
    back_end_m[:, :m] = backs_m
    back_start_m[:, m:] = backs_m
    return k, back_end_m.reshape(-1), back_start_m.reshape(-1)
