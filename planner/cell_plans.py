"""One heading of a non-convex field planned cheaply: cells, their lines, variants and order.

:func:`plan_heading` decomposes the inner area at a heading (:mod:`planner.decomposition`),
scans each cell's lines (R2, R3 per cell), scores its four variants and orders the cells with
straight moves; the winner is then reordered with routed moves (:func:`reorder`) and, with
headland passes, its lines reach the headland (:func:`reach_headland`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from shapely import Polygon

from planner.cell_order import CellVariants, order_cells
from planner.coverage import Chains, convex_chains, convex_chains_numpy, covered_cells
from planner.decomposition import SweepRings, decompose_sweep
from planner.lines import LineScan, from_sweep, scan_cells
from planner.ordering import aggregate_scan, combine_variants, variant_ends
from planner.types import Objective

FloatArray = npt.NDArray[np.float64]
#: ``move_m(exits, entries)``: lengths [m] of the moves from every exit to every entry.
MoveCost = Callable[[FloatArray, FloatArray], FloatArray]
#: What an excluded variant adds to its cell's length [m]: more than any plan is long (a
#: 2,000 ha field at 1 m is 20,000 km of lines), so one is driven only if no other can be.
EXCLUDED_M = 1e12


@dataclass(frozen=True, slots=True)
class Cell:
    """One cell at a heading: its ring and chains (sweep frame) and its lines in the scan."""

    u_ring: FloatArray
    v_ring: FloatArray
    chains: Chains
    lines: slice


@dataclass(frozen=True, slots=True)
class CellPlan:
    """A heading planned cheaply: cells, lines, variants, cell order and its figures."""

    heading_deg: float
    cells: list[Cell]
    scan: LineScan
    variants: CellVariants
    working_m: float
    order: list[tuple[int, int]]
    length_m: float
    line_count: int
    covered_m2: float


def better(candidate: CellPlan, best: CellPlan, objective: Objective) -> bool:
    """Whether ``candidate`` beats ``best`` by the objective (lines first, or length)."""
    if objective == "fewest_lines" and candidate.line_count != best.line_count:
        return candidate.line_count < best.line_count
    return candidate.length_m < best.length_m - 1e-6


def plan_heading(
    parts: Sequence[Polygon | SweepRings],
    heading: float,
    d: float,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    edge_m: float,
) -> CellPlan:
    """Decompose, scan and order the cells at one heading; turns and moves straight.

    ``parts`` may be prepared by :func:`planner.decomposition.sweep_rings` (many headings).
    """
    return order_heading(cover_heading(parts, heading, d, edge_m), start_xy, finish_xy)


@dataclass(frozen=True, slots=True)
class CellCover:
    """A heading's cells and lines and what they cover: :func:`plan_heading` before the order."""

    heading_deg: float
    cells: list[Cell]
    scan: LineScan
    line_count: int
    covered_m2: float


def cover_heading(
    parts: Sequence[Polygon | SweepRings], heading: float, d: float, edge_m: float
) -> CellCover:
    """Decompose and scan the cells at one heading, and measure what their lines cover."""
    rings = [ring for part in parts for ring in decompose_sweep(part, heading)]
    scan, cells = _scan_cells(rings, d, edge_m)
    covered = covered_cells(
        [c.chains for c in cells], scan.offsets, scan.u, scan.v_lo, scan.v_hi, d
    )
    return CellCover(heading, cells, scan, len(scan.u), covered)


