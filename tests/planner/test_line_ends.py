"""planner.line_ends: line ends pulled back where a vehicle with a turning radius turns."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from planner import convex_fits
from planner.coverage import Chains, convex_chains
from planner.errors import InvalidParameterError
from planner.line_ends import FittedLines, fit_line_turns, fit_lines
from planner.vehicles import resolve_vehicle

SMALL = resolve_vehicle("small_tractor")  # 3 m radius: at 4 m every turn is an Ω


def _fit(ring: list[tuple[float, float]], u: list[float]) -> FittedLines:
    """Fit lines at ``u``, back and forth from the first going up, in the area ``ring``."""
    xy = np.array(ring, dtype=float)
    area = convex_chains(xy[:, 0], xy[:, 1])
    us = np.array(u)
    lo = np.interp(us, area.lo_u, area.lo_v)
    hi = np.interp(us, area.hi_u, area.hi_v)
    up = np.arange(len(us)) % 2 == 0
    return fit_lines(
        us,
        np.where(up, lo, hi),
        np.where(up, hi, lo),
        np.arange(len(us)),
        machine=area,
        vehicle=SMALL,
    )


def test_an_omega_beside_a_wall_leans_away_from_it_instead_of_sliding_down_the_wall() -> None:
    # Line 10 runs 0.5 m left of a wall beyond which the area is 30 m lower. The level Ω
    # from line 6 to line 10 swings 1 m out beyond line 10, over the wall: slid back as a
    # whole it goes 30 m down, and both lines lose it (19 m left of 60). With line 6's end
    # further back, the loop leans left and turns at the top.
    ring = [(-4, 0), (18, 0), (18, 30), (10.6, 30), (10.4, 60), (-4, 60)]
    fit = _fit(ring, [-2.0, 2.0, 6.0, 10.0, 14.0])
    length = dict(zip(fit.index.tolist(), np.abs(fit.v_end - fit.v_start).tolist(), strict=True))
    assert length[2] > 35.0 and length[3] > 45.0
    # Each turn still runs from its line's end to the next line's start, inside the area.
    area = shapely.Polygon(ring).buffer(1e-6)
    for k in range(len(fit.turns)):
        curve = fit.turns.curve(k)
        assert np.allclose(curve[0], [fit.u[k], fit.v_end[k]])
        assert np.allclose(curve[-1], [fit.u[k + 1], fit.v_start[k + 1]])
        assert area.covers(shapely.LineString(curve))


def test_a_side_line_shorter_than_the_pull_back_its_turn_costs_is_left_out() -> None:
    # Line 2 runs 10 m up a tongue; its Ω to line 6 pulls both ends back 6.3 m: the line
    # keeps 3.7 m and costs line 6 its 6.3 m. Without it, line 6 runs to the top.
    ring = [(0, 50), (4.2, 50), (4.2, 0), (12, 0), (12, 60), (0, 60)]
    fit = _fit(ring, [2.0, 6.0, 10.0])
    assert fit.index.tolist() == [1, 2]
    assert fit.v_start[0] == 60.0  # line 6 starts at the top: no turn before it


def _placed_sets(
    seed: int, vehicle_name: str
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Chains]]:
    """Lines as the convex fitting places them, on random convex fields at random headings."""
    rng = np.random.default_rng(seed)
    vehicle = resolve_vehicle(vehicle_name)
    sets = []
    while len(sets) < 40:
        points = rng.normal(size=(int(rng.integers(3, 10)), 2)) * 10 ** rng.uniform(1.0, 2.0)
        hull = shapely.convex_hull(shapely.MultiPoint(points))
        if not isinstance(hull, shapely.Polygon) or hull.area < 400.0:
            continue
        field = shapely.orient_polygons(hull)
        try:
            area = convex_fits.convex_machine_area(field, vehicle)
        except InvalidParameterError:
            continue
        heading = float(rng.uniform(0.0, 180.0))
        placed = convex_fits._place(
            convex_fits._Rings(field, area), heading, 4.0, vehicle, "boustrophedon", len(sets) % 4
        )
        sets.append((placed.u, placed.v_start, placed.v_end, placed.index, placed.machine))
    return sets


@pytest.mark.parametrize("vehicle_name", ["small_tractor", "hand_tractor"])
def test_many_sets_fitted_at_once_fit_as_each_alone(vehicle_name: str) -> None:
    """fit_line_turns' one call for many line sets: each set's fit bit for bit its own."""
    vehicle = resolve_vehicle(vehicle_name)
    sets = _placed_sets(7, vehicle_name)
    # A set of one line, and a machine area whose chain steps back (the kernel declines it).
    u, a, b, index, machine = sets[0]
    sets.append((u[:1], a[:1], b[:1], index[:1], machine))
    u, a, b, index, machine = sets[1]
    stepping = Chains(machine.lo_u[::-1].copy(), machine.lo_v, machine.hi_u, machine.hi_v)
    sets.append((u, a, b, index, stepping))
    first = fit_line_turns([s[:4] for s in sets], [s[4] for s in sets], vehicle)
    assert first[-2] is None
    lopsided = 0
    for (u, a, b, index, machine), turns in zip(sets, first, strict=True):
        alone = fit_lines(u, a, b, index, machine=machine, vehicle=vehicle)
        at_once = fit_lines(u, a, b, index, machine=machine, vehicle=vehicle, first_turns=turns)
        for name in ("u", "v_start", "v_end", "index"):
            assert np.array_equal(getattr(alone, name), getattr(at_once, name))
        for name in ("xy", "offsets", "length_m", "turn_rad"):
            mine, theirs = getattr(at_once.turns, name), getattr(alone.turns, name)
            assert mine.shape == theirs.shape
            assert np.array_equal(mine.view(np.int64), theirs.view(np.int64))
        if turns is not None:
            lopsided += int(np.count_nonzero(turns[1] != turns[2]))
    if vehicle.min_turn_radius_m > 0.0:
        assert lopsided > 0  # some Ωs were fitted lopsided: the test's premise
