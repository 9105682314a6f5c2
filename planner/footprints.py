"""What the fitted lines cover (R4): their footprints and the area of the field under them."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import numpy.typing as npt
import shapely
from shapely import MultiPolygon, Polygon

from planner.cell_plans import CellPlan
from planner.coverage import covered_area
from planner.line_ends import FittedLines
from planner.lines import from_sweep

#: Grid that footprint unions snap to [m] (see :func:`planner.general.plan_general`).
UNION_GRID_M = 1e-6

FloatArray = npt.NDArray[np.float64]


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
    till a strip of it, which is added with shapely (two boxes per cell). The corners of
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
    total = 0.0
    outer: list[FittedLines] = []
    for (cell_index, _), fit in zip(plan.order, fitted, strict=True):
        if len(fit.u) == 0:
            continue
        cell = plan.cells[cell_index]
        order = np.argsort(fit.u, kind="stable")
        u, a, b = fit.u[order], fit.v_start[order], fit.v_end[order]
        total += covered_area(cell.chains, u, np.minimum(a, b), np.maximum(a, b), width_m)
        ends = order[[0, -1]]
        outer.append(replace(fit, u=fit.u[ends], v_start=fit.v_start[ends], v_end=fit.v_end[ends]))
    boxes = np.asarray(line_footprints(outer, heading, width_m))
    band = 0.0
    if len(boxes):
        shapely.prepare(area)
        out = boxes[~shapely.contains(area, boxes)]
        if len(out):
            reach = union_boxes(out)
            band = float(
                shapely.intersection(field_local, reach).area
                - shapely.intersection(area, reach).area
            )
    return total, band


def union_boxes(boxes: npt.NDArray[np.object_]) -> shapely.Geometry:
    """Union of footprint boxes: exact overlay, snapped to :data:`UNION_GRID_M` if that fails.

    A handful of rectangles unite robustly without a precision grid, five times faster; the
    snapped overlay is the fallback for the near-degenerate case GEOS refuses.
    """
    try:
        united: shapely.Geometry = shapely.union_all(boxes)
    except shapely.errors.GEOSException:
        united = shapely.union_all(boxes, grid_size=UNION_GRID_M)
    return united


def line_footprints(fitted: list[FittedLines], heading: float, width_m: float) -> list[Polygon]:
    """Footprints of the fitted lines (R4): rectangles ``width_m`` wide, flat ends, local."""
    if not fitted:
        return []
    u = np.concatenate([f.u for f in fitted])
    a = np.concatenate([f.v_start for f in fitted])
    b = np.concatenate([f.v_end for f in fitted])
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    half = width_m / 2.0
    cu = np.stack([u - half, u + half, u + half, u - half], axis=1)
    cv = np.stack([lo, lo, hi, hi], axis=1)
    x, y = from_sweep(cu, cv, heading)
    boxes = np.asarray(shapely.polygons(np.stack([x, y], axis=2)))
    return list(boxes[hi > lo])
