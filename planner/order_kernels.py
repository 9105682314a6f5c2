"""Compiled searches for the order of a heading's cells, with the numpy code's arithmetic.

:mod:`planner.cell_order` orders a heading's cells (every order of a few cells, a local search
or the nearest cell next of many) and chooses each cell's variant (which end, which way) by a
Viterbi pass over the moves between them. In numpy that is a few calls per order on small
arrays; these kernels do the same searches in loops, compiled by numba, on the same float64
costs: every sum is taken in the same order, ``np.min`` keeps its NaN rule and ``np.argmin``
its first of equals, so the orders and variants, and so the plans, are the same to the last
bit. Every kernel takes one array type (C-contiguous, writable; :func:`_writable`), so
:func:`warm_up` compiles all that the plans call.

The numpy code stays the reference: ``tests/planner/test_cell_kernels.py`` compares the two
bit for bit on random problems and the real fields'. Like :mod:`planner.kernels`, the kernels
are cached on disk (``cache=True``) and compiled, or loaded, by :func:`warm_up`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.kernel_helpers import _jit, _mn

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@_jit
def _move(
    move: FloatArray, exits: FloatArray, entries: FloatArray, a: int, i: int, b: int, j: int
) -> float:
    """Return the move from the exit of ``(a, i)`` to the entry of ``(b, j)`` (``move``).

    Straight (``move`` empty) as ``planner.cell_order._StraightProblem`` computes it.
    """
    if move.shape[0] == 0:
        return float(np.hypot(exits[a, i, 0] - entries[b, j, 0], exits[a, i, 1] - entries[b, j, 1]))
    return float(move[a, i, b, j])


@_jit
def _order_costs(
    move: FloatArray,
    exits: FloatArray,
    entries: FloatArray,
    first: FloatArray,
    last: FloatArray,
    inner: FloatArray,
    orders: IntArray,
) -> FloatArray:
    """``planner.cell_order._Problem.costs``: the best variants' route length of each order."""
    k_orders, n = orders.shape
    out = np.empty(k_orders)
    here = np.empty(4)
    after = np.empty(4)
    for k in range(k_orders):
        c = orders[k, 0]
        for j in range(4):
            here[j] = first[c, j]
        for t in range(1, n):
            a, b = orders[k, t - 1], orders[k, t]
            for j in range(4):
                best = here[0] + _move(move, exits, entries, a, 0, b, j)
                for i in range(1, 4):
                    best = _mn(best, here[i] + _move(move, exits, entries, a, i, b, j))
                after[j] = best + inner[b, j]
            for j in range(4):
                here[j] = after[j]
        c = orders[k, n - 1]
        best = here[0] + last[c, 0]
        for j in range(1, 4):
            best = _mn(best, here[j] + last[c, j])
        out[k] = best
    return out


@_jit
def _order_variants(
    move: FloatArray,
    exits: FloatArray,
    entries: FloatArray,
    first: FloatArray,
    last: FloatArray,
    inner: FloatArray,
    order: IntArray,
) -> IntArray:
    """``planner.cell_order._Problem.variants``: Viterbi with back-pointers (``np.argmin``)."""
    n = len(order)
    back = np.empty((n, 4), dtype=np.int64)
    here = np.empty(4)
    after = np.empty(4)
    for j in range(4):
        here[j] = first[order[0], j]
    for t in range(1, n):
        a, b = order[t - 1], order[t]
        for j in range(4):
            best = here[0] + _move(move, exits, entries, a, 0, b, j)
            arg = 0
            for i in range(1, 4):
                x = here[i] + _move(move, exits, entries, a, i, b, j)
                if best == best and (x < best or x != x):
                    best, arg = x, i
            back[t, j] = arg
            after[j] = best + inner[b, j]
        for j in range(4):
            here[j] = after[j]
    chosen = np.empty(n, dtype=np.int64)
    c = order[n - 1]
    best = here[0] + last[c, 0]
    w = 0
    for j in range(1, 4):
        x = here[j] + last[c, j]
        if best == best and (x < best or x != x):
            best, w = x, j
    chosen[n - 1] = w
    for t in range(n - 1, 0, -1):
        w = back[t, w]
        chosen[t - 1] = w
    return chosen


