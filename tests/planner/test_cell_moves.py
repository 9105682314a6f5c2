"""Cells as the vehicle drives them (planner.cell_moves): lines and slivers dropped for curves."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st

from bench.move_corners import curvatures
from planner.cell_moves import _LineDrops, _without_lines, drive_cells
from planner.line_ends import FittedLines
from planner.routing import FieldRouter
from planner.turns import TurnCurves
from planner.vehicles import resolve_vehicle


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


def lines_of(u: list[float], v_start: float, v_end: float) -> FittedLines:
    """A cell of lines at ``u`` [m], driven alternately from ``v_start`` and ``v_end`` (heading 0).

    The turns between them are stand-ins: the drops carry them, never look at them.
    """
    n = len(u)
    v_from = np.where(np.arange(n) % 2 == 0, v_start, v_end).astype(float)
    v_to = np.where(np.arange(n) % 2 == 0, v_end, v_start).astype(float)
    turns = TurnCurves(
        np.zeros((2 * (n - 1), 2)),
        np.arange(0, 2 * n - 1, 2, dtype=np.int64),
        np.full(n - 1, 10.0),
        np.full(n - 1, np.pi),
        3.0,
    )
    return FittedLines(np.asarray(u, dtype=float), v_from, v_to, np.arange(n), turns)


#: A 3 m radius: the small tractor's.
SMALL = resolve_vehicle("small_tractor")


def scalloped(pockets_u: list[float]) -> FieldRouter:
    """A 48 m × 30 m field (x = u, y = v at heading 0) with 1.6 m × 1 m pockets on top."""
    pockets = [shapely.box(u - 0.8, 29.9, u + 0.8, 31.0) for u in pockets_u]
    return FieldRouter(shapely.union_all([shapely.box(0, 0, 48, 30), *pockets]))


@pytest.mark.parametrize("stubs", [1, 4])
def test_a_row_of_stubs_in_pockets_goes_and_the_cells_round_it_join_by_curves(
    stubs: int,
) -> None:
    # Lines at 2 … 14 m and 34 … 46 m, and between them stubs of 0.6 m, one per pocket,
    # driven up: a stub is entered by a curve from below, but no curve leaves it (0.2 m
    # short of the pocket's end, 1.6 m wide).
    pockets = [18.0 + 4.0 * k for k in range(stubs)]
    cells = [
        lines_of([2.0, 6.0, 10.0, 14.0], 1.0, 29.0),
        *(lines_of([u], 30.2, 30.8) for u in pockets),
        lines_of([34.0, 38.0, 42.0, 46.0], 29.0, 1.0),
    ]
    drops = _LineDrops(0.0, cells, scalloped(pockets), SMALL)
    moves = drops._keys(drops.first_dropped, drops.last_dropped)
    assert [drops.planned[key].curved for key in moves] == [True] + [False] * stubs
    drops.drop_slivers()
    alive = drops._alive(drops.first_dropped, drops.last_dropped)
    assert alive == [0, len(cells) - 1]
    (move,) = drops._keys(drops.first_dropped, drops.last_dropped)
    assert drops.planned[move].curved


def test_a_stub_longer_than_the_radius_and_a_stub_joined_by_curves_stay() -> None:
    # A stub of 0.6 m in the open, 8 m below the top, is joined and left by curves; a
    # pocket 4 m deep holds a 3.5 m line (over the 3 m radius), which no curve leaves.
    field = FieldRouter(
        shapely.union_all([shapely.box(0, 0, 48, 30), shapely.box(29.2, 29.9, 30.8, 34.0)])
    )
    cells = [
        lines_of([2.0, 6.0, 10.0, 14.0], 1.0, 29.0),
        lines_of([18.0], 21.4, 22.0),
        lines_of([22.0, 26.0], 29.0, 1.0),
        lines_of([30.0], 30.0, 33.5),
        lines_of([38.0, 42.0, 46.0], 29.0, 1.0),
    ]
    drops = _LineDrops(0.0, cells, field, SMALL)
    keys = drops._keys(drops.first_dropped, drops.last_dropped)
    assert [drops.planned[key].curved for key in keys] == [True, True, True, False]
    drops.drop_slivers()
    assert drops._alive(drops.first_dropped, drops.last_dropped) == [0, 1, 2, 3, 4]


def test_a_sliver_whose_move_has_corners_for_the_other_cells_sake_stays() -> None:
    # A 10 m line up a corridor 1.6 m wide: no curve leaves it, whatever follows. Dropping
    # the stub after it (which a curve leaves) would leave the move from it with corners.
    field = FieldRouter(
        shapely.union_all([shapely.box(0, 0, 48, 30), shapely.box(1.2, 29.9, 2.8, 44.0)])
    )
    cells = [
        lines_of([2.0], 31.0, 41.0),
        lines_of([18.0], 21.4, 22.0),
        lines_of([22.0, 26.0], 29.0, 1.0),
    ]
    drops = _LineDrops(0.0, cells, field, SMALL)
    keys = drops._keys(drops.first_dropped, drops.last_dropped)
    assert [drops.planned[key].curved for key in keys] == [False, True]
    drops.drop_slivers()
    assert drops._alive(drops.first_dropped, drops.last_dropped) == [0, 1, 2]


def test_a_plan_of_slivers_only_keeps_them() -> None:
    pockets = [18.0, 22.0, 26.0]
    cells = [lines_of([u], 30.2, 30.8) for u in pockets]
    drops = _LineDrops(0.0, cells, scalloped(pockets), SMALL)
    keys = drops._keys(drops.first_dropped, drops.last_dropped)
    assert [drops.planned[key].curved for key in keys] == [False, False]
    drops.drop_slivers()
    assert drops._alive(drops.first_dropped, drops.last_dropped) == [0, 1, 2]


def test_driving_cells_drops_a_row_of_stubs_by_itself(monkeypatch: pytest.MonkeyPatch) -> None:
    # The drops of up to three lines (switched off here) clear this short row too; on a
    # real scalloped core they left rows of moves with corners (66 sharp turns in
    # south_africa_2017-52's spiral, docs/vehicles.md).
    monkeypatch.setattr(_LineDrops, "drop_for_curves", lambda self: None)
    pockets = [18.0, 22.0, 26.0, 30.0]
    cells = [
        lines_of([2.0, 6.0, 10.0, 14.0], 1.0, 29.0),
        *(lines_of([u], 30.2, 30.8) for u in pockets),
        lines_of([34.0, 38.0, 42.0, 46.0], 29.0, 1.0),
    ]
    plan = SimpleNamespace(heading_deg=0.0)  # drive_cells reads the heading only
    driven = drive_cells(plan, cells, scalloped(pockets), vehicle=SMALL)  # type: ignore[arg-type]
    assert [len(fit.u) for fit in driven.fitted] == [4, 0, 0, 0, 0, 4]
    (move,) = driven.moves
    assert (curvatures(move, rounding_m=0.0) <= 1.0 / SMALL.min_turn_radius_m * (1 + 1e-6)).all()
