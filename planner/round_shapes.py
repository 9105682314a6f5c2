"""The shapes of the spiral's rounds: regions whose boundary a vehicle of a turning radius drives.

:func:`regular_region` makes an offset of the field regular for the radius (convex corners
become arcs of it; inner corners and holes too tight for it are given a wide berth);
:func:`round_parts` takes off the spikes a pinch can leave; :func:`resample_ring` samples a
round evenly, as it is driven. Used by :mod:`planner.spiral`.
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np
import numpy.typing as npt
import shapely
from shapely import LinearRing, MultiPolygon, Polygon
from shapely.geometry.base import BaseGeometry

from planner.headlands import polygon_parts
from planner.turns import SAGITTA_M, STEP_M

FloatArray = npt.NDArray[np.float64]

#: Rounds and core parts smaller than this are dropped (slivers of the offsets) [m²].
SLIVER_M2 = 1e-6
#: Rounds are planned for a radius this much larger than the vehicle's, so that the polygonal
#: arcs of the buffers (and the rounding of exported coordinates) never bend tighter than it.
RADIUS_SLACK = 1.03
#: Buffers' segments per quarter circle: chords of a 3 m arc about 0.15 m long.
QUAD_SEGS = 32
#: Shortest step between the points of a round [m].
_MIN_STEP_M = 0.15
#: Sliver tolerance of the regularisation [m].
_EPS_M = 1e-3


def regular_region(
    region: Polygon | MultiPolygon, radius_m: float
) -> Polygon | MultiPolygon | shapely.Geometry:
    """Return a part of ``region`` whose boundary bends no tighter than ``radius_m``.

    The result ``S`` lies inside ``region`` and both ``S`` and its complement are unions of
    discs of radius ``radius_m``, so a vehicle with that turning radius can drive its boundary
    (convex corners become arcs of the radius; inner corners and holes too tight for it are
    given a wide berth). With ``C`` the complement of ``region``, the discs that fit in ``C``
    cover all of it but a residue (its sharp corners, its small pieces: the closing of
    ``region`` less ``region``); the residue grown by the radius is cut from ``region``, so the
    complement is a union of discs; the closing of the opening of what is left then keeps
    within it and is regular both ways.

    Parameters
    ----------
    region : Polygon or MultiPolygon
    radius_m : float
        Turning radius [m], > 0.

    Returns
    -------
    Geometry
        Possibly empty.

    Examples
    --------
    A 20 m square at 3 m: the corners become quarter circles of 3 m.

    >>> s = regular_region(shapely.box(0, 0, 20, 20), 3.0)
    >>> round(s.area), round(400 - (4 - math.pi) * 9)
    (392, 392)
    """
    r = float(radius_m)
    q = QUAD_SEGS
    closed = region.buffer(r, quad_segs=q).buffer(-r, quad_segs=q)
    residue = [
        p
        for p in shapely.get_parts(closed.difference(region.buffer(_EPS_M, quad_segs=q)))
        if p.area > SLIVER_M2
    ]
    kept: BaseGeometry = region
    if residue:
        kept = region.difference(shapely.union_all(residue).buffer(r + _EPS_M, quad_segs=q))
    return kept.buffer(-r, quad_segs=q).buffer(2.0 * r, quad_segs=q).buffer(-r, quad_segs=q)


def round_parts(region: Polygon | MultiPolygon, radius_m: float) -> list[Polygon]:
    """Return the parts of ``region`` whose rings a vehicle of radius ``radius_m`` drives.

    :func:`regular_region`'s closing can leave a spike where two discs of the complement
    nearly meet (a pinch narrower than the vehicle's turn: their arcs cross at a corner a few
    centimetres long). Where a ring, resampled as it is driven, bends tighter than the radius
    allows, an opening rounds the spikes off, within what the closing kept (so still inside
    ``region``): first only within two radii of the tight points, else everywhere (the pinch
    may then part the region). The opening makes corners of its own where two of its discs
    cross, so each is taken only if its rings then bend no tighter; if neither is, there is
    no round the vehicle can drive here and the result is empty (the rounds end there, and
    the core inside the last round is covered back and forth).
    """
    regular = regular_region(region, radius_m)
    parts = polygon_parts(regular)
    tight = [xy for p in parts for ring in _rings(p) for xy in _tight_points(ring, radius_m)]
    if not tight:
        return parts
    q = QUAD_SEGS
    eroded = shapely.buffer(regular, -radius_m, quad_segs=q)
    spikes = shapely.difference(regular, shapely.buffer(eroded, radius_m, quad_segs=q))
    near = shapely.buffer(shapely.multipoints(tight), 2.0 * radius_m, quad_segs=q)
    for cut in (shapely.intersection(spikes, near), spikes):
        opened = polygon_parts(cast(shapely.Geometry, shapely.difference(regular, cut)))
        if not any(_tight_points(ring, radius_m) for p in opened for ring in _rings(p)):
            return opened
    return []


def _rings(polygon: Polygon) -> list[LinearRing]:
    return [polygon.exterior, *polygon.interiors]


def round_step_m(radius_m: float) -> float:
    """Return the step between a round's points for a turning radius [m].

    Short enough that a chord of the tightest arc stays within :data:`SAGITTA_M` of it, and
    no shorter than 15 cm (a vehicle that tight turns on the spot).
    """
    return min(STEP_M, max(_MIN_STEP_M, 2.0 * math.sqrt(2.0 * radius_m * SAGITTA_M)))


def _tight_points(ring: LinearRing, radius_m: float) -> list[FloatArray]:
    """Points where ``ring``, resampled as it is driven, turns tighter than the vehicle may.

    ``radius_m`` is the planning radius (the vehicle's times :data:`RADIUS_SLACK`); the bound
    is the vehicle's own, so the polygonal arcs of the buffers pass. The ring's own vertices
    are looked at first (turn over the mean of the two edges, or the step if shorter): a ring
    whose every vertex bends no tighter is not resampled here.
    """
    limit = RADIUS_SLACK / radius_m
    step = round_step_m(radius_m)
    coords = np.asarray(ring.coords)[:-1]
    if len(coords) < 3 or _curvatures(coords, turning_step_m=step).max() <= limit:
        return []
    points = resample_ring(ring, step)
    return list(points[_curvatures(points) > limit])


def _curvatures(points: FloatArray, *, turning_step_m: float | None = None) -> FloatArray:
    """Curvature [1/m] at each point of a closed polyline (not closed in ``points``).

    With ``turning_step_m``, the turn at each vertex over the mean length of its two edges,
    or that step if shorter (a bound for points resampled that far apart); else that of the
    circle through each three points.
    """
    a, b, c = np.roll(points, 1, axis=0), points, np.roll(points, -1, axis=0)
    ab, bc = b - a, c - b
    cross = ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0]
    dot = np.einsum("ij,ij->i", ab, bc)
    l1, l2 = np.hypot(*ab.T), np.hypot(*bc.T)
    if turning_step_m is not None:
        spread = np.minimum((l1 + l2) / 2.0, turning_step_m)
        curvature = np.abs(np.arctan2(cross, dot)) / np.maximum(spread, 1e-300)
    else:
        curvature = 2.0 * np.abs(cross) / np.maximum(l1 * l2 * np.hypot(*(c - a).T), 1e-300)
    return np.asarray(curvature, dtype=float)


def resample_ring(ring: LinearRing, step_m: float) -> FloatArray:
    """Return points evenly along a closed ring, at most ``step_m`` apart; not closed.

    Even steps keep the three-point curvature of the buffers' polygonal arcs at their radius.
    """
    coords = np.asarray(ring.coords, dtype=float)
    # Distance along the ring at each vertex. GEOS's ``line_interpolate_point`` walks the
    # ring from its start for every point (4.5 s of a 16 ha field's 12 s spiral); one
    # searchsorted over the cumulative lengths is linear.
    at_vertex = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(coords, axis=0).T))))
    length = float(at_vertex[-1])
    if length <= 0.0:
        return coords[:1]
    n = max(3, math.ceil(length / step_m - 1e-9))
    along = np.arange(n) * (length / n)
    edge = np.clip(np.searchsorted(at_vertex, along, side="right") - 1, 0, len(coords) - 2)
    edge_m = at_vertex[edge + 1] - at_vertex[edge]
    share = np.divide(
        along - at_vertex[edge], edge_m, out=np.zeros_like(along), where=edge_m > 0.0
    )[:, None]
    return np.asarray(coords[edge] + share * (coords[edge + 1] - coords[edge]), dtype=float)
