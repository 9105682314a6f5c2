"""Cheap heading scores (closed forms per edge) equal line-by-line intersection with shapely."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely import LineString, Polygon

from planner.heading_search import score_headings
from planner.lines import from_sweep, to_sweep
from tests.planner.random_fields import fields_with_holes

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def reference(field: Polygon, heading: float, d: float) -> tuple[float, int]:
    """Lines d apart from d/2 inside the field's extent, cut by shapely: length and pieces."""
    xy = shapely.get_coordinates(field)
    u, v = to_sweep(xy[:, 0], xy[:, 1], heading)
    total, pieces = 0.0, 0
    at = u.min() + d / 2.0
    while at < u.max():
        a = from_sweep(at, v.min() - 1.0, heading)
        b = from_sweep(at, v.max() + 1.0, heading)
        cut = field.intersection(LineString([a, b]))
        parts = [p for p in shapely.get_parts(cut) if p.length > 0]
        total += sum(p.length for p in parts)
        pieces += len(parts)
        at += d
    return total, pieces


@SETTINGS
@given(field=fields_with_holes(), heading=st.floats(0.0, 179.999), frac=st.floats(0.01, 0.2))
def test_scores_equal_shapely_line_by_line(field: Polygon, heading: float, frac: float) -> None:
    d = frac * np.sqrt(field.area)
    scores = score_headings([field], np.array([heading]), d)
    length, pieces = reference(field, heading, d)
    assert scores.working_m[0] == pytest.approx(length, rel=1e-6, abs=1e-6)
    # A line through a vertex exactly may count a touching piece differently; else equal.
    assert abs(int(scores.pieces[0]) - pieces) <= 1


def test_turn_backs_count_the_ends_and_each_split() -> None:
    ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    scores = score_headings([ell], np.array([0.0, 135.0]), 4.0)
    # North-south: only the two ends. North-west: the inner corner splits the sweep, and
    # the two arms end separately.
    assert scores.turn_backs.tolist() == [2, 4]
    estimate = scores.path_estimate_m(4.0)
    assert estimate[0] < estimate[1]