def cover_screened(
    rings: list[tuple[FloatArray, FloatArray]],
    offsets: npt.NDArray[np.int64],
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    covered_m2: float,
    heading: float,
    d: float,
) -> CellCover:
    """:func:`cover_heading` from cells and lines decomposed and scanned at ``heading`` already.

    ``rings``, ``offsets``, ``u``, ``v_lo``, ``v_hi`` and ``covered_m2`` as the compiled
    screen made them, ``cover_heading``'s bit for bit
    (:func:`planner.heading_screen.screened_cells`); a NaN ``covered_m2`` (left unmeasured)
    is measured here.
    """
    scan = LineScan(np.zeros(len(rings)), offsets, u, v_lo, v_hi)
    cells = _cells(rings, offsets)
    covered = covered_m2
    if math.isnan(covered):
        covered = covered_cells([c.chains for c in cells], offsets, u, v_lo, v_hi, d)
    return CellCover(heading, cells, scan, len(u), covered)


def order_heading(
    cover: CellCover,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    *,
    excluded: npt.NDArray[np.bool_] | None = None,
) -> CellPlan:
    """Order :func:`cover_heading`'s cells (their variants, straight moves): its cheap plan.

    ``excluded`` (cells, 4): variants not to drive, unless a cell has no other
    (:func:`planner.parity_kernels.parity_choice`); they cost :data:`EXCLUDED_M` more.
    """
    scan, heading = cover.scan, cover.heading_deg
    aggregates = aggregate_scan(scan)
    lengths = combine_variants(aggregates, None, None)
    eu, ev, xu, xv = variant_ends(scan, aggregates)
    entry = np.stack(from_sweep(eu, ev, heading), axis=2)
    exit_ = np.stack(from_sweep(xu, xv, heading), axis=2)
    inner_m = lengths.turns
    if excluded is not None and excluded.any():
        inner_m = np.where(excluded, inner_m + EXCLUDED_M, inner_m)
    variants = CellVariants(entry, exit_, inner_m)
    working = float(lengths.working.sum())
    order = order_cells(variants, start_xy, finish_xy, improve=False)
    length = working + order_length(variants, order, start_xy, finish_xy, None)
    return CellPlan(
        heading,
        cover.cells,
        scan,
        variants,
        working,
        order,
        length,
        cover.line_count,
        cover.covered_m2,
    )


def _scan_cells(
    rings: list[tuple[FloatArray, FloatArray]], d: float, edge_m: float
) -> tuple[LineScan, list[Cell]]:
    """Scan the lines of ``rings`` (compiled) and split each into its chains.

    :func:`scan_cells_numpy` is the reference (``tests/planner/test_cell_kernels.py``).
    """
    # No rings, or an empty ring (the kernel would read its first vertex): numpy decides.
    if not rings or any(len(u) == 0 or len(v) != len(u) for u, v in rings):
        return scan_cells_numpy(rings, d, edge_m)
    from planner import cell_kernels  # numba: imported by the first plan that needs it

    u = np.concatenate([r[0] for r in rings])
    v = np.concatenate([r[1] for r in rings])
    sizes = np.array([len(r[0]) for r in rings], dtype=np.int64)
    offsets, line_u, v_lo, v_hi = cell_kernels.scan_rings(u, v, sizes, d, edge_m)
    scan = LineScan(np.zeros(len(rings)), offsets, line_u, v_lo, v_hi)
    return scan, _cells(rings, offsets)


def _cells(
    rings: list[tuple[FloatArray, FloatArray]], offsets: npt.NDArray[np.int64]
) -> list[Cell]:
    """Return each ring as a cell with its chains and its lines ``offsets[c]:offsets[c + 1]``."""
    lines = offsets.tolist()
    return [
        Cell(u_ring, v_ring, convex_chains(u_ring, v_ring), slice(lines[c], lines[c + 1]))
        for c, (u_ring, v_ring) in enumerate(rings)
    ]


def scan_cells_numpy(
    rings: list[tuple[FloatArray, FloatArray]], d: float, edge_m: float
) -> tuple[LineScan, list[Cell]]:
    """:func:`_scan_cells` in numpy: the reference for its compiled loops."""
    scan = scan_cells(rings, d, edge_m=edge_m)
    cells = [
        Cell(
            u_ring,
            v_ring,
            convex_chains_numpy(u_ring, v_ring),
            slice(scan.offsets[c], scan.offsets[c + 1]),
        )
        for c, (u_ring, v_ring) in enumerate(rings)
    ]
    return scan, cells


