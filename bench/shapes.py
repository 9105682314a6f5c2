"""Fields that the benches and the tests both draw, and the brute force that judges headings.

Seeded random shapes (:func:`star_field`, :func:`random_convex_jobs`), a local shape put on
Earth (:func:`field_from_local`), the plans of one field at fixed headings
(:func:`fixed_heading_figures`) and the non-convex heading rule's cases
(:data:`NON_CONVEX_CASES`; the rule's measure is :mod:`bench.heading_rule`). They live here,
not in ``tests/``, so that a bench measures the very fields a test checks without importing
the tests; the tests import them from here (``tests/conftest.py``,
``tests/planner/random_fields.py`` and ``tests/planner/plan_checks.py`` pass them on).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely
import shapely.affinity
from shapely import Polygon

from planner import plan_coverage
from planner.errors import PlannerError
from planner.projection import local_frame

#: Bali, near the paper's trial field.
BALI = (115.298, -8.6265)

#: Cases of the non-convex heading rule (issue 9 item 5, R5), by name: (vertices, seed,
#: size [m], holes asked for, interval [m]) for :func:`star_field`. The first few of a seeded
#: draw that plan quickly, and two that a 25-field check of the search found 1.4 % and 4.3 %
#: longer than a fixed heading.
NON_CONVEX_CASES: dict[str, tuple[int, int, float, int, float]] = {
    "10-gon-2-holes": (10, 2212568278, 334.8615342348589, 2, 18.13),
    "9-gon-3-holes": (9, 1850753208, 230.22401567130785, 3, 12.41),
    "6-gon-1-hole": (6, 4255028923, 78.40930496557849, 1, 2.81),
    "8-gon-1-hole": (8, 1123361780, 251.0792911278842, 1, 8.62),
    "13-gon-was-1.4pct": (13, 4110225764, 202.1527627324664, 3, 11.82),
    "16-gon-was-4.3pct": (16, 401347228, 401.4893937441768, 1, 40.07),
}


def field_from_local(
    exterior_m: list[tuple[float, float]],
    holes_m: list[list[tuple[float, float]]] | None = None,
    *,
    at: tuple[float, float] = BALI,
) -> Polygon:
    """A WGS84 polygon whose local shape (metres, x east, y north) is given, centred ``at``."""
    frame = local_frame(*at)
    return frame.to_lonlat(Polygon(exterior_m, holes_m or []))


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


def fixed_heading_figures(
    field: Polygon, headings_deg: list[float], **options: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The field planned at each fixed heading: the headings planned, path lengths, coverages.

    The brute force that judges the heading search (R5, issue 9 item 5): heading [deg], path
    length [m] and coverage ratio; headings at which the vehicle cannot plan the field (too
    many lines, too narrow for it) are left out of all three arrays; a bug still raises.
    """
    planned, lengths, covers = [], [], []
    for heading in headings_deg:
        try:
            stats = plan_coverage(field, angle_deg=heading, **options).stats
        except PlannerError:
            continue
        planned.append(stats.angle_deg)
        lengths.append(stats.path_length_m)
        covers.append(stats.coverage_ratio)
    return np.asarray(planned), np.asarray(lengths), np.asarray(covers)
