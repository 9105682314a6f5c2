"""planner.screen_kernels: the compiled measure of a cell on its own against coverage's."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner.coverage import convex_chains, covered_area
from planner.screen_kernels import _covered_area
from tests.planner.test_heading_screen import same_bits

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@SETTINGS
@given(
    seed=st.integers(0, 2**32 - 1),
    lines=st.integers(1, 12),
    last_gap=st.floats(0.05, 1.5),
    uneven=st.booleans(),
)
def test_covered_area_is_coverages(seed: int, lines: int, last_gap: float, uneven: bool) -> None:
    """A convex cell, lines ``d`` apart but the last (nearer, or not), ends anywhere."""
    rng = np.random.default_rng(seed)
    d = 4.0
    angles = np.sort(rng.uniform(0.0, 2.0 * np.pi, size=int(rng.integers(3, 12))))
    radius = rng.uniform(5.0, 40.0)
    u_ring, v_ring = radius * np.cos(angles), radius * np.sin(angles) * rng.uniform(0.3, 2.0)
    chains = convex_chains(u_ring, v_ring)
    assert chains.packed is not None
    u = chains.u_min + 1.0 + d * np.arange(lines, dtype=float)
    if lines >= 2:
        u[-1] = u[-2] + d * last_gap
    if uneven and lines >= 3:
        u[0] += 0.5 * d  # nearer than d before the last: covered_area's overlapping form
    v_lo = rng.uniform(-50.0, 10.0, size=lines)
    v_hi = v_lo + rng.uniform(0.0, 60.0, size=lines)
    ok, compiled = _covered_area(chains.packed, u, v_lo, v_hi, d)
    if uneven and lines >= 3:
        assert not ok
    else:
        assert ok and same_bits(
            np.array(compiled), np.array(covered_area(chains, u, v_lo, v_hi, d))
        )
