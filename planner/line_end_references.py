"""The numpy reference of the turn-fitting kernel, and the fallback for what it declines.

:func:`planner.line_ends.fit_lines` slides every turn back along its lines until it fits the
machine area with a compiled kernel, :func:`planner.fit_kernels.fit_turns`. :func:`fitted_numpy`
computes the same in numpy, all turns at once. It is kept for two reasons: it is the oracle that
``tests/planner/test_fit_kernels.py`` holds the kernel to bit for bit, and it is the fallback
for the machine areas the kernel declines (it returns ``None`` for an empty chain, or one whose
``u`` steps back, where ``np.interp`` and ``searchsorted`` answer differently). It lives apart
from :mod:`planner.line_ends` so that the fitting reads on its own: :mod:`planner.turn_slides`
imports it, and it imports nothing of :mod:`planner.line_ends` (no import cycle).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.coverage import Chains
from planner.turns import TurnCurves

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


def fitted_numpy(
    curves: TurnCurves, top: BoolArray, machine: Chains, *, tolerance_m: float
) -> tuple[TurnCurves, FloatArray, BoolArray]:
    """:func:`planner.line_ends._fit_turns`' sliding of turns in numpy: the kernel's reference.

    ``top``: whether each turn is at the top (the upper chain's side); ``tolerance_m``: how
    far outside the machine area a point still counts as inside [m]
    (:data:`planner.line_ends.FIT_TOLERANCE_M`, as the kernel is given it).
    """
    # Array methods and slices rather than np.repeat/np.diff/…: the wrappers cost more than
    # the work on a few turns.
    owner = np.arange(len(top)).repeat(curves.point_counts())
    pu, pv = curves.xy[:, 0], curves.xy[:, 1]
    hi = np.interp(pu, machine.hi_u, machine.hi_v)
    lo = np.interp(pu, machine.lo_u, machine.lo_v)
    beyond = (pu < machine.u_min - tolerance_m) | (pu > machine.u_max + tolerance_m)
    top_point = top[owner]
    need = np.where(top_point, pv - hi, lo - pv)
    need = np.where(beyond, np.inf, need)
    delta = np.zeros(len(top))
    np.maximum.at(delta, owner, need)
    # A chain vertex between two points of a curve (a spike of the boundary) counts too.
    seg_turn, seg_need = _chain_vertices_under(pu, pv, owner, top, machine)
    np.maximum.at(delta, seg_turn, seg_need)
    reachable = np.isfinite(delta)
    delta = np.where(reachable, delta, 0.0)
    shift = np.where(top, -delta, delta)  # along v: down at the top, up at the bottom
    moved = pv + shift[owner]
    clash = np.where(top_point, lo - moved, moved - hi) > tolerance_m
    fits = reachable.copy()
    np.logical_and.at(fits, owner, ~clash)
    seg_turn, seg_need = _chain_vertices_under(pu, moved, owner, ~top, machine)
    np.logical_and.at(fits, seg_turn, seg_need <= tolerance_m)
    xy = np.empty((len(pu), 2))  # np.stack([pu, moved], axis=1), without stack's cost
    xy[:, 0], xy[:, 1] = pu, moved
    fitted = TurnCurves(xy, curves.offsets, curves.length_m, curves.turn_rad, curves.radius_m)
    return fitted, shift, fits


def _chain_vertices_under(
    pu: FloatArray, pv: FloatArray, owner: IntArray, top: BoolArray, machine: Chains
) -> tuple[IntArray, FloatArray]:
    """How far each curve passes beyond the chain vertices that lie between its points.

    For a turn at the top (``top[turn]``) the upper chain's vertices, else the lower's: at
    every chain vertex within the ``u``-span of a step of the curve, the curve's ``v`` there
    minus the vertex's (upper chain), or the reverse (lower chain).

    Returns
    -------
    turn : ndarray of int
        The turn of each such vertex crossing.
    need : ndarray
        How far beyond the chain the curve passes there [m] (negative: inside).
    """
    same = owner[1:] == owner[:-1]
    i = same.nonzero()[0]  # array methods, not the np.* wrappers (as in fitted_numpy)
    ua, ub, va, vb = pu[i], pu[i + 1], pv[i], pv[i + 1]
    turn = owner[i]
    at_top = top[turn]
    # Both chains in one sorted array: the lower chain's vertices shifted past every curve.
    shift = 4.0 * (float(np.abs(pu).max(initial=0.0)) + abs(machine.u_max) + abs(machine.u_min))
    shift += 1.0
    cu = np.concatenate([machine.hi_u, machine.lo_u + shift])
    cv = np.concatenate([machine.hi_v, machine.lo_v])
    offset = np.where(at_top, 0.0, shift)
    lo_u, hi_u = np.minimum(ua, ub) + offset, np.maximum(ua, ub) + offset
    first = cu.searchsorted(lo_u, side="right")
    stop = cu.searchsorted(hi_u, side="left")
    count = np.maximum(stop - first, 0)
    total = int(count.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    step = np.arange(len(count)).repeat(count)
    vertex = np.arange(total) - (count.cumsum() - count).repeat(count) + first[step]
    a_u, b_u = ua[step] + offset[step], ub[step] + offset[step]
    t = (cu[vertex] - a_u) / np.where(b_u != a_u, b_u - a_u, 1.0)
    curve_v = va[step] + t * (vb[step] - va[step])
    gap = np.where(at_top[step], curve_v - cv[vertex], cv[vertex] - curve_v)
    return turn[step], gap
