"""What the fitted lines cover (R4): their footprints and the area of the field under them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import shapely
from shapely import MultiPolygon, Polygon

from planner.band_kernels import boxes_over_rings_m2
from planner.cell_plans import CellPlan
from planner.coverage import Chains, covered_cells
from planner.line_ends import FittedLines
from planner.lines import from_sweep, to_sweep

#: Grid that footprint unions snap to [m] (see :func:`planner.general.plan_general`).
UNION_GRID_M = 1e-6

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def lines_covered(
    plan: CellPlan | None,
    fitted: list[FittedLines],
    field_local: Polygon,
    area: Polygon | MultiPolygon,
    heading: float,
    width_m: float,
) -> float:
    """Area of the field the lines' footprints cover (R4) [m²].

    Inside each cell (a piece of the machine area) exactly, by its chains. Beyond the cells
    lies the band half a vehicle wide along the boundary: the outermost line of a cell may
    till a strip of it, which is added by :func:`band_m2` (two boxes per cell). The corners of
    footprints that poke past a slanted line end are not counted (a slight underestimate).
    """
    cells_m2, band_m2 = cells_and_band_m2(plan, fitted, field_local, area, heading, width_m)
    return cells_m2 + band_m2


def cells_and_band_m2(
    plan: CellPlan | None,
    fitted: list[FittedLines],
    field_local: Polygon,
    area: Polygon | MultiPolygon,
    heading: float,
    width_m: float,
) -> tuple[float, float]:
    """:func:`lines_covered` in its two parts: inside the cells, and in the band beyond [m²]."""
    if plan is None or not fitted:
        return 0.0, 0.0
    lines = cell_lines(plan, fitted)
    if not len(lines.u):
        return 0.0, 0.0
    total = lines_in_cells_m2(lines, width_m)
    # Only a cell's outermost lines can reach past it into the band.
    ends = np.stack([lines.offsets[:-1], lines.offsets[1:] - 1], axis=1).ravel()
    band = band_m2(
        lines.u[ends], lines.v_lo[ends], lines.v_hi[ends], field_local, area, heading, width_m
    )
    return total, band


def band_m2(
    u: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    field_local: Polygon | MultiPolygon,
    area: Polygon | MultiPolygon,
    heading: float,
    width_m: float,
) -> float:
    """Area the footprints of lines ``u, [lo, hi]`` (sweep frame) cover beyond ``area`` [m²].

    That is, of the union of their boxes (:func:`footprint_boxes`), the part inside
    ``field_local`` less the part inside ``area``. The boxes are aligned with the sweep
    frame, so this is measured there without an overlay (:mod:`planner.band_kernels`).
    """
    half = width_m / 2.0
    keep = hi > lo
    if not keep.any() or not half > 0.0:
        return 0.0
    parts, polygon = shapely.get_parts([field_local, area], return_index=True)
    rings, part = shapely.get_rings(parts, return_index=True)
    xy, ring = shapely.get_coordinates(rings, return_index=True)
    ends = np.searchsorted(ring, np.arange(len(rings)), side="right").astype(np.int64)
    exterior = np.concatenate([[True], part[1:] != part[:-1]])
    signs = np.where(exterior, 1.0, -1.0) * np.where(polygon[part] == 0, 1.0, -1.0)
    u = u[keep]
    if len(u) * len(xy) > BAND_KERNEL_MAX_WORK:
        boxes = footprint_boxes(u, lo[keep], hi[keep], heading, width_m)
        return _band_by_overlay(boxes, field_local, area)
    ring_u, ring_v = to_sweep(xy[:, 0], xy[:, 1], heading)
    return float(
        boxes_over_rings_m2(u - half, u + half, lo[keep], hi[keep], ring_u, ring_v, ends, signs)
    )


#: Boxes times ring vertices beyond which the band is measured by shapely's overlay: the
#: kernel visits every ring edge for every rectangle (a 1,999-vertex wavy boundary's band
#: took it 1.3 s, the overlay about 0.2 s); on the real fields it is 4 times faster.
BAND_KERNEL_MAX_WORK = 200_000


def _band_by_overlay(
    boxes: npt.NDArray[np.object_],
    field_local: Polygon | MultiPolygon,
    area: Polygon | MultiPolygon,
) -> float:
    """:func:`band_m2` by shapely: the ``boxes``' union, inside the field less inside ``area``."""
    shapely.prepare(area)
    out = boxes[~shapely.contains(area, boxes)]
    if not len(out):
        return 0.0
    try:
        reach = shapely.union_all(out)
    except shapely.errors.GEOSException:  # near-degenerate boxes GEOS refuses unsnapped
        reach = shapely.union_all(out, grid_size=UNION_GRID_M)
    return float(
        shapely.intersection(field_local, reach).area - shapely.intersection(area, reach).area
    )


