"""planner.kernel_helpers: numpy's rules, compiled, against numpy."""

from __future__ import annotations

import numpy as np

from planner.kernel_helpers import _pairwise_sum


def test_pairwise_sum_is_numpys() -> None:
    rng = np.random.default_rng(7)
    for n in [*range(1, 300), 1000, 4097, 30001]:
        values = rng.normal(size=n) * 10.0 ** rng.integers(-3, 6, size=n)
        assert _pairwise_sum(values, 0, n) == values.sum()
        if n > 1:
            assert values[0] + _pairwise_sum(values, 1, n - 1) == np.add.reduceat(values, [0])[0]
