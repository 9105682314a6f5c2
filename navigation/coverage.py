"""What a track's implement tilled: the coverage ratio, and the ground it missed.

The footprint is the track swept by the implement, ``implement_width_m`` wide (the plan's
``implement_width_m`` when it has one, else its interval). :func:`coverage_ratio` computes it on
a raster (cells of at most ``width / 8``, finer for small fields) as every cell whose centre lies
within ``width / 2`` of the track: the same as buffering the track with round joins, except at
the track's two very ends (round here, flat in a buffer with flat caps), which usually lie
outside the field at the start and finish points. :func:`missed_ground` traces the field left
outside the footprint on the same raster into polygons (product.md §8).
"""

from __future__ import annotations

import math
from typing import cast

import contourpy
import numpy as np
import numpy.typing as npt
import shapely
from scipy import ndimage  # type: ignore[import-untyped]

from navigation.route import distance_along
from planner.projection import LocalFrame
from planner.types import CoveragePlan

FloatArray = npt.NDArray[np.float64]

#: Raster cells for the footprint: aimed at, and never more than (memory and time).
TARGET_RASTER_CELLS = 250_000
MAX_RASTER_CELLS = 4_000_000
#: Cells are at most this fraction of the implement width.
RASTER_CELLS_PER_INTERVAL = 8
#: Track samples marked on the raster at a time (bounded temporaries).
CHUNK_SAMPLES = 65_536


def implement_width_m(plan: CoveragePlan) -> float:
    """Return the width one pass tills [m]: the plan's ``implement_width_m``, else its interval.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> implement_width_m(SimpleNamespace(interval_m=4.0))
    4.0
    >>> implement_width_m(SimpleNamespace(interval_m=4.0, implement_width_m=0.8))
    0.8
    """
    width = getattr(plan, "implement_width_m", None)
    return float(width) if width else float(plan.interval_m)


def _grid(
    field: shapely.Polygon, width_m: float
) -> tuple[float, float, float, int, int, npt.NDArray[np.bool_]]:
    half = 0.5 * width_m
    min_x, min_y, max_x, max_y = field.bounds
    min_x -= half
    min_y -= half
    max_x += half
    max_y += half
    area = (max_x - min_x) * (max_y - min_y)
    cell = min(
        width_m / RASTER_CELLS_PER_INTERVAL, max(math.sqrt(area / TARGET_RASTER_CELLS), 0.005)
    )
    cell = max(cell, math.sqrt(area / MAX_RASTER_CELLS))
    nx = int(math.ceil((max_x - min_x) / cell))
    ny = int(math.ceil((max_y - min_y) / cell))
    return min_x, min_y, cell, nx, ny, polygon_mask(field, min_x, min_y, cell, nx, ny)


def _swept(
    x_m: FloatArray,
    y_m: FloatArray,
    min_x: float,
    min_y: float,
    cell: float,
    nx: int,
    ny: int,
    half: float,
) -> npt.NDArray[np.bool_]:
    """Cells within ``half`` of the polyline (densified to half a cell, then a distance map).

    The samples are made and marked :data:`CHUNK_SAMPLES` at a time, so a day's log needs the
    distance along the track and the raster, not several arrays of its length.
    """
    s = distance_along(x_m, y_m)
    total = float(s[-1])
    count = max(int(total / (0.5 * cell)) + 2, len(x_m))
    free = np.ones((ny, nx), dtype=bool)
    marked = False
    for start in range(0, count, CHUNK_SAMPLES):
        stop = min(start + CHUNK_SAMPLES, count)
        if total > 0:
            # np.linspace(0, total, count)[start:stop], made a block at a time.
            samples = np.arange(start, stop) * (total / (count - 1))
            if stop == count:
                samples[-1] = total
            px = np.interp(samples, s, x_m)
            py = np.interp(samples, s, y_m)
        else:
            px, py = x_m[start:stop], y_m[start:stop]
        ix = np.floor((px - min_x) / cell).astype(np.int64)
        iy = np.floor((py - min_y) / cell).astype(np.int64)
        keep = (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny)
        if keep.any():
            free[iy[keep], ix[keep]] = False
            marked = True
    if not marked:
        return np.zeros((ny, nx), dtype=bool)
    dist = ndimage.distance_transform_edt(free, sampling=cell)
    return np.asarray(dist <= half)


def coverage_ratio(
    frame: LocalFrame,
    plan: CoveragePlan,
    x_m: FloatArray,
    y_m: FloatArray,
    *,
    reference: tuple[FloatArray, FloatArray] | None = None,
) -> float:
    """Share of the field within ``implement_width / 2`` of the track (raster, see module doc).

    Parameters
    ----------
    frame : LocalFrame
    plan : CoveragePlan
    x_m, y_m : arrays
        The track, local frame [m].
    reference : (array, array) or None
        A polyline (the part of the plan driven so far) whose footprint replaces the field as
        the denominator: the share of what that part would till that the track tilled.
    """
    field = frame.to_local(plan.field_lonlat)
    width = implement_width_m(plan)
    min_x, min_y, cell, nx, ny, in_field = _grid(field, width)
    covered = _swept(x_m, y_m, min_x, min_y, cell, nx, ny, 0.5 * width) & in_field
    if reference is not None:
        in_field = in_field & _swept(*reference, min_x, min_y, cell, nx, ny, 0.5 * width)
    n_field = int(in_field.sum())
    if n_field == 0:
        return 0.0
    return float((covered & in_field).sum() / n_field)


