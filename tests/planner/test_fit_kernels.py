"""The compiled turns (planner.fit_kernels) equal their numpy references bit for bit."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner import fit_kernels, turns
from planner.turns import BULB_WORDS, DUBINS_WORDS, TurnCurves, TurnEnds
from tests.conftest import PAPER_FIELD


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal to the last bit, signed zeros included."""
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype == np.float64:
        return np.array_equal(a.view(np.int64), b.view(np.int64))
    return np.array_equal(a, b)


def same_curves(a: TurnCurves, b: TurnCurves) -> bool:
    return (
        all(same_bits(getattr(a, f), getattr(b, f)) for f in ("xy", "offsets", "length_m"))
        and same_bits(a.turn_rad, b.turn_rad)
        and a.radius_m == b.radius_m
    )


def check_ends(ends: TurnEnds, radius_m: float) -> None:
    """Both words and samples equal the numpy code's, for every word set and both steps."""
    for words in (tuple(DUBINS_WORDS), BULB_WORDS, ("LSL", "RSR")):
        try:
            slow = turns._dubins_words_numpy(ends, radius_m=radius_m, words=words)
        except ValueError:
            with pytest.raises(ValueError):
                turns.dubins_words(ends, radius_m=radius_m, words=words)
            continue
        fast = turns.dubins_words(ends, radius_m=radius_m, words=words)
        assert same_bits(slow[0], fast[0]) and same_bits(slow[1], fast[1])
        signs, lengths = fast[0], fast[1] * radius_m
        for step in (turns.STEP_M, 0.13):
            assert same_curves(
                turns._sample_numpy(ends, signs, lengths, radius_m, step),
                turns._sample(ends, signs, lengths, radius_m, step),
            )
        # Backwards segments (Reeds–Shepp's negative lengths) and zero ones.
        backwards = lengths * np.where(np.arange(lengths.size) % 3 == 1, -1.0, 1.0).reshape(
            lengths.shape
        )
        backwards[:, 2] = np.where(np.arange(len(backwards)) % 2 == 0, 0.0, backwards[:, 2])
        assert same_curves(
            turns._sample_numpy(ends, signs, backwards, radius_m, turns.STEP_M),
            turns._sample(ends, signs, backwards, radius_m, turns.STEP_M),
        )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_turn_kernels_equal_numpy_on_line_ends(seed: int) -> None:
    # U-turns between lines as the fitting plans them: alternating ±π/2, spacings on a grid
    # (many exactly equal, mirror images), ends offset along the lines, and some odd poses.
    rng = np.random.default_rng(300 + seed)
    for trial in range(300):
        n = int(rng.integers(0, 30))
        scale = 10 ** rng.uniform(-1.0, 2.0)
        x0 = rng.normal(size=n) * scale
        y0 = rng.normal(size=n) * scale
        x1 = x0 + np.round(rng.normal(size=n) * scale, int(rng.integers(0, 3)))
        y1 = y0 + (trial % 2) * np.round(rng.normal(size=n) * scale * 0.1, 1)
        yaw0 = rng.choice([math.pi / 2.0, -math.pi / 2.0, 0.3], n)
        yaw1 = np.where(rng.random(n) < 0.8, -yaw0, rng.uniform(-4.0, 4.0, n))
        radius_m = float(rng.choice([0.35, 1.0, 3.0, scale]))
        check_ends(TurnEnds(x0, y0, yaw0, x1, y1, yaw1), radius_m)


pose = st.tuples(
    st.floats(-50.0, 50.0, allow_nan=False),
    st.floats(-50.0, 50.0, allow_nan=False),
    st.floats(-7.0, 7.0, allow_nan=False),
)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(pose, pose), min_size=1, max_size=8), st.floats(0.05, 8.0))
def test_turn_kernels_equal_numpy_on_any_poses(
    pairs: list[tuple[tuple[float, float, float], tuple[float, float, float]]], radius_m: float
) -> None:
    columns = np.array([[*a, *b] for a, b in pairs]).T.copy()
    check_ends(TurnEnds(*columns), radius_m)


def test_plans_turns_equal_numpy(monkeypatch: pytest.MonkeyPatch) -> None:
    # The paper field planned with the numpy code and with the kernels: the same plan.
    from planner import parse_field_geojson, plan_coverage
    from planner.export import plan_to_geojson

    spec = parse_field_geojson(json.loads(PAPER_FIELD.read_text()))

    def plans() -> str:
        return json.dumps(
            [
                plan_to_geojson(
                    plan_coverage(
                        spec.field_lonlat,
                        interval_m=interval,
                        start_lonlat=spec.start_lonlat,
                        finish_lonlat=spec.finish_lonlat,
                        vehicle=vehicle,
                    )
                )
                for interval in (1.0, 4.0)
                for vehicle in ("hand_tractor", "small_tractor")
            ]
        )

    fast = plans()
    monkeypatch.setattr(turns, "dubins_words", turns._dubins_words_numpy)
    monkeypatch.setattr(turns, "_sample", turns._sample_numpy)
    assert plans() == fast


def test_warm_up_compiles() -> None:
    fit_kernels.warm_up()
