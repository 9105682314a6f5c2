"""Lopsided Ωs (planner.lopsided_turns): the chosen variants take their level turns' places."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from planner import lopsided_turns
from planner.turns import TurnCurves, TurnEnds, concat_turns, take_turns, vehicle_turns
from planner.vehicles import resolve_vehicle


def _turns(steps: list[float], at: float) -> TurnCurves:
    n = len(steps)
    up = np.full(n, math.pi / 2.0)
    x0 = np.asarray(np.arange(n) * 4.0 + at, dtype=np.float64)
    return vehicle_turns(
        TurnEnds(x0, np.zeros(n), up, x0 + 4.0, np.array(steps), -up),
        resolve_vehicle("small_tractor"),
    )


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-15.0, 15.0, allow_nan=False), min_size=1, max_size=12),
    st.lists(st.floats(-15.0, 15.0, allow_nan=False), min_size=1, max_size=12),
    st.data(),
)
def test_replaced_turns_are_take_of_the_concatenation(
    level: list[float], variants: list[float], data: st.DataObject
) -> None:
    fitted, moved = _turns(level, 0.0), _turns(variants, 100.0)
    t = np.array(
        sorted(data.draw(st.sets(st.integers(0, len(level) - 1), min_size=1))), dtype=np.int64
    )
    best = np.array(
        data.draw(st.lists(st.integers(0, len(variants) - 1), min_size=len(t), max_size=len(t))),
        dtype=np.int64,
    )
    # The replacement as it was written first: the variants appended, then all taken.
    pick = np.arange(len(fitted))
    pick[t] = len(fitted) + np.arange(len(t))
    expected = take_turns(concat_turns(fitted, take_turns(moved, best)), pick)
    got = lopsided_turns._replaced(fitted, moved, t, best)
    for a, b in (
        (got.xy, expected.xy),
        (got.offsets, expected.offsets),
        (got.length_m, expected.length_m),
        (got.turn_rad, expected.turn_rad),
    ):
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
