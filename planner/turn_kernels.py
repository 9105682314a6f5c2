"""One compiled call for a forward-only vehicle's turns: words, points and moves together.

:func:`planner.turns.vehicle_turns` plans a few turns per call, thousands of times a plan
(the lopsided Ωs of :mod:`planner.lopsided_turns` cell by cell): for a forward-only vehicle
its numpy steps (the Dubins words of the wide turns and the bulbs, their points, merging the
two and moving them onto their ends) cost more than the turns. :func:`planned_turns` is the
same computation in one compiled call: the same kernels
(:mod:`planner.fit_kernels`' ``_dubins``, ``_sample``) on the same values, turn by turn, so
every point is the same to the last bit (``tests/planner/test_turns.py`` compares them).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.fit_kernels import _dubins, _floats, _sample
from planner.kernel_helpers import _jit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: The signs of the six Dubins words' segments (:data:`planner.turns.DUBINS_WORDS`' order).
_SIGNS = np.array([[1, 0, 1], [-1, 0, -1], [1, 0, -1], [-1, 0, 1], [-1, 1, -1], [1, -1, 1]])


@_jit
def _planned(
    dx: FloatArray,
    dy: FloatArray,
    yaw0: FloatArray,
    yaw1: FloatArray,
    narrow: BoolArray,
    radius: float,
    arc_step: float,
    step: float,
    shape_of: IntArray,
    x0: FloatArray,
    y0: FloatArray,
    x1: FloatArray,
    y1: FloatArray,
    word_signs: IntArray,
) -> tuple[FloatArray, IntArray, IntArray, FloatArray, bool]:
    """Shapes from the origin (bulbs where ``narrow``), each moved onto its turns' ends.

    Returns the points and offsets of the turns, each shape's segment signs and signed
    lengths [m], and False if some shape has no word (nothing else is then meaningful).
    """
    n = len(dx)
    signs = np.zeros((n, 3), dtype=np.int64)
    lengths = np.zeros((n, 3))
    # The wide turns with all six words, the bulbs with RLR and LRL: as two calls would.
    for bulbs in (False, True):
        pick = np.nonzero(narrow == bulbs)[0]
        if len(pick) == 0:
            continue
        codes = np.array([4, 5]) if bulbs else np.arange(6)
        zero = np.zeros(len(pick))
        best = np.empty(len(pick), dtype=np.int64)
        params = np.empty((len(pick), 3))
        _dubins(zero, zero, yaw0[pick], dx[pick], dy[pick], yaw1[pick], radius, codes, best, params)
        for j in range(len(pick)):
            if best[j] < 0:
                return np.empty((0, 2)), np.zeros(1, dtype=np.int64), signs, lengths, False
            s = pick[j]
            for c in range(3):
                signs[s, c] = word_signs[codes[best[j]], c]
                lengths[s, c] = params[j, c] * radius
    zero = np.zeros(n)
    shape_xy, shape_offsets = _sample(
        zero, zero, yaw0, dx, dy, signs, lengths, radius, arc_step, step
    )
    m = len(shape_of)
    offsets = np.zeros(m + 1, dtype=np.int64)
    for k in range(m):
        s = shape_of[k]
        offsets[k + 1] = offsets[k] + shape_offsets[s + 1] - shape_offsets[s]
    xy = np.empty((offsets[m], 2))
    for k in range(m):
        s = shape_of[k]
        at = offsets[k]
        for i in range(shape_offsets[s], shape_offsets[s + 1]):
            xy[at, 0] = shape_xy[i, 0] + x0[k]
            xy[at, 1] = shape_xy[i, 1] + y0[k]
            at += 1
        first, last = offsets[k], offsets[k + 1] - 1
        xy[first, 0], xy[first, 1] = x0[k], y0[k]
        xy[last, 0], xy[last, 1] = x1[k], y1[k]
    return xy, offsets, signs, lengths, True


def planned_turns(
    dx: FloatArray,
    dy: FloatArray,
    yaw0: FloatArray,
    yaw1: FloatArray,
    narrow: BoolArray,
    radius_m: float,
    arc_step_m: float,
    step_m: float,
    shape_of: IntArray,
    ends: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
) -> tuple[FloatArray, IntArray, IntArray, FloatArray] | None:
    """Plan forward-only turns: points and offsets, each shape's signs and lengths [m].

    Shape ``s`` joins the origin, heading ``yaw0[s]``, to ``(dx, dy)[s]``, heading
    ``yaw1[s]``: the shortest Dubins word at ``radius_m``, of RLR and LRL only where
    ``narrow[s]``, sampled as :func:`planner.turns.dubins_turn` samples it. Turn ``k`` is
    shape ``shape_of[k]`` moved to start at ``ends``' ``(x0, y0)[k]`` and end exactly at
    ``(x1, y1)[k]``, as :func:`planner.turns.vehicle_turns` moves it. None if some shape
    has no word.
    """
    f = _floats
    x0, y0, x1, y1 = ends
    xy, offsets, signs, lengths, ok = _planned(
        f(dx),
        f(dy),
        f(yaw0),
        f(yaw1),
        np.ascontiguousarray(narrow, dtype=np.bool_),
        float(radius_m),
        float(arc_step_m),
        float(step_m),
        np.ascontiguousarray(shape_of, dtype=np.int64),
        f(x0),
        f(y0),
        f(x1),
        f(y1),
        _SIGNS,
    )
    return (xy, offsets, signs, lengths) if ok else None


def warm_up() -> None:
    """Compile the kernel, or load it from the disk cache, on one U-turn and one bulb."""
    up = np.full(2, np.pi / 2.0)
    planned_turns(
        np.array([8.0, 2.0]),
        np.zeros(2),
        up,
        -up,
        np.array([False, True]),
        3.0,
        0.5,
        0.5,
        np.array([0, 1, 1]),
        (np.zeros(3), np.zeros(3), np.ones(3), np.ones(3)),
    )
