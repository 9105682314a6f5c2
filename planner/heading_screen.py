"""Many headings of one field screened in one compiled call: what each heading's cells cover.

:func:`planner.cell_plans.cover_heading` decomposes the field at a heading into cells, scans
their lines and measures what the lines cover. Its cores are compiled, but the Python around
them (the rotation, the critical cuts, the cells' rings and chains as objects, the sums) makes
it cost about 0.5 ms a heading on the real fields. :func:`screen_covers` runs the whole of it
for every heading in one compiled loop (:mod:`planner.screen_kernels`) and returns only the
figures, ``cover_heading``'s to the last bit: covered area, lines and turns
(``bench/screen_speed.py``: about 8 times faster). What the compiled loop leaves to numpy or
shapely (a boundary too degenerate for the sweep, which shapely clips; footprints wider than
the lines' spacing; NaN) is measured by ``cover_heading`` itself, for that heading.

With a turning radius, the headings the estimate ranks best are then screened with each cell
fitted for the vehicle (:mod:`planner.fit_screen`). :func:`screen_cells` keeps the cells of
those that may rank so while it screens, and :func:`fit_screened` fits them: each heading is
decomposed once. Asked for the best few only (``rank``), it measures no cover that cannot be
among them (the field's area less a heading's turns below the best so far: with a radius,
most headings), and the plan takes its cells from the screen (:func:`screened_cells`).
``tests/planner/test_heading_screen.py`` holds the figures equal to ``cover_heading``'s on
real and random fields, the kept cells' fit equal to :func:`screen_fitted`'s, a ranked
screen's best equal to a full one's, and the screened cells equal to ``cover_heading``'s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
import shapely

from planner.decomposition import SweepRings
from planner.fit_screen import TurnTable
from planner.screen_kernels import (
    _BY_PYTHON,
    _fit_kept,
    _ring_arrays,
    _Rings,
    _screen,
    _sweep_cosines,
)

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


class _Kept(NamedTuple):
    """The cells :func:`planner.screen_kernels._screen` kept to fit, laid end to end."""

    kept_of: IntArray
    chain_at: IntArray
    cell_at: IntArray
    line_at: IntArray
    chains: FloatArray
    chains_at: IntArray
    offsets: IntArray
    u: FloatArray
    v_lo: FloatArray
    v_hi: FloatArray


class StagedCells(NamedTuple):
    """Every heading's cells and lines as :func:`planner.screen_kernels._screen` made them."""

    staged: npt.NDArray[np.bool_]
    vertex_at: IntArray
    size_at: IntArray
    offset_at: IntArray
    scan_at: IntArray
    u: FloatArray
    v: FloatArray
    sizes: IntArray
    offsets: IntArray
    line_u: FloatArray
    v_lo: FloatArray
    v_hi: FloatArray


class ScreenedCells(NamedTuple):
    """One heading's cells and lines, as :func:`planner.cell_plans.cover_heading` makes them.

    Attributes
    ----------
    rings : list of (ndarray, ndarray)
        Each cell's ``(u, v)`` ring, sweep frame [m].
    offsets : ndarray of int
        Each cell's lines ``[offsets[c]:offsets[c + 1]]``.
    u, v_lo, v_hi : ndarray
        The lines (:class:`planner.lines.LineScan`'s fields).
    covered_m2 : float
        What they cover, NaN if the screen left it unmeasured [m²].
    """

    rings: list[tuple[FloatArray, FloatArray]]
    offsets: IntArray
    u: FloatArray
    v_lo: FloatArray
    v_hi: FloatArray
    covered_m2: float


class ScreenedCovers(NamedTuple):
    """What :func:`screen_cells` measured at each heading, and the cells it kept to fit.

    Attributes
    ----------
    covered_m2, line_count, turn_count : ndarray
        Per heading, as :func:`screen_covers` returns them.
    interval_m : float
        Line spacing and footprint width [m].
    kept : _Kept or None
        The cells and lines of the headings :func:`fit_screened` can fit (None: none).
    staged : StagedCells or None
        Every heading's cells and lines, where the compiled screen made them
        (:func:`screened_cells`).
    """

    covered_m2: FloatArray
    line_count: IntArray
    turn_count: IntArray
    interval_m: float
    kept: _Kept | None
    staged: StagedCells | None = None


