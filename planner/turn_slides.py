"""Turns slid back along their lines until they fit the machine area.

:func:`planner.line_ends.fit_lines` slides every turn back until the whole driven curve lies
inside the machine area (:func:`slide_turns`), and :mod:`planner.lopsided_turns` slides its
lopsided Ωs the same way. A compiled kernel (:func:`planner.fit_kernels.fit_turns`) does the
work; its numpy reference (:mod:`planner.line_end_references`) fits the machine areas the
kernel declines.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from planner.coverage import Chains, packed
from planner.line_end_references import fitted_numpy
from planner.turns import TurnCurves, turn_range

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


def slide_turns(
    curves: TurnCurves, top: BoolArray, machine: Chains, *, tolerance_m: float
) -> tuple[TurnCurves, FloatArray, BoolArray]:
    """Slide each turn back along ``v`` until it fits the machine area.

    ``top``: whether each turn is at the upper chain; ``tolerance_m``: how far outside the
    area a point still counts as inside [m].

    Returns
    -------
    curves : TurnCurves
        The turns moved by their shifts.
    shift : ndarray
        Each turn's move along ``v`` (down at the top, up at the bottom) [m].
    fits : ndarray of bool
        Whether it fits at all.
    """
    from planner import fit_kernels  # numba: imported by the first plan that needs it

    fast = fit_kernels.fit_turns(
        curves.xy,
        curves.offsets,
        top,
        machine.lo_u,
        machine.lo_v,
        machine.hi_u,
        machine.hi_v,
        tolerance_m,
    )
    if fast is None:
        return fitted_numpy(curves, top, machine, tolerance_m=tolerance_m)
    shift, fits, xy = fast
    fitted = TurnCurves(xy, curves.offsets, curves.length_m, curves.turn_rad, curves.radius_m)
    return fitted, shift, fits


def slide_turn_groups(
    curves: TurnCurves,
    top: BoolArray,
    turn_at: IntArray,
    machines: Sequence[Chains],
    *,
    tolerance_m: float,
) -> tuple[TurnCurves, FloatArray, BoolArray]:
    """:func:`slide_turns` of many groups of turns, each on its own machine area, at once.

    Group ``g`` is the turns ``turn_at[g]:turn_at[g + 1]`` of ``curves``, slid on
    ``machines[g]``; each group's figures are those :func:`slide_turns` gives it alone, to
    the last bit (one compiled call for all: a cell has a few turns, and sliding them cell by
    cell was mostly call overhead).
    """
    from planner import fit_kernels  # numba: imported by the first plan that needs it

    areas = [_packed(m) for m in machines]
    chain_at = np.zeros(len(areas) + 1, dtype=np.int64)
    np.cumsum([len(a) for a in areas], out=chain_at[1:])
    chains = np.concatenate(areas) if areas else np.zeros(0)
    shift, fits, xy, done = fit_kernels.fit_turn_groups(
        curves.xy, curves.offsets, top, turn_at, chains, chain_at, tolerance_m
    )
    for g in np.flatnonzero(~done).tolist():
        t0, t1 = int(turn_at[g]), int(turn_at[g + 1])
        p0, p1 = int(curves.offsets[t0]), int(curves.offsets[t1])
        group = turn_range(curves, t0, t1)
        moved, shift[t0:t1], fits[t0:t1] = fitted_numpy(
            group, top[t0:t1], machines[g], tolerance_m=tolerance_m
        )
        xy[p0:p1] = moved.xy
    fitted = TurnCurves(xy, curves.offsets, curves.length_m, curves.turn_rad, curves.radius_m)
    return fitted, shift, fits


def _packed(machine: Chains) -> FloatArray:
    """Return ``machine`` packed as :func:`slide_turn_groups`' kernel reads it.

    ``[n_lo, n_hi, lo_u, lo_v, hi_u, hi_v]``; ``[0, 0]`` for chains the kernel must not read
    (empty, or ``u`` and ``v`` of other lengths).
    """
    m = machine
    if not (0 < len(m.lo_u) == len(m.lo_v) and 0 < len(m.hi_u) == len(m.hi_v)):
        return np.zeros(2)
    return packed(m)
