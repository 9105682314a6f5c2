"""``planner.decomposition.decompose_sweep`` of one part at one heading, compiled whole.

:mod:`planner.cell_kernels` compiles the sweep that cuts a part into cells, and leaves its glue
(the rotation into the sweep frame, the critical cuts, the cells' area filter) to numpy. To
decompose a part at every candidate heading in one compiled loop
(:mod:`planner.screen_kernels`), that glue is compiled here with the numpy code's arithmetic:
the rotation (``to_sweep``'s products, with the caller's cosines), the cuts
(``decomposition._cuts``: ``np.unique`` and the snap) and the cells' size and area filter
(``decomposition._rings``, whose ``np.add.reduceat`` adds by numpy's pairwise rule,
:func:`planner.kernel_helpers._pairwise_sum`). So the cells are ``decompose_sweep``'s to the
last bit (but the sign of a zero, as in :mod:`planner.cell_kernels`), where it decomposes in
the sweep; where it leaves the cells to numpy or shapely, :func:`_part_cells` says so.
``tests/planner/test_decomposition_kernels.py`` holds each twin equal to its numpy original;
``tests/planner/test_heading_screen.py`` the whole against ``cover_heading``.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.cell_kernels import _sweep_cells
from planner.kernel_helpers import _jit, _pairwise_sum

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

_SNAP_M = 1e-6  # planner.decomposition._SNAP_M
_MIN_CELL_M2 = 1e-6  # planner.decomposition._MIN_CELL_M2


@_jit
def _cuts(critical_u: FloatArray) -> FloatArray:
    """``planner.decomposition._cuts``: sorted, snapped ``u`` of the critical vertices (no NaN).

    Sorts ``critical_u`` in place and returns a view of it.
    """
    cuts = critical_u
    cuts.sort()
    m = 0
    for i in range(len(cuts)):  # np.unique
        if m == 0 or cuts[i] != cuts[m - 1]:
            cuts[m] = cuts[i]
            m += 1
    keep = np.empty(m, dtype=np.bool_)
    for i in range(m):
        keep[i] = i == 0 or i == m - 1 or cuts[i] - cuts[i - 1] > _SNAP_M
    kept = 0
    for i in range(m):
        if keep[i]:
            cuts[kept] = cuts[i]
            kept += 1
    if kept >= 2 and cuts[kept - 1] - cuts[kept - 2] <= _SNAP_M:
        cuts[kept - 2] = cuts[kept - 1]
        kept -= 1
    return cuts[:kept]


@_jit
def _rings(
    u: FloatArray, v: FloatArray, sizes: IntArray
) -> tuple[FloatArray, FloatArray, IntArray]:
    """``planner.decomposition._rings`` laid end to end: the rings of ≥ 3 vertices and area."""
    out_u, out_v = np.empty(len(u)), np.empty(len(u))
    out_sizes = np.empty(len(sizes), dtype=np.int64)
    twice = np.empty(len(u))
    n_out = w = 0
    start = 0
    for r in range(len(sizes)):
        size = sizes[r]
        if size >= 3:
            for i in range(size):
                j = start + (i + 1 if i + 1 < size else 0)
                twice[i] = u[start + i] * v[j] - v[start + i] * u[j]
            # np.add.reduceat: the segment's first value, then numpy's sum of the rest.
            if (twice[0] + _pairwise_sum(twice, 1, size - 1)) / 2.0 > _MIN_CELL_M2:
                for i in range(start, start + size):
                    out_u[w], out_v[w] = u[i], v[i]
                    w += 1
                out_sizes[n_out] = size
                n_out += 1
        start += size
    return out_u[:w], out_v[:w], out_sizes[:n_out]


@_jit
def _part_cells(
    x: FloatArray,
    y: FloatArray,
    sizes: IntArray,
    first: IntArray,
    ring_of: IntArray,
    local: IntArray,
    nxt: IntArray,
    prv: IntArray,
    cos_t: float,
    sin_t: float,
) -> tuple[bool, FloatArray, FloatArray, IntArray]:
    """``planner.decomposition.decompose_sweep`` of one part, its rings laid end to end.

    Returns False (and empty arrays) where that function leaves the cells to numpy or shapely.
    """
    n = len(x)
    u, v = np.empty(n), np.empty(n)
    for i in range(n):  # planner.lines.to_sweep
        u[i] = x[i] * cos_t - y[i] * sin_t
        v[i] = x[i] * sin_t + y[i] * cos_t
    turn = np.empty(n, dtype=np.bool_)
    n_turn = 0
    for i in range(n):
        turn[i] = (u[i] - u[prv[i]]) * (u[nxt[i]] - u[i]) <= 0.0
        n_turn += turn[i]
    critical = np.empty(n_turn)
    k = 0
    for i in range(n):
        if turn[i]:
            critical[k] = u[i]
            k += 1
    cuts = _cuts(critical)
    if len(cuts) <= 2:
        outer = sizes[0]
        return True, u[:outer].copy(), v[:outer].copy(), sizes[:1].copy()
    status, cell_u, cell_v, cell_sizes = _sweep_cells(
        u, v, turn, cuts, sizes, first, ring_of, local, nxt, prv
    )
    if status != 1:
        return False, u[:0], v[:0], sizes[:0]
    ring_u, ring_v, ring_sizes = _rings(cell_u, cell_v, cell_sizes)
    return True, ring_u, ring_v, ring_sizes


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on an L (one cut, 3 cells)."""
    from shapely import Polygon

    from planner.decomposition import sweep_rings

    r = sweep_rings(Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)]))
    cos_t, sin_t = np.cos(np.radians(135.0)), np.sin(np.radians(135.0))
    sizes, first = r.sizes.astype(np.int64), r.first.astype(np.int64)
    ring_of, local = r.ring_of.astype(np.int64), r.local.astype(np.int64)
    nxt, prv = r.nxt.astype(np.int64), r.prv.astype(np.int64)
    _part_cells(r.x, r.y, sizes, first, ring_of, local, nxt, prv, float(cos_t), float(sin_t))
