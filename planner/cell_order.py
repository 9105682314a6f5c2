"""Cell order: in which order to cover the cells, and which of its four variants each uses.

Every cell is covered back and forth in one of four variants (:data:`planner.ordering.VARIANTS`),
each entering at one line end and leaving at another. The order of the cells and the variant of
each are chosen together to keep the route short: the start leg, the moves between cells, the
turns inside each cell and the finish leg. For a given order the best variants follow exactly
from a Viterbi pass (four states per cell); the order itself is searched exhaustively for a few
cells and otherwise built greedily from the start and improved by 2-opt and moving single cells.
Moves are costed as straight lines, or as routed lengths round holes when given.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Up to this many cells every order is tried.
EXHAUSTIVE_MAX_CELLS = 6
#: Up to this many cells the greedy order is improved by local search.
LOCAL_SEARCH_MAX_CELLS = 60
#: Local-search rounds at most.
_MAX_ROUNDS = 8
#: Local search reverses spans and moves cells over at most this many positions.
_WINDOW = 6


@dataclass(frozen=True, slots=True)
class CellVariants:
    """The four variants of each of ``m`` cells.

    Attributes
    ----------
    entry_xy, exit_xy : ndarray, shape (m, 4, 2)
        Where each variant enters its first line and leaves its last, local [m].
    inner_m : ndarray, shape (m, 4)
        Length driven inside the cell (turns; lines are the same for every variant) [m].
    """

    entry_xy: FloatArray
    exit_xy: FloatArray
    inner_m: FloatArray


def order_cells(
    cells: CellVariants,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    *,
    improve: bool = True,
    move_m: Callable[[FloatArray, FloatArray], FloatArray] | None = None,
) -> list[tuple[int, int]]:
    """Choose the order of the cells and the variant of each.

    Parameters
    ----------
    cells : CellVariants
    start_xy, finish_xy : tuple of float or None
        Where the tractor comes from and must end, local [m]; None if free.
    improve : bool
        Improve the greedy order by local search (beyond :data:`EXHAUSTIVE_MAX_CELLS`).
    move_m : callable, optional
        ``move_m(exits, entries)`` gives the length [m] of the move from every point of
        ``exits`` (k, 2) to every point of ``entries`` (k, 2); straight lines if None.

    Returns
    -------
    list of (int, int)
        ``(cell, variant)`` in driving order, every cell once.

    Examples
    --------
    Two one-line cells, the tractor starting beside the second:

    >>> e = np.array([[[0, 0], [0, 10], [0, 0], [0, 10]], [[20, 0], [20, 10], [20, 0], [20, 10]]])
    >>> x = e[:, [1, 0, 1, 0]]
    >>> order_cells(CellVariants(e * 1.0, x * 1.0, np.zeros((2, 4))), (20.0, -5.0), None)
    [(1, 0), (0, 1)]
    """
    m = len(cells.inner_m)
    first = cells.inner_m.copy()
    if start_xy is not None:
        first += np.hypot(*(cells.entry_xy - np.asarray(start_xy)).transpose(2, 0, 1))
    last = np.zeros((m, 4))
    if finish_xy is not None:
        last += np.hypot(*(cells.exit_xy - np.asarray(finish_xy)).transpose(2, 0, 1))
    if m == 1:  # one cell: its best variant (what the exhaustive search below would find)
        return [(0, int(np.argmin(first[0] + last[0])))]
    # move[c, w, c2, w2]: from the exit of (c, w) to the entry of (c2, w2). Hundreds of cells
    # (a jagged boundary) would make it gigabytes: straight moves are then computed as needed.
    ex = cells.exit_xy.reshape(m * 4, 2)
    en = cells.entry_xy.reshape(m * 4, 2)
    if move_m is None and m > LOCAL_SEARCH_MAX_CELLS:
        problem: _Problem = _StraightProblem(cells, first, last)
    else:
        if move_m is None:
            move = np.hypot(ex[:, None, 0] - en[None, :, 0], ex[:, None, 1] - en[None, :, 1])
        else:
            move = move_m(ex, en)
        problem = _Problem(move.reshape(m, 4, m, 4), first, last, cells.inner_m)

    if m <= EXHAUSTIVE_MAX_CELLS:
        orders = _permutations(m)
        costs = np.round(problem.search_costs(orders), 9)
        return problem.search_variants(orders[int(np.argmin(costs))])
    candidates = np.stack([problem.search_greedy(), np.arange(m)])  # nearest next; sweep order
    costs = np.round(problem.search_costs(candidates), 9)
    order = candidates[int(np.argmin(costs))]
    if improve and m <= LOCAL_SEARCH_MAX_CELLS:
        order = problem.improve(order)
    return problem.search_variants(order)


class _Problem:
    """The costs of one ordering problem, and the searches over it."""

    def __init__(
        self, move: FloatArray, first: FloatArray, last: FloatArray, inner: FloatArray
    ) -> None:
        self.move, self.first, self.last, self.inner = move, first, last, inner
        self._compile(move, np.empty((0, 4, 2)), np.empty((0, 4, 2)))

    def _compile(self, move: FloatArray, exits: FloatArray, entries: FloatArray) -> None:
        # The searches run compiled (planner.order_kernels, the same figures) on float64 costs;
        # the methods below stay the numpy reference.
        arrays = (move, exits, entries, self.first, self.last, self.inner)
        self.compiled = all(a.dtype == np.float64 for a in arrays)
        if self.compiled:

            def c(a: FloatArray) -> FloatArray:  # the one array type the kernels take
                return np.require(a, requirements=["C", "W"])

            self._arrays = (
                c(move),
                c(exits),
                c(entries),
                c(self.first),
                c(self.last),
                c(self.inner),
            )

    def search_costs(self, orders: IntArray) -> FloatArray:
        """:meth:`costs`, compiled where it can be."""
        if not self.compiled:
            return self.costs(orders)
        from planner import order_kernels  # numba: imported by the first plan that needs it

        return order_kernels.order_costs(*self._arrays, orders)

    def search_variants(self, order: IntArray) -> list[tuple[int, int]]:
        """:meth:`variants`, compiled where it can be."""
        if not self.compiled:
            return self.variants(order)
        from planner import order_kernels

        chosen = order_kernels.order_variants(*self._arrays, order)
        return list(zip(order.tolist(), chosen.tolist(), strict=True))

    def search_greedy(self) -> IntArray:
        """:meth:`greedy`, compiled where it can be."""
        if not self.compiled:
            return self.greedy()
        from planner import order_kernels

        move, exits, entries, first, _, inner = self._arrays
        return order_kernels.order_greedy(move, exits, entries, first, inner)

    def step(self, a: IntArray, b: IntArray) -> FloatArray:
        """Return the moves from every variant of cells ``a`` to those of cells ``b``, (K, 4, 4)."""
        return np.asarray(self.move[a, :, b, :])

    def row(self, c: int, w: int) -> FloatArray:
        """Return the moves from the exit of ``(c, w)`` to every entry, shape (m, 4)."""
        return np.asarray(self.move[c, w])

    def costs(self, orders: IntArray) -> FloatArray:
        """Route length of the best variants for each order, shape (K,), orders (K, m)."""
        here = self.first[orders[:, 0]]
        for t in range(1, orders.shape[1]):
            step = self.step(orders[:, t - 1], orders[:, t])  # (K, 4, 4)
            here = (here[:, :, None] + step).min(axis=1) + self.inner[orders[:, t]]
        return (here + self.last[orders[:, -1]]).min(axis=1)  # type: ignore[no-any-return]

    def variants(self, order: IntArray) -> list[tuple[int, int]]:
        """Choose the best variant of every cell of ``order`` (Viterbi with back-pointers)."""
        here = self.first[order[0]]
        back = []
        for a, b in itertools.pairwise(order.tolist()):
            options = here[:, None] + self.step(np.array([a]), np.array([b]))[0]
            back.append(np.argmin(options, axis=0))
            here = options.min(axis=0) + self.inner[b]
        w = int(np.argmin(here + self.last[order[-1]]))
        chosen = [w]
        for choice in reversed(back):
            w = int(choice[w])
            chosen.append(w)
        return list(zip(order.tolist(), chosen[::-1], strict=True))

    def greedy(self) -> IntArray:
        """Nearest cell next, from the cell that begins best (nearest the start, if given)."""
        m = len(self.inner)
        current = int(np.argmin(self.first.min(axis=1)))
        w_here = int(np.argmin(self.first[current]))
        order = [current]
        visited = np.zeros(m, dtype=bool)
        visited[current] = True
        for _ in range(m - 1):
            value = self.row(current, w_here) + self.inner
            value[visited] = np.inf
            flat = int(np.argmin(value))
            current, w_here = flat // 4, flat % 4
            order.append(current)
            visited[current] = True
        return np.asarray(order, dtype=np.int64)

    def improve(self, order: IntArray) -> IntArray:
        """Best 2-opt reversal or single-cell move, repeatedly, while it shortens the route."""
        neighbourhood, changed, rank = _neighbourhood(len(order))
        best = float(self.search_costs(order[None])[0])
        for _ in range(_MAX_ROUNDS):
            candidates = order[neighbourhood]
            if self.compiled:  # every candidate in full: the figures of costs_from
                costs = self.search_costs(candidates)
            else:
                costs = self.costs_from(order, candidates, changed)
            # The first of equals in the search's own order (``rank``), as before.
            ties = np.flatnonzero(costs == costs.min())
            k = int(ties[np.argmin(rank[ties])])
            if costs[k] >= best - 1e-9:
                break
            order, best = candidates[k], float(costs[k])
        return order

    def costs_from(self, order: IntArray, candidates: IntArray, changed: IntArray) -> FloatArray:
        """:meth:`costs` of ``candidates``, each ``order`` up to its position ``changed``.

        The Viterbi states of ``order``'s common beginning are computed once, and a candidate
        is carried on from where it first differs (``changed`` ascending): about half the
        steps of :meth:`costs`, the same figures (each row takes the same operations).
        """
        n = len(order)
        prefix = [self.first[order[0]]]
        for t in range(1, n):
            step = self.step(order[t - 1 : t], order[t : t + 1])
            prefix.append((prefix[-1][None, :, None] + step).min(axis=1)[0] + self.inner[order[t]])
        here = np.empty((len(candidates), 4))
        bounds = np.searchsorted(changed, np.arange(n + 1), side="left").tolist()
        for t in range(n):
            begin, active = bounds[t], bounds[t + 1]
            if t == 0:
                here[:active] = self.first[candidates[:active, 0]]
                continue
            here[begin:active] = prefix[t - 1]
            rows = candidates[:active]
            step = self.step(rows[:, t - 1], rows[:, t])
            here[:active] = (here[:active, :, None] + step).min(axis=1) + self.inner[rows[:, t]]
        return (here + self.last[candidates[:, -1]]).min(axis=1)  # type: ignore[no-any-return]


@functools.lru_cache(maxsize=EXHAUSTIVE_MAX_CELLS + 1)
def _permutations(m: int) -> IntArray:
    """Return every order of ``m`` cells, shape (m!, m) (read-only, shared)."""
    orders = np.array(list(itertools.permutations(range(m))), dtype=np.int64)
    orders.flags.writeable = False
    return orders


@functools.lru_cache(maxsize=LOCAL_SEARCH_MAX_CELLS + 1)
def _neighbourhood(n: int) -> tuple[IntArray, IntArray, IntArray]:
    """Return the local search's orders of positions ``0..n-1``, where each first differs.

    Returns
    -------
    positions : ndarray, shape (K, n)
        Every reversal of a span and every single-cell move within :data:`_WINDOW`, by the
        first position they change (ascending; read-only, shared).
    changed : ndarray, shape (K,)
        That first position.
    rank : ndarray, shape (K,)
        Each one's place in the search's order (reversals, then moves).
    """
    i, j = np.triu_indices(n, k=1)
    near = j - i <= _WINDOW
    i, j = i[near], j[near]
    idx = np.broadcast_to(np.arange(n), (len(i), n))
    # Reversal of order[i..j]: position p takes i + j - p inside the span.
    inside = (idx >= i[:, None]) & (idx <= j[:, None])
    reversals = np.where(inside, i[:, None] + j[:, None] - idx, idx)
    # Moving the cell at position a to position b (a != b).
    a, b = np.nonzero(~np.eye(n, dtype=bool))
    near = np.abs(a - b) <= _WINDOW
    a, b = a[near], b[near]
    # Position p of the moved order takes src at dst and shifts the cells between by one.
    p = np.arange(n)[None, :]
    src, dst = a[:, None], b[:, None]
    forward = (src < dst) & (p >= src) & (p < dst)
    backward = (src > dst) & (p > dst) & (p <= src)
    moves = np.where(p == dst, src, p + forward - backward)
    positions = np.vstack([reversals, moves]).astype(np.int64)
    changed = np.concatenate([i, np.minimum(a, b)]).astype(np.int64)
    by_change = np.argsort(changed, kind="stable")
    positions, changed = positions[by_change], changed[by_change]
    rank = by_change.astype(np.int64)
    for array in (positions, changed, rank):
        array.flags.writeable = False
    return positions, changed, rank


class _StraightProblem(_Problem):
    """:class:`_Problem` with straight moves computed from the coordinates when needed."""

    def __init__(self, cells: CellVariants, first: FloatArray, last: FloatArray) -> None:
        super().__init__(np.empty((0, 4, 0, 4)), first, last, cells.inner_m)
        self.exit_xy, self.entry_xy = cells.exit_xy, cells.entry_xy
        self._compile(self.move, self.exit_xy, self.entry_xy)  # straight moves as needed

    def step(self, a: IntArray, b: IntArray) -> FloatArray:
        gap = self.exit_xy[a][:, :, None, :] - self.entry_xy[b][:, None, :, :]
        return np.asarray(np.hypot(gap[..., 0], gap[..., 1]))

    def row(self, c: int, w: int) -> FloatArray:
        gap = self.entry_xy - self.exit_xy[c, w]
        return np.asarray(np.hypot(gap[..., 0], gap[..., 1]))
