"""The plan's lazy sequences behave as the tuples of their items."""

import pickle

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.types import PathSegment, PathSegments, Waypoint, Waypoints

ROLES = ("start", "line_start", "line_end", "turn", "headland", "finish")
KINDS = ("transit", "line", "turn", "headland", "round")
degrees = st.floats(-180, 180, allow_nan=False)


@st.composite
def waypoint_columns(draw: st.DrawFn) -> tuple[list, list, list, list]:
    n = draw(st.integers(0, 12))
    lon = draw(st.lists(degrees, min_size=n, max_size=n))
    lat = draw(st.lists(degrees, min_size=n, max_size=n))
    roles = draw(st.lists(st.sampled_from(ROLES), min_size=n, max_size=n))
    lines = draw(st.lists(st.none() | st.integers(0, 99), min_size=n, max_size=n))
    return lon, lat, roles, lines


@st.composite
def segment_columns(draw: st.DrawFn) -> tuple[list, list, list]:
    n = draw(st.integers(1, 12))
    lon = draw(st.lists(degrees, min_size=n, max_size=n))
    lat = draw(st.lists(degrees, min_size=n, max_size=n))
    bounds = []
    for _ in range(draw(st.integers(0, 6))):
        first = draw(st.integers(0, n - 1))
        last = draw(st.integers(first, n - 1))
        kind = draw(st.sampled_from(KINDS))
        bounds.append((kind, draw(st.none() | st.integers(0, 9)), first, last))
    return lon, lat, bounds


def check_like_tuple(lazy: object, items: tuple) -> None:
    assert isinstance(lazy, Waypoints | PathSegments)
    assert len(lazy) == len(items)
    assert tuple(lazy) == items
    assert lazy == items and lazy == list(items)
    assert hash(lazy) == hash(items)
    for i in range(-len(items), len(items)):
        assert lazy[i] == items[i]
    for index in (len(items), -len(items) - 1):
        with pytest.raises(IndexError):
            lazy[index]
    for start in range(-3, 4):
        for step in (1, 2, -1):
            assert lazy[start::step] == items[start::step]
    again = pickle.loads(pickle.dumps(lazy))
    assert type(again) is type(lazy) and again == lazy and tuple(again) == items
    if items:
        assert lazy != items[:-1]
        assert lazy != (*items[:-1], None)
    assert lazy != "not a sequence of items"


@settings(max_examples=60, deadline=None)
@given(columns=waypoint_columns())
def test_waypoints_are_their_tuple(columns: tuple[list, list, list, list]) -> None:
    lon, lat, roles, lines = columns
    items = tuple(Waypoint(i, lon[i], lat[i], roles[i], lines[i]) for i in range(len(lon)))
    check_like_tuple(Waypoints(lon, lat, roles, lines), items)


@settings(max_examples=60, deadline=None)
@given(columns=segment_columns())
def test_path_segments_are_their_tuple(columns: tuple[list, list, list]) -> None:
    lon, lat, bounds = columns
    items = tuple(
        PathSegment(kind, index, tuple(zip(lon[a : b + 1], lat[a : b + 1], strict=True)))
        for kind, index, a, b in bounds
    )
    check_like_tuple(PathSegments(lon, lat, bounds), items)


def test_segments_over_different_columns_compare_by_their_points() -> None:
    # Columns that differ only where no segment reads them make the same segments.
    a = PathSegments([1.0, 2.0, 9.0], [3.0, 4.0, 9.0], [("line", 0, 0, 1)])
    b = PathSegments([1.0, 2.0, 7.0], [3.0, 4.0, 7.0], [("line", 0, 0, 1)])
    assert a == b


def test_waypoint_columns_must_agree() -> None:
    with pytest.raises(ValueError, match="differ in length"):
        Waypoints([1.0], [2.0, 3.0], ["start"], [None])