def screened_cells(screened: ScreenedCovers, heading_index: int) -> ScreenedCells | None:
    """Return the cells and lines :func:`screen_cells` made at one heading (None: it did not).

    Bit for bit those of :func:`planner.cell_plans.cover_heading` at that heading
    (``tests/planner/test_heading_screen.py``), so a plan need not decompose it again.
    """
    s, a = screened.staged, int(heading_index)
    if s is None or not s.staged[a]:
        return None
    u = s.u[s.vertex_at[a] : s.vertex_at[a + 1]]
    v = s.v[s.vertex_at[a] : s.vertex_at[a + 1]]
    ends = np.cumsum(s.sizes[s.size_at[a] : s.size_at[a + 1]]).tolist()
    rings = [(u[i:j], v[i:j]) for i, j in zip([0, *ends[:-1]], ends, strict=True)]
    k0, k1 = s.scan_at[a], s.scan_at[a + 1]
    return ScreenedCells(
        rings,
        s.offsets[s.offset_at[a] : s.offset_at[a + 1]],
        s.line_u[k0:k1],
        s.v_lo[k0:k1],
        s.v_hi[k0:k1],
        float(screened.covered_m2[a]),
    )


def screen_covers(
    prepared: Sequence[SweepRings], headings_deg: npt.ArrayLike, interval_m: float, edge_m: float
) -> tuple[FloatArray, IntArray, IntArray]:
    """Measure what :func:`planner.cell_plans.cover_heading` does, at many headings at once.

    Parameters
    ----------
    prepared : sequence of SweepRings
        The field's parts, each prepared by :func:`planner.decomposition.sweep_rings`, in the
        order ``cover_heading`` takes them.
    headings_deg : array_like of float
        Line headings, degrees clockwise from north.
    interval_m : float
        Line spacing and footprint width [m].
    edge_m : float
        How far inside each cell its outer lines run [m] (``cover_heading``'s ``edge_m``).

    Returns
    -------
    covered_m2 : ndarray of float
        Per heading, ``cover_heading(...).covered_m2`` to the last bit [m²].
    line_count : ndarray of int
        Per heading, ``cover_heading(...).line_count``.
    turn_count : ndarray of int
        Per heading, the lines less the cells with a line, at least 0
        (``planner.fitted_cells._turn_count`` of the cover).

    A heading ``cover_heading`` raises at gives NaN, -1 and -1.

    Examples
    --------
    An L at 135° has three cells; at 0° one:

    >>> from shapely import Polygon
    >>> from planner.decomposition import sweep_rings
    >>> ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    >>> covered, lines, turns = screen_covers([sweep_rings(ell)], [0.0, 135.0], 4.0, 2.0)
    >>> lines.tolist(), turns.tolist()
    ([15, 23], [14, 20])
    """
    screened = screen_cells(prepared, headings_deg, interval_m, edge_m)
    return screened.covered_m2, screened.line_count, screened.turn_count


