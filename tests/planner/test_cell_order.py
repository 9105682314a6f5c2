"""Cell order: exact for few cells, never worse than greedy for many."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner import cell_order
from planner.cell_order import CellVariants, _neighbourhood, _Problem, order_cells

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def random_cells(rng: np.random.Generator, m: int) -> CellVariants:
    centres = rng.uniform(0, 500, (m, 1, 2))
    entry = centres + rng.uniform(-40, 40, (m, 4, 2))
    exit_ = centres + rng.uniform(-40, 40, (m, 4, 2))
    inner = rng.uniform(0, 100, (m, 4))
    return CellVariants(entry, exit_, inner)


def route_length(cells: CellVariants, order: list[tuple[int, int]], start, finish) -> float:
    total = sum(float(cells.inner_m[c, w]) for c, w in order)
    for (c0, w0), (c1, w1) in itertools.pairwise(order):
        total += float(np.hypot(*(cells.entry_xy[c1, w1] - cells.exit_xy[c0, w0])))
    if start is not None:
        c, w = order[0]
        total += float(np.hypot(*(cells.entry_xy[c, w] - np.asarray(start))))
    if finish is not None:
        c, w = order[-1]
        total += float(np.hypot(*(cells.exit_xy[c, w] - np.asarray(finish))))
    return total


def brute_force(cells: CellVariants, start, finish) -> float:
    m = len(cells.inner_m)
    best = np.inf
    for perm in itertools.permutations(range(m)):
        for variants in itertools.product(range(4), repeat=m):
            order = list(zip(perm, variants, strict=True))
            best = min(best, route_length(cells, order, start, finish))
    return best


@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 4), ends=st.integers(0, 3))
def test_few_cells_are_ordered_optimally(seed: int, m: int, ends: int) -> None:
    rng = np.random.default_rng(seed)
    cells = random_cells(rng, m)
    start = tuple(rng.uniform(0, 500, 2)) if ends & 1 else None
    finish = tuple(rng.uniform(0, 500, 2)) if ends & 2 else None
    order = order_cells(cells, start, finish)
    assert sorted(c for c, _ in order) == list(range(m))
    assert route_length(cells, order, start, finish) == pytest.approx(
        brute_force(cells, start, finish), abs=1e-6
    )


@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(7, 40))
def test_local_search_never_loses_to_the_greedy_order(seed: int, m: int) -> None:
    rng = np.random.default_rng(seed)
    cells = random_cells(rng, m)
    start = tuple(rng.uniform(0, 500, 2))
    greedy = order_cells(cells, start, None, improve=False)
    improved = order_cells(cells, start, None)
    assert sorted(c for c, _ in improved) == list(range(m))
    assert (
        route_length(cells, improved, start, None)
        <= route_length(cells, greedy, start, None) + 1e-9
    )
    assert order_cells(cells, start, None) == improved  # deterministic


@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(2, 30))
def test_local_search_costs_from_a_shared_beginning_are_its_full_costs(seed: int, m: int) -> None:
    """Carrying each neighbour on from where it first differs gives exactly the full costs,
    and the search's choice among equal neighbours is the first in its own order."""
    rng = np.random.default_rng(seed)
    # Whole metres: many neighbours tie, so the choice among equals is exercised too.
    move = np.round(rng.uniform(0, 50, (m, 4, m, 4)))
    first, last, inner = (np.round(rng.uniform(0, 50, (m, 4))) for _ in range(3))
    problem = _Problem(move, first, last, inner)
    order = rng.permutation(m).astype(np.int64)
    positions, changed, rank = _neighbourhood(m)
    assert np.array_equal(np.sort(rank), np.arange(len(rank)))
    assert (positions[np.arange(len(changed)), changed] != changed).all()
    assert (np.arange(m)[None, :] < changed[:, None])[positions != np.arange(m)].sum() == 0
    candidates = order[positions]
    full = problem.costs(candidates)
    assert np.array_equal(problem.costs_from(order, candidates, changed), full)
    # One round of the search: the first of the cheapest neighbours in its own order.
    in_search_order = np.empty_like(full)
    in_search_order[rank] = full
    by_search = np.empty_like(candidates)
    by_search[rank] = candidates
    best = float(problem.costs(order[None])[0])
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(cell_order, "_MAX_ROUNDS", 1)
        improved = problem.improve(order)
    k = int(np.argmin(in_search_order))
    expected = by_search[k] if in_search_order[k] < best - 1e-9 else order
    assert np.array_equal(improved, expected)
