"""The headings R5 fits first: the best-covering by the decomposition's estimate at every heading.

With a turning radius the estimate's best are ranked again on their cells fitted from a table
of the vehicle's turns (:mod:`planner.fit_screen`); :mod:`planner.fitted_cells` then fits and
compares them as the vehicle drives them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import numpy.typing as npt

from planner.cell_plans import CellCover
from planner.decomposition import SweepRings
from planner.fit_screen import TurnTable
from planner.fitted_cells import turn_change_m
from planner.parity_kernels import parity_choice, parity_losses_m2
from planner.types import Vehicle

if TYPE_CHECKING:
    from planner.heading_screen import ScreenedCovers

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


#: Headings fitted because the decomposed estimate ranks them best for coverage (R5). Two left
#: 3 of 223 real fields at 4 m with the hand tractor and 3 of 25 star fields short of the rule
#: against a 1° brute force; three leave 1 (0.01 pp beyond the slack) and none, for about 5 %
#: more planning time (``python -m bench.heading_brute_force_real``, ``python -m
#: bench.heading_brute_force_non_convex``, ``python -m bench.plan_times``).
COVER_FITS = 3


#: With a turning radius, this many of the headings the estimate ranks best-covering are
#: screened fitted (:func:`planner.heading_screen.fit_screened`) and ranked on that.
SCREENED_FITS = 24


class CoverPicks(NamedTuple):
    """:func:`cover_picks`' headings, and the screen of every heading it ranked them on.

    ``cell_losses_m2``: for each heading screened fitted (by its index), what fitting takes
    off each of its cells both ways round, as :func:`excluded_variants` would measure it.
    """

    picks: list[int]
    screen: ScreenedCovers
    cell_losses_m2: dict[int, FloatArray]


def cover_picks(
    prepared: Sequence[SweepRings],
    headings_deg: FloatArray,
    interval_m: float,
    edge_m: float,
    vehicle: Vehicle,
    turn_table: TurnTable | None = None,
    *,
    parity_slack_m2: float = math.inf,
) -> CoverPicks:
    """Pick the headings to fit from the decomposed estimate at every heading (R5).

    The heading search's ragged scan misjudges which heading covers most by more than the
    rule's slack on about one real field in six (35 of 223 at 4 m with the hand tractor);
    the decomposition's estimate (:func:`estimate_m2`: the cells' coverage less the turns'
    pull-back) far less often. So every heading is decomposed, compiled
    (:func:`planner.heading_screen.screen_cells`), and the :data:`COVER_FITS` best by that
    estimate are picked; ties go to the smaller heading (R7). With a turning radius the
    estimate errs by a few pp between headings (the pull-back depends on the boundary at
    each line end, and lines drop), so its :data:`SCREENED_FITS` best are ranked again on
    each cell fitted from a table of the vehicle's turns (:mod:`planner.fit_screen`), each
    cell counted the way round the plan will drive it (``parity_slack_m2``): on the 223 real
    fields at 4 m with the small tractor, 5 fall short of the rule against a 1° brute force
    (worst 0.32 pp beyond the slack; 6 before :func:`choose_cells` fitted neighbours of a
    heading that fitting cost its cover; 0.54 pp while two were fitted), against 43 (worst
    5.71 pp) on the estimate alone and 20 (worst 1.27 pp) while cells were driven the way
    round that saved length.

    Parameters
    ----------
    prepared : sequence of SweepRings
        The machine area's parts (:func:`planner.decomposition.sweep_rings`).
    headings_deg : ndarray, shape (A,)
    interval_m, edge_m : float
        Line spacing, and how far inside each cell its outer lines run [m].
    vehicle : Vehicle
    turn_table : TurnTable, optional
        The vehicle's turns (:func:`planner.fit_screen.turn_table`): given, the
        :data:`SCREENED_FITS` best by the estimate are ranked again on their cells fitted
        from it (the estimate misjudges turns with a radius by a few percentage points).
    parity_slack_m2 : float, optional
        What the cells' order gives up for length, as :func:`excluded_variants` [m²]
        (:func:`planner.parity_kernels.cell_loss_m2`); by default it chooses for length only.

    Returns
    -------
    CoverPicks
        The picks, indices into ``headings_deg`` best-covering first, and the screen they
        were ranked on (its cells and lines serve the plan:
        :func:`planner.cell_plans.cover_screened`).

    Examples
    --------
    An L: its best cover is along its arms.

    >>> from shapely import Polygon
    >>> from planner.decomposition import sweep_rings
    >>> from planner.vehicles import resolve_vehicle
    >>> ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    >>> headings = np.array([0.0, 45.0, 90.0, 135.0])
    >>> picks = cover_picks([sweep_rings(ell)], headings, 4.0, 2.0, resolve_vehicle(None)).picks
    >>> headings[picks[:2]].tolist()  # the best two
    [0.0, 90.0]
    """
    from planner.heading_screen import fit_screened_cells, screen_cells  # numba: first plan's

    d = float(interval_m)
    _, reach_m = turn_change_m(vehicle, d)
    # With a table, the cells of the headings that may rank among the SCREENED_FITS best are
    # kept, so that fitting them decomposes none again. Only the best are needed: the
    # others' covers are left unmeasured (NaN).
    needed = COVER_FITS if turn_table is None else SCREENED_FITS
    screen = screen_cells(
        prepared,
        headings_deg,
        d,
        edge_m,
        reach_m=reach_m,
        keep=0 if turn_table is None else SCREENED_FITS,
        rank=needed,
    )
    covered_m2, turn_count = screen.covered_m2, screen.turn_count
    # As estimate_m2; a heading the decomposition refuses, or that cannot rank, is never picked.
    estimate = np.where(
        np.isfinite(covered_m2), covered_m2 - 2.0 * turn_count * reach_m * d, -np.inf
    )
    # Rounded to a µm² so that the last bits of another CPU's sums cannot reorder a tie (R7).
    estimate = np.round(estimate, 6)
    order = np.lexsort((headings_deg, -estimate))  # headings refused sort last
    cell_losses_m2: dict[int, FloatArray] = {}
    if turn_table is not None:
        screened = order[:SCREENED_FITS]
        screened = screened[np.isfinite(estimate[screened])]  # (the refused are last)
        fits = fit_screened_cells(screen, screened, turn_table, parity_slack_m2=parity_slack_m2)
        rank = np.round(np.where(np.isfinite(fits.fitted_m2), fits.fitted_m2, -np.inf), 6)
        order = np.concatenate(
            [screened[np.lexsort((headings_deg[screened], -rank))], order[len(screened) :]]
        )
        for a, losses in zip(screened.tolist(), fits.cell_losses_m2, strict=True):
            if losses is not None:
                cell_losses_m2[a] = losses
    picks = [int(a) for a in order[:COVER_FITS] if np.isfinite(estimate[a])]
    return CoverPicks(picks, screen, cell_losses_m2)


def excluded_variants(
    cover: CellCover,
    table: TurnTable,
    interval_m: float,
    slack_m2: float,
    cell_losses_m2: FloatArray | None = None,
) -> BoolArray:
    """Return the variants of ``cover``'s cells that would buy length with coverage (R5).

    Each cell is screened fitted both ways round
    (:func:`planner.parity_kernels.parity_losses_m2`, unless ``cell_losses_m2`` holds that
    already: :class:`CoverPicks`); the variants of a way that loses more than ``slack_m2``
    beyond the other are excluded from the cell order
    (:func:`planner.cell_plans.order_heading`).

    Returns
    -------
    ndarray of bool, shape (cells, 4)
    """
    scan = cover.scan
    losses = cell_losses_m2
    if losses is None:
        losses = parity_losses_m2(
            [c.chains for c in cover.cells], scan.offsets, scan.u, scan.v_lo, scan.v_hi,
            interval_m, table,
        )  # fmt: skip
    return parity_choice(losses, np.diff(scan.offsets), slack_m2)