def screen_cells(
    prepared: Sequence[SweepRings],
    headings_deg: npt.ArrayLike,
    interval_m: float,
    edge_m: float,
    *,
    reach_m: float = 0.0,
    keep: int = 0,
    rank: int = 0,
) -> ScreenedCovers:
    """:func:`screen_covers`, keeping the cells of the headings that may be fitted next.

    Each heading is decomposed once: the cells and lines of every heading that may rank among
    the ``keep`` best by the estimate ``covered_m2 - 2 * turn_count * reach_m * interval_m``
    (:func:`planner.fitted_cells.estimate_m2`, rounded to a µm², ties to the smaller heading)
    are kept for :func:`fit_screened`, which would otherwise decompose them again.

    Parameters
    ----------
    prepared, headings_deg, interval_m, edge_m
        As :func:`screen_covers`.
    reach_m : float
        How far each turn pulls its two line ends back [m]
        (:func:`planner.fitted_cells.turn_change_m`).
    keep : int
        How many of the best-estimated headings :func:`fit_screened` may be asked for.
    rank : int
        If above 0, only the ``rank`` best by that estimate are needed: a heading that cannot
        be among them (the field's area less its turns' term is below the ``rank``-th best)
        is left unmeasured, its ``covered_m2`` NaN (its lines and turns are counted). With a
        turning radius most headings are (``planner.screen_kernels._screen``). At least
        ``keep``: the headings to fit must all be measured.

    Returns
    -------
    ScreenedCovers
    """
    headings = np.atleast_1d(np.asarray(headings_deg, dtype=np.float64)).ravel()
    d, edge = float(interval_m), float(edge_m)
    if rank > 0:
        rank = max(rank, keep)  # a heading left unmeasured is not kept either
    rings = _ring_arrays(prepared) if len(headings) else None
    if rings is None:  # cover_heading measures (or refuses) every heading
        slow = _by_python(prepared, headings, d, edge, np.arange(len(headings)))
        return ScreenedCovers(*slow, d, None)
    area_m2 = float(sum(p.field.area for p in prepared))
    status, covered, line_count, turn_count, kept, staged = _run_screen(
        rings, headings, d, edge, float(reach_m), int(keep), int(rank), area_m2
    )
    left = np.flatnonzero(status == _BY_PYTHON)
    if len(left):
        slow = _by_python(prepared, headings, d, edge, left)
        covered[left], line_count[left], turn_count[left] = (s[left] for s in slow)
    return ScreenedCovers(covered, line_count, turn_count, d, kept if keep > 0 else None, staged)


def fit_screened(
    screened: ScreenedCovers,
    which: npt.ArrayLike,
    table: TurnTable,
    *,
    parity_slack_m2: float = math.inf,
) -> FloatArray:
    """Estimate the coverage of the headings ``which`` once fitted, from their kept cells [m²].

    :func:`screen_fitted` of ``screened``'s headings ``which`` (indices), to the last bit, at
    those whose cells :func:`screen_cells` kept; NaN at the others.
    """
    return fit_screened_cells(screened, which, table, parity_slack_m2=parity_slack_m2).fitted_m2


class ScreenedFits(NamedTuple):
    """:func:`fit_screened_cells`' figures.

    Attributes
    ----------
    fitted_m2 : ndarray of float
        :func:`fit_screened`'s.
    cell_losses_m2 : list of ndarray or None
        Per heading asked for, what fitting takes off each of its cells, with the cell's
        first line driven up, then down, shape (cells, 2)
        (:func:`planner.parity_kernels.parity_losses_m2` of its cells, to the last bit);
        None where the cells were not kept [m²].
    """

    fitted_m2: FloatArray
    cell_losses_m2: list[FloatArray | None]


def fit_screened_cells(
    screened: ScreenedCovers,
    which: npt.ArrayLike,
    table: TurnTable,
    *,
    parity_slack_m2: float = math.inf,
) -> ScreenedFits:
    """:func:`fit_screened`, with each heading's cells' losses both ways round."""
    at = np.atleast_1d(np.asarray(which, dtype=np.int64)).ravel()
    if screened.kept is None:
        return ScreenedFits(np.full(len(at), np.nan), [None] * len(at))
    t = table
    fitted, loss_at, losses = _fit_kept(
        *screened.kept, screened.covered_m2, at, screened.interval_m,
        t.offsets, t.u, t.v, t.u_lo, t.u_hi, t.beyond_m, t.scalars, float(parity_slack_m2),
    )  # fmt: skip
    bounds = loss_at.tolist()
    cells: list[FloatArray | None] = [
        losses[i:j] if math.isfinite(f) else None
        for i, j, f in zip(bounds[:-1], bounds[1:], fitted.tolist(), strict=True)
    ]
    return ScreenedFits(fitted, cells)


