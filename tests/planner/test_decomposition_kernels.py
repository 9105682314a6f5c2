"""planner.decomposition_kernels: the compiled glue of the decomposition against its numpy."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner.decomposition import _cuts
from planner.decomposition_kernels import _cuts as compiled_cuts
from tests.planner.test_heading_screen import same_bits

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@SETTINGS
@given(st.lists(st.floats(-1e3, 1e3) | st.sampled_from([0.0, 1e-7, 2e-6, -5e-7]), min_size=1))
def test_cuts_are_decompositions(values: list[float]) -> None:
    critical = np.array(values)
    assert same_bits(compiled_cuts(critical.copy()), _cuts(critical))
