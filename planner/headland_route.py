"""Headland passes driven: each round entered where it is nearest, moves routed inside."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import shapely
from shapely import LinearRing

from planner.route_builder import RouteBuilder
from planner.routing import FieldRouter

FloatArray = npt.NDArray[np.float64]


def first_ring_point(rings: list[LinearRing]) -> tuple[float, float]:
    """Return the first point of a pass's first ring: where the lines hand over."""
    x0, y0 = rings[0].coords[0]
    return float(x0), float(y0)


def ring_order(rings: list[LinearRing], here: tuple[float, float] | None) -> list[LinearRing]:
    """Rings of one pass, nearest first from ``here`` (given order if None)."""
    left = list(rings)
    ordered = []
    while left:
        if here is None:
            ring = left.pop(0)
        else:
            point = shapely.Point(here)
            k = min(range(len(left)), key=lambda i: left[i].distance(point))
            ring = left.pop(k)
        ordered.append(ring)
        entry = ring_entry(ring, here)
        here = entry
    return ordered


def ring_entry(ring: LinearRing, from_xy: tuple[float, float] | None) -> tuple[float, float]:
    """Return the point of ``ring`` nearest ``from_xy`` (its first point if None)."""
    if from_xy is None:
        x0, y0 = ring.coords[0]
        return float(x0), float(y0)
    point = ring.interpolate(ring.project(shapely.Point(from_xy)))
    return float(point.x), float(point.y)


def add_headland(
    route: RouteBuilder,
    ring: LinearRing,
    pass_index: int,
    router: FieldRouter,
    *,
    end_near: tuple[float, float] | None = None,
) -> None:
    """Drive ``ring`` once round, entering where it is nearest the tractor.

    With ``end_near``, the round goes on along the ring to its point nearest ``end_near``.
    """
    here = route.here()
    entry = ring_entry(ring, here)
    coords = np.asarray(ring.coords)[:-1]
    distance_along = shapely.line_locate_point(ring, shapely.points(coords))
    at = float(ring.project(shapely.Point(entry)))
    ahead = np.asarray((distance_along - at) % ring.length, dtype=float)
    order = np.argsort(ahead, kind="stable")
    points: list[tuple[float, float]] = [
        entry,
        *[(float(c[0]), float(c[1])) for c in coords[order] if np.hypot(*(c - entry)) > 1e-9],
        entry,
    ]
    if end_near is not None:
        exit_at = float(ring.project(shapely.Point(end_near)))
        further = (exit_at - at) % ring.length
        exit_point = ring.interpolate(exit_at)
        points += [
            (float(coords[i, 0]), float(coords[i, 1]))
            for i in order
            if 1e-9 < ahead[i] < further - 1e-9
        ]
        if further > 1e-9:
            points.append((float(exit_point.x), float(exit_point.y)))
    loop = np.asarray(points)
    if here is not None:
        if route.roles[-1] == "start":
            route.append("transit", None, np.asarray([here, entry]), "headland")
        else:
            route.append("turn", None, router.path(here, entry), "turn", last_role="headland")
    route.append("headland", pass_index, loop, "headland")