def polygon_mask(
    polygon: shapely.Polygon, min_x: float, min_y: float, cell: float, nx: int, ny: int
) -> npt.NDArray[np.bool_]:
    """Cells of an ``ny × nx`` grid whose centres lie inside ``polygon`` (scanline, even-odd).

    Each row's centre line crosses the polygon's edges (holes included) at sorted x; the
    centres between the first and second crossing, the third and fourth, … are inside.
    """
    rings = [polygon.exterior, *polygon.interiors]
    coords = [np.asarray(r.coords) for r in rings]
    x1 = np.concatenate([c[:-1, 0] for c in coords])
    y1 = np.concatenate([c[:-1, 1] for c in coords])
    x2 = np.concatenate([c[1:, 0] for c in coords])
    y2 = np.concatenate([c[1:, 1] for c in coords])
    cy = min_y + (np.arange(ny) + 0.5) * cell
    row_idx, edge_idx = np.nonzero((y1[None, :] <= cy[:, None]) != (y2[None, :] <= cy[:, None]))
    yr = cy[row_idx]
    xe1, ye1, xe2, ye2 = x1[edge_idx], y1[edge_idx], x2[edge_idx], y2[edge_idx]
    xc = xe1 + (yr - ye1) * (xe2 - xe1) / (ye2 - ye1)
    order = np.lexsort((xc, row_idx))
    rows = row_idx[order]
    # First column whose centre is right of the crossing.
    cols = np.clip(np.ceil((xc[order] - min_x) / cell - 0.5), 0, nx).astype(np.int64)
    diff = np.zeros((ny, nx + 1), dtype=np.int32)
    sign = np.where(np.arange(len(rows)) % 2 == 0, 1, -1)
    np.add.at(diff, (rows, cols), sign)
    return np.cumsum(diff[:, :nx], axis=1) > 0


def missed_ground(
    frame: LocalFrame,
    plan: CoveragePlan,
    x_m: FloatArray,
    y_m: FloatArray,
    *,
    min_width_m: float | None = None,
    min_area_m2: float = 1.0,
) -> list[shapely.Polygon]:
    """Return the parts of the field the track's footprint missed, as local polygons.

    The footprint is the raster of :func:`coverage_ratio` (cells of ``width / 8`` or finer):
    the field's cells farther than half the implement width from the track are the gaps.
    Slivers narrower than ``min_width_m`` (default a tenth of the implement width: the ragged
    edge a wandering track leaves) are opened away, the cells traced into polygons (contourpy's
    filled contours at the half level, so edges lie within a cell of the raster's), clipped to
    the field, and pieces under ``min_area_m2`` dropped: what remains is ground worth going
    back for. A 6-hour 10 Hz log takes a fraction of a second.

    Parameters
    ----------
    frame : LocalFrame
    plan : CoveragePlan
    x_m, y_m : arrays
        The track, local frame [m].
    min_width_m : float or None
        Gaps narrower than this are ignored [m].
    min_area_m2 : float
        Gaps smaller than this are ignored [m²].

    Returns
    -------
    list of Polygon
        Largest first, local frame.
    """
    field = frame.to_local(plan.field_lonlat)
    width = implement_width_m(plan)
    min_width = 0.1 * width if min_width_m is None else min_width_m
    min_x, min_y, cell, nx, ny, in_field = _grid(field, width)
    gap = in_field & ~_swept(x_m, y_m, min_x, min_y, cell, nx, ny, 0.5 * width)
    radius = int(round(0.5 * min_width / cell))
    if radius >= 1:
        disc = ndimage.iterate_structure(ndimage.generate_binary_structure(2, 1), radius)
        gap = ndimage.binary_opening(gap, structure=disc)
    if not gap.any():
        return []
    # Pad by one empty cell so every gap is closed; contour lines run through cell centres.
    z = np.pad(gap.astype(np.float64), 1)
    xs = min_x + (np.arange(nx + 2) - 0.5) * cell
    ys = min_y + (np.arange(ny + 2) - 0.5) * cell
    generator = contourpy.contour_generator(
        xs, ys, z, fill_type=contourpy.FillType.OuterOffset, corner_mask=False
    )
    filled = generator.filled(0.5, 1.5)  # OuterOffset: (points, offsets) per outer ring
    points = cast("list[FloatArray]", filled[0])
    offsets = cast("list[npt.NDArray[np.uint32]]", filled[1])
    polygons = []
    for pts, offs in zip(points, offsets, strict=True):
        rings = [pts[int(a) : int(b)] for a, b in zip(offs[:-1], offs[1:], strict=True)]
        polygon = shapely.Polygon(rings[0], rings[1:]).buffer(0)
        polygons.append(polygon)
    # Within a cell of the raster's edge: the traced staircase becomes straight edges, so a
    # gap has the few vertices a planner wants, not one per cell.
    gaps = shapely.union_all(polygons).simplify(cell).intersection(field)
    parts = [
        g
        for g in getattr(gaps, "geoms", [gaps])
        if isinstance(g, shapely.Polygon) and not g.is_empty and g.area >= min_area_m2
    ]
    return sorted(parts, key=lambda g: -g.area)
