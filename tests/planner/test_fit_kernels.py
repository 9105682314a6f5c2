"""The compiled turns (planner.fit_kernels) equal their numpy references bit for bit."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely import MultiPoint, Polygon

from planner import (
    convex_fits,
    fit_kernels,
    kernels,
    line_end_references,
    line_ends,
    pipeline,
    turn_references,
    turns,
)
from planner.coverage import Chains
from planner.errors import InvalidParameterError
from planner.lines import to_sweep
from planner.ordering import HeadingAggregates, combine_variants
from planner.turns import BULB_WORDS, DUBINS_WORDS, TurnCurves, TurnEnds
from planner.vehicles import resolve_vehicle
from tests.conftest import PAPER_FIELD
from tests.planner.test_kernels import convex_rings, headings


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


def copy_curves(curves: TurnCurves) -> TurnCurves:
    return TurnCurves(
        curves.xy.copy(),
        curves.offsets.copy(),
        curves.length_m.copy(),
        curves.turn_rad.copy(),
        curves.radius_m,
    )


def check_ends(ends: TurnEnds, radius_m: float) -> None:
    """Both words and samples equal the numpy code's, for every word set and both steps."""
    for words in (tuple(DUBINS_WORDS), BULB_WORDS, ("LSL", "RSR")):
        try:
            slow = turn_references.dubins_words_numpy(ends, radius_m=radius_m, words=words)
        except ValueError:
            with pytest.raises(ValueError):
                turns.dubins_words(ends, radius_m=radius_m, words=words)
            continue
        fast = turns.dubins_words(ends, radius_m=radius_m, words=words)
        assert same_bits(slow[0], fast[0]) and same_bits(slow[1], fast[1])
        signs, lengths = fast[0], fast[1] * radius_m
        for step in (turns.STEP_M, 0.13):
            assert same_curves(
                turn_references.sample_numpy(ends, signs, lengths, radius_m, step),
                turns._sample(ends, signs, lengths, radius_m, step),
            )
        # Moved onto other ends: each turn its own shape, or shapes shared (in any order).
        shapes = turns._sample(ends, signs, lengths, radius_m, turns.STEP_M)
        moved = TurnEnds(
            ends.x0 + 3.7, ends.y0 + 3.7, ends.yaw0, ends.x1 + 3.7, ends.y1 + 3.7, ends.yaw1
        )
        n = len(ends)
        for shape_of in (None, np.arange(n)[::-1].copy()):
            assert same_curves(
                turn_references.translate_numpy(copy_curves(shapes), shape_of, moved),
                turns._translate(copy_curves(shapes), shape_of, moved),
            )
        # Backwards segments (Reeds–Shepp's negative lengths) and zero ones.
        backwards = lengths * np.where(np.arange(lengths.size) % 3 == 1, -1.0, 1.0).reshape(
            lengths.shape
        )
        backwards[:, 2] = np.where(np.arange(len(backwards)) % 2 == 0, 0.0, backwards[:, 2])
        assert same_curves(
            turn_references.sample_numpy(ends, signs, backwards, radius_m, turns.STEP_M),
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
    monkeypatch.setattr(turns, "dubins_words", turn_references.dubins_words_numpy)
    monkeypatch.setattr(turns, "_sample", turn_references.sample_numpy)
    monkeypatch.setattr(turns, "_translate", turn_references.translate_numpy)
    monkeypatch.setattr(fit_kernels, "fit_turns", lambda *args: None)  # numpy decides
    monkeypatch.setattr(pipeline, "driving_time_s", turn_references.driving_time_numpy)

    def combined(*args: Any) -> tuple[np.ndarray, np.ndarray]:
        h, counts, rows, start_xy, finish_xy = args
        aggregates = HeadingAggregates(h, counts, np.zeros(len(h)), *rows)
        lengths = combine_variants(aggregates, start_xy, finish_xy)
        return lengths.turns, lengths.transit

    monkeypatch.setattr(fit_kernels, "combine_variants", combined)
    assert plans() == fast


def test_warm_up_compiles() -> None:
    fit_kernels.warm_up()


def fitted_both(
    curves: TurnCurves, top: np.ndarray, machine: Chains
) -> tuple[tuple[TurnCurves, np.ndarray, np.ndarray], tuple[TurnCurves, np.ndarray, np.ndarray]]:
    slow = line_end_references.fitted_numpy(
        curves, top, machine, tolerance_m=line_ends.FIT_TOLERANCE_M
    )
    fast = fit_kernels.fit_turns(
        curves.xy, curves.offsets, top, machine.lo_u, machine.lo_v, machine.hi_u, machine.hi_v,
        line_ends.FIT_TOLERANCE_M,
    )  # fmt: skip
    assert fast is not None
    shift, fits, xy = fast
    return slow, (
        TurnCurves(xy, curves.offsets, curves.length_m, curves.turn_rad, 1.0),
        shift,
        fits,
    )


@pytest.mark.parametrize("seed", [0, 1])
def test_turn_fitting_kernel_equals_numpy(seed: int) -> None:
    # Convex fields at random headings, every vehicle, lines placed as the fitting does: the
    # turns slid into the machine area by the kernel and by the numpy code.
    rng = np.random.default_rng(400 + seed)
    for trial in range(60):
        scale = 10 ** rng.uniform(0.7, 2.3)
        points = rng.normal(size=(int(rng.integers(3, 12)), 2)) * scale * rng.uniform(0.2, 1, 2)
        if trial % 3 == 0:
            points = np.round(points)
        hull = shapely.convex_hull(MultiPoint(points))
        if not isinstance(hull, Polygon) or hull.area < 50.0:
            continue
        field = shapely.orient_polygons(hull)
        for preset in ("hand_tractor", "small_tractor", "rover"):
            vehicle = resolve_vehicle(preset)
            try:
                area = convex_fits.convex_machine_area(field, vehicle)
            except InvalidParameterError:
                continue
            interval = float(rng.choice([1.0, 2.5, 4.0]))
            heading = float(rng.uniform(0.0, 180.0))
            rings = convex_fits._Rings(field, area)
            placed = convex_fits._place(
                rings, heading, interval, vehicle, "boustrophedon", int(trial % 4)
            )
            if len(placed.u) < 2:
                continue
            (curves,) = line_ends.plan_line_turns(
                [(placed.u, placed.v_start, placed.v_end, placed.index)], vehicle
            )
            assert curves is not None
            top = placed.v_end[:-1] >= placed.v_start[:-1]
            # Also every turn on the other side, and nudged off the chains.
            for flip, nudge in ((False, 0.0), (True, 0.0), (False, 0.3)):
                shifted = TurnCurves(
                    curves.xy + np.array([0.0, nudge]), curves.offsets, curves.length_m,
                    curves.turn_rad, curves.radius_m,
                )  # fmt: skip
                slow, fast = fitted_both(shifted, top ^ flip, placed.machine)
                assert same_bits(slow[0].xy, fast[0].xy)
                assert same_bits(slow[1], fast[1]) and same_bits(slow[2], fast[2])


def test_turn_fitting_kernel_declines_chains_out_of_order() -> None:
    chains = Chains(
        np.array([0.0, 2.0, 1.0]), np.zeros(3), np.array([0.0, 1.0, 2.0]), np.ones(3) * 5.0
    )
    xy = np.array([[0.5, 4.0], [1.0, 5.5], [1.5, 4.0]])
    offsets = np.array([0, 3])
    top = np.array([True])
    c = chains
    assert fit_kernels.fit_turns(xy, offsets, top, c.lo_u, c.lo_v, c.hi_u, c.hi_v, 1e-6) is None


@pytest.mark.parametrize("seed", [0, 1])
def test_combine_variants_kernel_equals_numpy(seed: int) -> None:
    rng = np.random.default_rng(500 + seed)
    for ring in convex_rings(seed, 60):
        d = float(rng.choice([0.5, 1.0, 4.0, 7.3]))
        h = headings(rng)
        u, v = to_sweep(ring[:, 0], ring[:, 1], h[:, None])
        counts, rows = kernels.length_aggregates(u, v, d)
        centre = ring.mean(axis=0)
        start = (float(centre[0] + rng.normal() * 50), float(centre[1] + rng.normal() * 50))
        finish = (float(ring[0, 0]), float(ring[0, 1]))
        for start_xy, finish_xy in ((start, finish), (None, finish), (start, None), (None, None)):
            slow = combine_variants(HeadingAggregates(h, counts, *rows), start_xy, finish_xy)
            turns_m, transit_m = fit_kernels.combine_variants(
                h, counts, rows[1:], start_xy, finish_xy
            )
            assert same_bits(slow.turns, turns_m) and same_bits(slow.transit, transit_m)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.sampled_from([0.0, 0.3, 1.0, 9.0])
        ),
        max_size=40,
    ),
    st.floats(0.1, 3.0),
    st.floats(5.0, 180.0),
)
def test_driving_time_kernel_equals_numpy(
    moves: list[tuple[float, float, float]], speed_mps: float, rate_dps: float
) -> None:
    # Polylines of sampled arcs (short steps), corners, long runs and repeated points.
    steps = np.array([(dx * s, dy * s) for dx, dy, s in moves]).reshape(-1, 2)
    xy = np.concatenate([np.zeros((1, 2)), np.cumsum(steps, axis=0)]) + 100.0
    fast = turns.driving_time_s(xy[:, 0], xy[:, 1], speed_mps=speed_mps, turn_rate_dps=rate_dps)
    slow = turn_references.driving_time_numpy(
        xy[:, 0], xy[:, 1], speed_mps=speed_mps, turn_rate_dps=rate_dps
    )
    assert same_bits(np.array([slow]), np.array([fast]))