def screen_fitted(
    prepared: Sequence[SweepRings],
    headings_deg: npt.ArrayLike,
    interval_m: float,
    edge_m: float,
    table: TurnTable,
    *,
    parity_slack_m2: float = math.inf,
) -> FloatArray:
    """Estimate the coverage of each heading's cells once fitted for the vehicle [m²].

    The cells and lines of :func:`screen_covers`, each cell's lines fitted from ``table``
    (:mod:`planner.fit_screen`) both ways round and counted as the plan drives it
    (:func:`planner.parity_kernels.cell_loss_m2` with ``parity_slack_m2``; by default the two
    ways averaged); NaN at a heading it cannot estimate (a turn beyond the table, a boundary
    the compiled decomposition leaves to shapely).

    Examples
    --------
    An L: along its arms the turns fit best.

    >>> from shapely import Polygon
    >>> from planner.decomposition import sweep_rings
    >>> from planner.fit_screen import turn_table
    >>> from planner.vehicles import resolve_vehicle
    >>> ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    >>> table = turn_table(resolve_vehicle("small_tractor"), 4.0)
    >>> fitted = screen_fitted([sweep_rings(ell)], [0.0, 45.0], 4.0, 1.35, table)
    >>> bool(fitted[0] > fitted[1])
    True
    """
    headings = np.atleast_1d(np.asarray(headings_deg, dtype=np.float64)).ravel()
    d = float(interval_m)
    rings = _ring_arrays(prepared) if len(headings) else None
    if rings is None:
        return np.full(len(headings), np.nan)
    # Every heading kept; those the compiled screen leaves to Python are not: NaN.
    _, covered, line_count, turn_count, kept, _ = _run_screen(
        rings, headings, d, float(edge_m), 0.0, len(headings), 0, 0.0
    )
    screened = ScreenedCovers(covered, line_count, turn_count, d, kept)
    return fit_screened(screened, np.arange(len(headings)), table, parity_slack_m2=parity_slack_m2)


def _run_screen(
    rings: _Rings,
    headings: FloatArray,
    d: float,
    edge: float,
    reach_m: float,
    keep: int,
    rank: int,
    area_m2: float,
) -> tuple[IntArray, FloatArray, IntArray, IntArray, _Kept, StagedCells]:
    """Call :func:`_screen` on the rings at ``headings``, keeping and ranking as it says."""
    cos_t, sin_t = _sweep_cosines(headings)
    figures, kept, staged = _screen(*rings, cos_t, sin_t, d, edge, reach_m, keep, rank, area_m2)
    status, covered, line_count, turn_count = figures
    for array in staged:
        array.flags.writeable = False  # the plan's cells are views of these
    return status, covered, line_count, turn_count, _Kept(*kept), StagedCells(*staged)


def _by_python(
    prepared: Sequence[SweepRings], headings: FloatArray, d: float, edge: float, which: IntArray
) -> tuple[FloatArray, IntArray, IntArray]:
    """:func:`screen_covers` of the headings ``which`` by ``cover_heading`` itself."""
    from planner.cell_plans import cover_heading  # it imports the planner's stages

    covered = np.full(len(headings), np.nan)
    line_count = np.full(len(headings), -1, dtype=np.int64)
    turn_count = np.full(len(headings), -1, dtype=np.int64)
    for a in which.tolist():
        try:
            cover = cover_heading(prepared, float(headings[a]), d, edge)
        except (ValueError, IndexError, ArithmeticError, shapely.errors.ShapelyError):
            continue  # NaN, -1, -1: no cover at this heading
        with_lines = sum(1 for c in cover.cells if c.lines.stop > c.lines.start)
        covered[a] = cover.covered_m2
        line_count[a] = cover.line_count
        turn_count[a] = max(cover.line_count - with_lines, 0)
    return covered, line_count, turn_count
