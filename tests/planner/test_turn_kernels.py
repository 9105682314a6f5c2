"""The one-call turns of a forward-only vehicle (planner.turn_kernels) equal the numpy path.

:func:`planner.turns.vehicle_turns` plans a forward-only vehicle's turns in one compiled call;
the reference is the path it replaced: ``_vehicle_turns`` (wide turns and bulbs apart, then
merged) on each distinct shape from the origin, moved onto its ends by
:func:`planner.turn_references.translate_numpy`. Every point and figure must be the same to
the last bit, or the plans would change.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner import turn_references, turns
from planner.turns import STEP_M, TurnCurves, TurnEnds
from planner.vehicles import resolve_vehicle


def _reference(ends: TurnEnds, vehicle_name: str) -> TurnCurves:
    """Each turn's shape planned from the origin in numpy's steps, then moved onto its ends."""
    vehicle = resolve_vehicle(vehicle_name)
    zero = np.zeros(len(ends))
    dx, dy = ends.x1 - ends.x0, ends.y1 - ends.y0
    relative = TurnEnds(zero, zero, ends.yaw0, dx, dy, ends.yaw1)
    shapes = turns._vehicle_turns(relative, vehicle, STEP_M)
    return turn_references.translate_numpy(shapes, None, ends)


def _assert_same(a: TurnCurves, b: TurnCurves) -> None:
    for x, y in ((a.xy, b.xy), (a.offsets, b.offsets), (a.length_m, b.length_m)):
        assert x.dtype == y.dtype and x.shape == y.shape
        assert x.tobytes() == y.tobytes()
    assert a.turn_rad.tobytes() == b.turn_rad.tobytes()
    assert a.radius_m == b.radius_m


def _headland_ends(spacing: list[float], step: list[float], base: list[float]) -> TurnEnds:
    """U-turns and Ωs at a headland: up one line, down the next ``spacing`` over."""
    n = len(spacing)
    up = np.full(n, math.pi / 2.0)
    x0 = np.array(base)
    y0 = np.array(base[::-1])
    return TurnEnds(x0, y0, up, x0 + np.array(spacing), y0 + np.array(step), -up)


@pytest.mark.parametrize("vehicle", ["small_tractor", "hand_tractor"])
@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from([0.5, 1.0, 2.0, 4.0, 5.999, 6.0, 8.0, 12.0]),  # across lines [m]
            st.floats(-15.0, 15.0, allow_nan=False),  # one end further back [m]
            st.floats(-500.0, 500.0, allow_nan=False),  # where the field lies [m]
        ),
        min_size=1,
        max_size=40,
    ),
    st.integers(1, 3),
)
def test_vehicle_turns_equal_the_numpy_path_bit_for_bit(
    vehicle: str, rows: list[tuple[float, float, float]], repeats: int
) -> None:
    # Repeated rows make shapes that ``vehicle_turns`` plans once (from 16 turns on).
    spacing, step, base = (list(c) * repeats for c in zip(*rows, strict=True))
    ends = _headland_ends(spacing, step, base)
    _assert_same(turns.vehicle_turns(ends, resolve_vehicle(vehicle)), _reference(ends, vehicle))


@given(
    st.lists(
        st.tuples(
            st.floats(-20.0, 20.0, allow_nan=False),
            st.floats(-20.0, 20.0, allow_nan=False),
            st.floats(-math.pi, math.pi, allow_nan=False),
            st.floats(-math.pi, math.pi, allow_nan=False),
        ),
        min_size=1,
        max_size=20,
    )
)
@settings(max_examples=40, deadline=None)
def test_moves_between_any_poses_equal_the_numpy_path(
    rows: list[tuple[float, float, float, float]],
) -> None:
    x1, y1, yaw0, yaw1 = (np.array(c) for c in zip(*rows, strict=True))
    zero = np.zeros(len(rows))
    ends = TurnEnds(zero + 3.0, zero - 2.0, yaw0, x1, y1, yaw1)
    vehicle = resolve_vehicle("small_tractor")
    try:
        expected = _reference(ends, "small_tractor")
    except ValueError:  # a bulb with no word: the one call must refuse it too
        with pytest.raises(ValueError, match="no Dubins word"):
            turns.vehicle_turns(ends, vehicle)
        return
    _assert_same(turns.vehicle_turns(ends, vehicle), expected)