@dataclass(frozen=True, slots=True)
class CellLines:
    """The fitted lines of a plan's cells that have any, each cell's left to right.

    Attributes
    ----------
    chains : list of Chains
        The cells, in driving order.
    offsets : ndarray of int
        Cell ``c`` has the lines ``offsets[c]:offsets[c + 1]``.
    u, v_lo, v_hi : ndarray
        The lines, sweep frame [m].
    """

    chains: list[Chains]
    offsets: IntArray
    u: FloatArray
    v_lo: FloatArray
    v_hi: FloatArray


def cell_lines(plan: CellPlan, fitted: list[FittedLines]) -> CellLines:
    """Gather ``fitted`` (one entry per cell of ``plan.order``) cell by cell, left to right."""
    chains: list[Chains] = []
    parts: list[FittedLines] = []
    orders: list[IntArray] = []
    for (cell_index, _), fit in zip(plan.order, fitted, strict=True):
        if len(fit.u):
            chains.append(plan.cells[cell_index].chains)
            parts.append(fit)
            orders.append(np.argsort(fit.u, kind="stable"))
    if not parts:
        empty = np.zeros(0)
        return CellLines([], np.zeros(1, dtype=np.int64), empty, empty, empty)
    counts = np.array([len(f.u) for f in parts], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    u = np.concatenate([f.u[o] for f, o in zip(parts, orders, strict=True)])
    a = np.concatenate([f.v_start[o] for f, o in zip(parts, orders, strict=True)])
    b = np.concatenate([f.v_end[o] for f, o in zip(parts, orders, strict=True)])
    return CellLines(chains, offsets, u, np.minimum(a, b), np.maximum(a, b))


def lines_in_cells_m2(lines: CellLines, width_m: float) -> float:
    """Area of the cells that ``lines``' footprints ``width_m`` wide cover [m²].

    All cells in one pass (:func:`planner.coverage.covered_cells`): the sum of
    :func:`planner.coverage.covered_area` over the cells.
    """
    return covered_cells(lines.chains, lines.offsets, lines.u, lines.v_lo, lines.v_hi, width_m)


def line_footprints(fitted: list[FittedLines], heading: float, width_m: float) -> list[Polygon]:
    """Footprints of the fitted lines (R4): rectangles ``width_m`` wide, flat ends, local."""
    if not fitted:
        return []
    u = np.concatenate([f.u for f in fitted])
    a = np.concatenate([f.v_start for f in fitted])
    b = np.concatenate([f.v_end for f in fitted])
    return list(footprint_boxes(u, np.minimum(a, b), np.maximum(a, b), heading, width_m))


def footprint_boxes(
    u: FloatArray, lo: FloatArray, hi: FloatArray, heading: float, width_m: float
) -> npt.NDArray[np.object_]:
    """Footprints of lines ``u, [lo, hi]`` (sweep frame) as local boxes; empty lines left out."""
    half = width_m / 2.0
    cu = np.stack([u - half, u + half, u + half, u - half], axis=1)
    cv = np.stack([lo, lo, hi, hi], axis=1)
    x, y = from_sweep(cu, cv, heading)
    boxes = np.asarray(shapely.polygons(np.stack([x, y], axis=2)))
    return boxes[hi > lo]
