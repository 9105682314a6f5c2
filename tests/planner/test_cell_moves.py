"""Cells as the vehicle drives them (planner.cell_moves): lines dropped at a cell's sides."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from planner.cell_moves import _without_lines
from planner.line_ends import FittedLines
from planner.turns import TurnCurves


def cell_of(n: int, seed: int) -> FittedLines:
    """``n`` lines in driving order and the ``n - 1`` turns between them, each its own size."""
    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 6, size=max(n - 1, 0))
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    turns = TurnCurves(
        rng.normal(size=(int(offsets[-1]), 2)),
        offsets,
        rng.uniform(1.0, 9.0, size=len(sizes)),
        rng.uniform(0.0, 3.0, size=len(sizes)),
        3.0,
    )
    v_start = rng.uniform(0.0, 5.0, size=n)
    return FittedLines(
        np.arange(n) * 4.0, v_start, v_start + 50.0, np.arange(n, dtype=np.int64), turns
    )


@given(
    n=st.integers(1, 7),
    first=st.integers(0, 7),
    last=st.integers(0, 7),
    seed=st.integers(0, 2**16),
)
def test_dropping_lines_keeps_the_others_and_the_turns_between_them(
    n: int, first: int, last: int, seed: int
) -> None:
    fit = cell_of(n, seed)
    kept = list(range(n))[first : max(n - last, first)]
    out = _without_lines(fit, first, last)
    assert out.index.tolist() == kept
    assert np.array_equal(out.u, fit.u[kept]) and np.array_equal(out.v_end, fit.v_end[kept])
    assert np.array_equal(out.v_start, fit.v_start[kept])
    # Turn k runs from line k to line k + 1: the ones kept join two lines kept.
    between = [k for k in range(n - 1) if k in kept and k + 1 in kept]
    assert len(out.turns) == len(between) == max(len(kept) - 1, 0)
    for j, k in enumerate(between):
        assert np.array_equal(out.turns.curve(j), fit.turns.curve(k))
    assert np.array_equal(out.turns.length_m, fit.turns.length_m[between])
    assert np.array_equal(out.turns.turn_rad, fit.turns.turn_rad[between])
    assert out.turns.offsets[0] == 0 and out.turns.offsets[-1] == len(out.turns.xy)