@pytest.mark.parametrize("empty", ["lo", "hi"])
def test_turn_fitting_kernel_leaves_an_empty_chain_to_numpy(empty: str) -> None:
    """The kernel would read ``hi_u[0]``/``lo_u[-1]`` past an empty chain: numpy decides."""
    full, none = np.array([0.0, 1.0, 2.0]), np.empty(0)
    lo_u, lo_v = (none, none) if empty == "lo" else (full, np.zeros(3))
    hi_u, hi_v = (none, none) if empty == "hi" else (full, np.full(3, 5.0))
    machine = Chains(lo_u, lo_v, hi_u, hi_v)
    xy = np.array([[0.5, 4.0], [1.0, 5.5], [1.5, 4.0]])
    curves = TurnCurves(xy, np.array([0, 3]), np.array([3.0]), np.array([math.pi]), 1.0)
    top = np.array([True])
    c, off = machine, curves.offsets
    assert fit_kernels.fit_turns(xy, off, top, c.lo_u, c.lo_v, c.hi_u, c.hi_v, 1e-6) is None
    # What a caller gets is the numpy code's answer: np.interp refuses an empty chain.
    with pytest.raises(ValueError, match="empty"):
        line_end_references.fitted_numpy(
            curves, top, machine, tolerance_m=line_ends.FIT_TOLERANCE_M
        )
    lines = SimpleNamespace(u=np.zeros(2), up=np.array([True, False]))
    with pytest.raises(ValueError, match="empty"):
        line_ends._fit_turns(np.array([0]), np.array([1]), lines, machine, None, curves)  # type: ignore[arg-type]