@_jit
def _order_greedy(
    move: FloatArray, exits: FloatArray, entries: FloatArray, first: FloatArray, inner: FloatArray
) -> IntArray:
    """``planner.cell_order._Problem.greedy``: nearest cell next (``np.argmin``'s first)."""
    m = len(inner)
    current = 0
    best = np.inf
    for c in range(m):
        row_min = first[c, 0]
        for j in range(1, 4):
            row_min = _mn(row_min, first[c, j])
        if c == 0 or (best == best and (row_min < best or row_min != row_min)):
            best, current = row_min, c
    w_here = 0
    for j in range(1, 4):
        x = first[current, j]
        y = first[current, w_here]
        if y == y and (x < y or x != x):
            w_here = j
    order = np.empty(m, dtype=np.int64)
    order[0] = current
    visited = np.zeros(m, dtype=np.bool_)
    visited[current] = True
    for step in range(1, m):
        best = np.inf
        flat = -1
        for c in range(m):
            for j in range(4):
                x = (
                    np.inf
                    if visited[c]
                    else _move(move, exits, entries, current, w_here, c, j) + inner[c, j]
                )
                if flat < 0 or (best == best and (x < best or x != x)):
                    best, flat = x, c * 4 + j
        current, w_here = flat // 4, flat % 4
        order[step] = current
        visited[current] = True
    return order


def _writable(a: IntArray) -> IntArray:
    """Return ``a`` as int64, C-contiguous and writable: the type the kernels are compiled for.

    (A read-only array, such as the shared permutations, would compile another copy.)
    """
    return np.require(a, dtype=np.int64, requirements=["C", "W"])


def order_costs(
    move_m: FloatArray,
    exits: FloatArray,
    entries: FloatArray,
    first_m: FloatArray,
    last_m: FloatArray,
    inner_m: FloatArray,
    orders: IntArray,
) -> FloatArray:
    """Route length [m] of the best variants of each of ``orders`` (K, m), compiled.

    ``move_m`` is (m, 4, m, 4), or (0, 4, 0, 4) for straight moves from ``exits`` to
    ``entries`` (m, 4, 2) [m]; ``first_m``, ``last_m`` and ``inner_m`` are (m, 4); all float64
    and C-contiguous (:class:`planner.cell_order._Problem`), lengths and points in metres.
    """
    return _order_costs(move_m, exits, entries, first_m, last_m, inner_m, _writable(orders))


def order_variants(
    move_m: FloatArray,
    exits: FloatArray,
    entries: FloatArray,
    first_m: FloatArray,
    last_m: FloatArray,
    inner_m: FloatArray,
    order: IntArray,
) -> IntArray:
    """Choose the best variant of every cell of ``order``, compiled (:func:`order_costs`)."""
    return _order_variants(move_m, exits, entries, first_m, last_m, inner_m, _writable(order))


def order_greedy(
    move_m: FloatArray,
    exits: FloatArray,
    entries: FloatArray,
    first_m: FloatArray,
    inner_m: FloatArray,
) -> IntArray:
    """Nearest cell next, from the cell that begins best, compiled (:func:`order_costs`)."""
    return _order_greedy(move_m, exits, entries, first_m, inner_m)


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on a tiny problem."""
    move = np.ones((2, 4, 2, 4))
    xy = np.zeros((2, 4, 2))
    ends = np.zeros((2, 4))
    order_costs(move, xy, xy, ends, ends, ends, np.array([[0, 1], [1, 0]]))
    order_variants(move, xy, xy, ends, ends, ends, np.array([0, 1]))
    order_greedy(move, xy, xy, ends, ends)
