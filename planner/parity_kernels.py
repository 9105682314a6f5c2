"""Which way round each cell is driven, for coverage: its two turn-end parities screened.

A cell's lines are driven back and forth in one of four variants
(:data:`planner.ordering.VARIANTS`). Two of them turn at the top between its first two lines
(left to right), the other two at the bottom: every turn of the cell changes end with the
parity. With a turning radius the ends where a cell turns decide what fitting the turns
takes off its cover (:func:`planner.line_ends.fit_lines`), by whole lines where a turn
cannot fit: on a real field, 37.5 pp of the field's area one way round against 15.7 pp the
other. The cell order chooses variants for length (:mod:`planner.cell_order`); R5 does not
let it buy length with coverage, so a parity the screen (:mod:`planner.fit_screen`) finds
costs clearly more cover than the other is excluded (:func:`parity_choice`), and the screen
counts each cell the way the plan will drive it (:func:`cell_loss_m2`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from planner.coverage import Chains, packed
from planner.fit_screen import CACHED_SLIDES, TurnTable, _fit_cell
from planner.kernel_helpers import _jit, _jit_counted_by_caller, read_only

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: A parity is excluded when the screen puts its loss this share of the field's area above
#: the other's: a quarter of R5's 0.2 pp.
PARITY_SLACK_SHARE = 0.0005


@_jit_counted_by_caller
def cell_loss_m2(up_m2: float, down_m2: float, slack_m2: float) -> float:
    """Return what fitting takes off a cell as the plan drives it, from both ways' losses [m²].

    The better parity where the other is excluded (:func:`parity_choice`); else the cell
    order picks either for length, and the two are averaged.
    """
    if abs(up_m2 - down_m2) > slack_m2:
        return up_m2 if up_m2 < down_m2 else down_m2
    return (up_m2 + down_m2) / 2.0


@_jit
def _parity_losses(
    all_chains: FloatArray,
    chains_at: IntArray,
    offsets: IntArray,
    line_u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    d: float,
    table: tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray],
    table_beyond_m: FloatArray,
    table_scalars: FloatArray,
) -> FloatArray:
    """Each cell's screened loss with its first line up and down [m²], shape (cells, 2)."""
    cells = len(offsets) - 1
    losses = np.zeros((cells, 2))
    work = np.empty((8, len(line_u)))
    flags = np.empty((3, len(line_u)), dtype=np.bool_)
    cache_keys = np.empty(5 * CACHED_SLIDES, dtype=np.int64)
    cache_values = np.empty(2 * CACHED_SLIDES)
    for c in range(cells):
        k0, k1 = offsets[c], offsets[c + 1]
        if k1 - k0 < 2:
            continue  # one line: no turn
        chains = all_chains[chains_at[c] : chains_at[c + 1]]
        for j in range(2):
            losses[c, j] = _fit_cell(
                chains, line_u[k0:k1], v_lo[k0:k1], v_hi[k0:k1], j == 0,
                table, table_beyond_m, table_scalars, cache_keys, cache_values,
                work[:, k0:k1], flags[:, k0:k1], d,
            )  # fmt: skip
    return losses


def parity_losses_m2(
    chains: Sequence[Chains],
    offsets: IntArray,
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    interval_m: float,
    table: TurnTable,
) -> FloatArray:
    """Screen what fitting takes off each cell, driven with its first line up and down [m²].

    Parameters
    ----------
    chains : sequence of Chains
        The cells, sweep frame.
    offsets : ndarray of int, shape (cells + 1,)
        Cell ``c`` has the lines ``offsets[c]:offsets[c + 1]``, left to right.
    u, v_lo, v_hi : ndarray
        The lines as scanned [m].
    interval_m : float
    table : TurnTable
        The vehicle's turns (:func:`planner.fit_screen.turn_table`).

    Returns
    -------
    ndarray, shape (cells, 2)
        The loss with the cell's first line (leftmost) driven up, then down.
    """
    packed_chains = [packed(c) for c in chains]
    chains_at = np.concatenate([[0], np.cumsum([len(p) for p in packed_chains])]).astype(np.int64)
    return _parity_losses(
        read_only(np.concatenate(packed_chains) if packed_chains else np.zeros(0), np.float64),
        read_only(chains_at, np.int64),
        read_only(offsets, np.int64),
        read_only(u, np.float64),
        read_only(v_lo, np.float64),
        read_only(v_hi, np.float64),
        float(interval_m),
        (
            read_only(table.offsets, np.int64),
            read_only(table.u, np.float64),
            read_only(table.v, np.float64),
            read_only(table.u_lo, np.float64),
            read_only(table.u_hi, np.float64),
        ),
        read_only(table.beyond_m, np.float64),
        read_only(table.scalars, np.float64),
    )


def parity_choice(losses_m2: FloatArray, line_counts: IntArray, slack_m2: float) -> BoolArray:
    """Which variants of each cell not to drive: those of a parity that loses clearly more.

    Parameters
    ----------
    losses_m2 : ndarray, shape (cells, 2)
        :func:`parity_losses_m2`.
    line_counts : ndarray of int, shape (cells,)
    slack_m2 : float
        A parity is excluded when it loses more than this beyond the other [m²].

    Returns
    -------
    ndarray of bool, shape (cells, 4)
        In :data:`planner.ordering.VARIANTS` order.

    Examples
    --------
    The first cell loses 30 m² more with its first line down; the second, of 3 lines, about
    the same either way:

    >>> parity_choice(np.array([[10.0, 40.0], [5.0, 6.0]]), np.array([4, 3]), 2.0).tolist()
    [[False, True, False, True], [False, False, False, False]]
    """
    up_m2, down_m2 = losses_m2[:, 0], losses_m2[:, 1]
    exclude_up = up_m2 > down_m2 + slack_m2
    exclude_down = down_m2 > up_m2 + slack_m2
    # left_up drives its first line up, left_down down. The right variants drive the lines
    # in reverse order, so right_up turns at the top between the first two when the count
    # is even (its second-last line driven is the first, and it runs up), as left_up does.
    even = line_counts % 2 == 0
    right_up_is_up = even
    return np.stack(
        [
            exclude_up,
            exclude_down,
            np.where(right_up_is_up, exclude_up, exclude_down),
            np.where(right_up_is_up, exclude_down, exclude_up),
        ],
        axis=1,
    )


def warm_up() -> None:
    """Compile the kernel, or load it from the disk cache, on an L's cells at 135°."""
    from shapely import Polygon

    from planner.cell_plans import cover_heading
    from planner.decomposition import sweep_rings
    from planner.fit_screen import turn_table
    from planner.vehicles import resolve_vehicle

    ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    cover = cover_heading([sweep_rings(ell)], 135.0, 4.0, 1.35)
    scan = cover.scan
    table = turn_table(resolve_vehicle("small_tractor"), 4.0)
    chains = [c.chains for c in cover.cells]
    parity_losses_m2(chains, scan.offsets, scan.u, scan.v_lo, scan.v_hi, 4.0, table)
