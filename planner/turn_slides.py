"""Turns slid back along their lines until they fit the machine area.

:func:`planner.line_ends.fit_lines` slides every turn back until the whole driven curve lies
inside the machine area (:func:`slide_turns`), and :mod:`planner.lopsided_turns` slides its
lopsided Ωs the same way. A compiled kernel (:func:`planner.fit_kernels.fit_turns`) does the
work; its numpy reference (:mod:`planner.line_end_references`) fits the machine areas the
kernel declines.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.coverage import Chains
from planner.line_end_references import fitted_numpy
from planner.turns import TurnCurves

FloatArray = npt.NDArray[np.float64]
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
