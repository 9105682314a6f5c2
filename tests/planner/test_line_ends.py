"""planner.line_ends: line ends pulled back where a vehicle with a turning radius turns."""

from __future__ import annotations

import numpy as np
import shapely

from planner.coverage import convex_chains
from planner.line_ends import FittedLines, fit_lines
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
