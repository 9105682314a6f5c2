"""Random simple non-convex polygons with holes, in local metres, for property tests."""

from __future__ import annotations

import math

import numpy as np
import shapely
from hypothesis import strategies as st
from shapely import Polygon


def star_field(n: int, seed: int, size_m: float, holes: int) -> Polygon:
    """A star-shaped (so simple), usually non-convex polygon with up to ``holes`` holes.

    ``n`` vertices at random angles and radii ``size_m`` × 0.35–1 about the origin; each
    hole a random 3–7-gon, kept where it lies 1 m inside the field and 1 m from the others.
    Deterministic in its arguments: the property tests draw them, fixed-case tests name them.
    """
    rng = np.random.default_rng(seed)
    angles = np.sort(rng.uniform(0.0, 2.0 * math.pi, n))
    # Spread the angles so no two vertices coincide and the star stays simple.
    angles = np.unique(np.round(angles, 6))
    if len(angles) < 3:
        angles = np.array([0.0, 2.1, 4.2])
    radii = size_m * rng.uniform(0.35, 1.0, len(angles))
    exterior = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
    field = shapely.orient_polygons(Polygon(exterior))
    if not field.is_valid or field.area < 1.0:
        field = shapely.box(-size_m, -size_m / 2, size_m, size_m / 2)
    kept: list[Polygon] = []
    for _ in range(holes):
        k = int(rng.integers(3, 8))
        r = size_m * rng.uniform(0.04, 0.15)
        a = np.sort(rng.uniform(0.0, 2.0 * math.pi, k))
        centre = rng.uniform(-size_m * 0.5, size_m * 0.5, 2)
        hole = Polygon(centre + np.stack([r * np.cos(a), r * np.sin(a)], axis=1))
        if not hole.is_valid or hole.area < 1.0:
            continue
        room = field.buffer(-1.0)
        if room.contains(hole) and all(hole.distance(h) > 1.0 for h in kept):
            kept.append(hole)
    if kept:
        field = Polygon(field.exterior, [h.exterior for h in kept])
    field = shapely.orient_polygons(field)
    assert field.is_valid
    return field  # type: ignore[no-any-return]


@st.composite
def fields_with_holes(
    draw: st.DrawFn, *, min_vertices: int = 3, max_vertices: int = 40, max_holes: int = 3
) -> Polygon:
    """A star-shaped (so simple), usually non-convex polygon of 0.2–20 ha with 0–3 holes."""
    n = draw(st.integers(min_vertices, max_vertices))
    seed = draw(st.integers(0, 2**32 - 1))
    size_m = 10 ** draw(st.floats(math.log10(50.0), math.log10(500.0)))
    return star_field(n, seed, size_m, draw(st.integers(0, max_holes)))


def random_convex_jobs(
    count: int,
    *,
    seed: int = 9,
    min_area_m2: float = 2e3,
    max_area_m2: float = 2e5,
    min_lines: float = 8.0,
) -> list[tuple[Polygon, float, tuple[float, float] | None, tuple[float, float] | None]]:
    """A fixed set of random convex fields (WGS84) with an interval, a start and a finish.

    The same draw as ``tests.planner.test_pipeline.convex_fields`` (3–16 hull points, any
    aspect and rotation, anywhere on Earth), but from a seeded generator, so that a bench can
    measure the same fields every time; areas ``min_area_m2`` to ``max_area_m2``, intervals
    such that a field has some ``min_lines`` to 100 lines across.
    """
    from planner.projection import local_frame  # the planner is only needed here

    rng = np.random.default_rng(seed)
    jobs = []
    for _ in range(count):
        lon, lat = float(rng.uniform(-179.0, 179.0)), float(rng.uniform(-70.0, 70.0))
        area = 10 ** float(rng.uniform(math.log10(min_area_m2), math.log10(max_area_m2)))
        n = int(rng.integers(3, 17))
        aspect = float(rng.uniform(0.1, 1.0))
        hull = shapely.MultiPoint(rng.uniform(-1, 1, (n, 2)) * [1.0, aspect]).convex_hull
        if hull.geom_type != "Polygon" or hull.area < 1e-3:
            hull = shapely.box(-1, -aspect, 1, aspect)
        hull = shapely.affinity.scale(hull, *(2 * [math.sqrt(area / hull.area)]))
        hull = shapely.affinity.rotate(hull, float(rng.uniform(0.0, 360.0)))
        side = math.sqrt(area)
        interval = float(rng.uniform(max(0.5, side / 100.0), max(0.5, side / min_lines)))
        frame = local_frame(lon, lat)
        field = frame.to_lonlat(Polygon(hull.exterior.coords))
        reach = side + 200.0
        start, finish = _maybe_point(rng, frame, reach), _maybe_point(rng, frame, reach)
        jobs.append((field, interval, start, finish))
    return jobs


def _maybe_point(rng: np.random.Generator, frame: object, reach_m: float) -> tuple | None:
    """Half the time None, else a point within ``reach_m`` of the origin, WGS84."""
    if rng.random() < 0.5:
        return None
    x, y = rng.uniform(-reach_m, reach_m, 2)
    plon, plat = frame.to_lonlat_xy(float(x), float(y))  # type: ignore[attr-defined]
    return float(plon), float(plat)