def reach_headland(plan: CellPlan, d: float) -> CellPlan:
    """Lengthen each line so that its whole footprint reaches the headland's inner edge.

    A line ends where it meets the cell's chain, but a slanted chain leaves an untilled
    triangle beside that end. With headland passes, every point within ``d / 2`` of the
    inner area lies in the headland band, inside the field; so each end moves out to the
    farthest the chain reaches across the footprint's width (``u ± d / 2``), and the
    footprint covers the inner area up to its edge. Turns and coverage follow the new ends.
    """
    scan = plan.scan
    v_lo, v_hi = scan.v_lo.copy(), scan.v_hi.copy()
    half = d / 2.0
    for cell in plan.cells:
        k = cell.lines
        u = scan.u[k]
        left = np.maximum(u - half, cell.chains.u_min)
        right = np.minimum(u + half, cell.chains.u_max)
        c = cell.chains
        top = np.maximum(np.interp(left, c.hi_u, c.hi_v), np.interp(right, c.hi_u, c.hi_v))
        bottom = np.minimum(np.interp(left, c.lo_u, c.lo_v), np.interp(right, c.lo_u, c.lo_v))
        for chain_u, chain_v, target, pick in (
            (c.hi_u, c.hi_v, top, np.maximum),
            (c.lo_u, c.lo_v, bottom, np.minimum),
        ):
            first = np.searchsorted(u, chain_u - half, side="left")
            stop = np.searchsorted(u, chain_u + half, side="right")
            for shift in range(3):
                line = first + shift
                ok = line < stop
                pick.at(target, line[ok], chain_v[ok])
        v_hi[k] = np.maximum(v_hi[k], top)
        v_lo[k] = np.minimum(v_lo[k], bottom)
    longer = LineScan(scan.headings_deg, scan.offsets, scan.u, v_lo, v_hi)
    return CellPlan(
        plan.heading_deg,
        plan.cells,
        longer,
        plan.variants,
        plan.working_m,
        plan.order,
        plan.length_m,
        plan.line_count,
        plan.covered_m2,
    )


def reorder(
    plan: CellPlan,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    move_m: MoveCost | None,
) -> CellPlan:
    """Return the winning heading with its cell order improved (by ``move_m`` if given)."""
    order = order_cells(plan.variants, start_xy, finish_xy, improve=True, move_m=move_m)
    length = plan.working_m + order_length(plan.variants, order, start_xy, finish_xy, move_m)
    before = plan.working_m + order_length(plan.variants, plan.order, start_xy, finish_xy, move_m)
    if length >= before:
        return plan
    return CellPlan(
        plan.heading_deg,
        plan.cells,
        plan.scan,
        plan.variants,
        plan.working_m,
        order,
        length,
        plan.line_count,
        plan.covered_m2,
    )


def order_length(
    cells: CellVariants,
    order: list[tuple[int, int]],
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    move_m: MoveCost | None,
) -> float:
    """Return the length of the cells in ``order``, the moves and the start and finish legs [m]."""
    total = sum(float(cells.inner_m[c, w]) for c, w in order)
    points = [cells.entry_xy[c, w] for c, w in order]
    if len(order) > 1:
        exits = np.asarray([cells.exit_xy[c, w] for c, w in order[:-1]])
        entries = np.asarray([cells.entry_xy[c, w] for c, w in order[1:]])
        if move_m is None:
            total += float(np.hypot(*(entries - exits).T).sum())
        else:
            total += float(np.trace(move_m(exits, entries)))
    if start_xy is not None:
        total += float(np.hypot(*(points[0] - np.asarray(start_xy))))
    if finish_xy is not None:
        c, w = order[-1]
        total += float(np.hypot(*(cells.exit_xy[c, w] - np.asarray(finish_xy))))
    return total
