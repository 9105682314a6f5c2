"""The compiled cells, order searches, heading terms and corner test equal numpy bit for bit.

(planner.cell_kernels, planner.order_kernels and planner.edge_kernels.)
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely import Polygon

from planner import cell_kernels, edge_kernels, heading_search, order_kernels
from planner.cell_order import (
    EXHAUSTIVE_MAX_CELLS,
    LOCAL_SEARCH_MAX_CELLS,
    CellVariants,
    _neighbourhood,
    _permutations,
    _Problem,
    _StraightProblem,
)
from planner.cell_plans import _scan_cells, plan_heading, scan_cells_numpy
from planner.decomposition import (
    _cuts,
    _pieces,
    decompose_sweep,
    decompose_sweep_numpy,
    sweep_rings,
)
from planner.heading_search import _SCRATCH_ARRAYS, _score_block, _score_block_numpy
from planner.lines import to_sweep
from planner.projection import field_frame
from planner.visibility import CornerVisibility, FieldInterior
from tests.planner.random_fields import fields_with_holes, star_field
from tests.planner.test_real_fields import real_fields

FloatArray = np.ndarray
Rings = list[tuple[FloatArray, FloatArray]]
SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def same_bits(a: FloatArray, b: FloatArray) -> bool:
    """Equal to the last bit, signed zeros included."""
    a, b = np.asarray(a), np.asarray(b)
    return (
        a.dtype == b.dtype
        and a.shape == b.shape
        and np.array_equal(a.view(np.int64), b.view(np.int64))
    )


def assert_same_rings(fast: Rings, slow: Rings) -> None:
    assert len(fast) == len(slow)
    for (fu, fv), (su, sv) in zip(fast, slow, strict=True):
        assert same_bits(fu, su) and same_bits(fv, sv)


def assert_same_cells(rings: Rings, d: float, edge_m: float) -> None:
    fast_scan, fast_cells = _scan_cells(rings, d, edge_m)
    slow_scan, slow_cells = scan_cells_numpy(rings, d, edge_m)
    for name in ("headings_deg", "offsets", "u", "v_lo", "v_hi"):
        assert same_bits(getattr(fast_scan, name), getattr(slow_scan, name)), name
    for fast, slow in zip(fast_cells, slow_cells, strict=True):
        assert fast.lines == slow.lines
        for name in ("lo_u", "lo_v", "hi_u", "hi_v"):
            assert same_bits(getattr(fast.chains, name), getattr(slow.chains, name)), name


def assert_same_at(field: Polygon, heading: float, d: float) -> None:
    """Cells, their lines and chains of ``field`` at ``heading``: compiled == numpy."""
    prepared = sweep_rings(field)
    rings = decompose_sweep(prepared, heading)
    assert_same_rings(rings, decompose_sweep_numpy(prepared, heading))
    # The kernel gives up (the clipping fallback) exactly where the numpy code does.
    r = prepared
    u, v = to_sweep(r.x, r.y, heading)
    turn = (u - u[r.prv]) * (u[r.nxt] - u) <= 0.0
    cuts = _cuts(u[turn])
    if len(cuts) > 2:
        status, *_ = cell_kernels.sweep_cells(
            u, v, turn, cuts, r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv
        )
        pieces = _pieces(u, v, turn, cuts, r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv)
        assert (status == 0) == (pieces is None)
    if rings:
        for edge_m in (d / 2.0, d / 4.0, 0.3 * d):
            assert_same_cells(rings, d, edge_m)


@SETTINGS
@given(
    field=fields_with_holes(max_vertices=60),
    heading=st.floats(0.0, 179.999),
    d=st.sampled_from([0.5, 1.0, 2.5, 4.0, 7.3, 30.0]),
    grid=st.sampled_from([None, 1.0, 5.0]),
)
def test_random_fields_compiled_equal_numpy(
    field: Polygon, heading: float, d: float, grid: float | None
) -> None:
    if grid is not None:
        # Vertices on a grid: edges parallel to the lines, ties at the cuts and in the chains.
        field = shapely.orient_polygons(shapely.set_precision(field, grid))
        if not isinstance(field, Polygon) or field.is_empty or not field.is_valid:
            return
        heading = float(np.round(heading / 45.0) * 45.0)
    assert_same_at(field, heading, d)


@pytest.mark.parametrize("heading", [0.0, 45.0, 90.0, 135.0])
def test_a_saw_tooth_field_compiled_equals_numpy(heading: float) -> None:
    teeth = [(x, 0.0 if i % 2 == 0 else 2.0) for i, x in enumerate(range(0, 62, 2))]
    field = shapely.orient_polygons(Polygon([*teeth, (60, 0), (60, 30), (0, 30)]))
    assert_same_at(field, heading, 4.0)
    assert len(decompose_sweep(field, 90.0)) > 10


@pytest.mark.parametrize(("seed", "heading"), [(31, 0.0), (47, 90.0), (311, 45.0)])
def test_degenerate_fields_fall_back_as_numpy_does(seed: int, heading: float) -> None:
    """Vertices on a 5 m grid where the monotone runs do not end on the cuts: clipping."""
    field = star_field(5 + seed % 50, seed, 50.0 + seed, seed % 4)
    field = shapely.orient_polygons(shapely.set_precision(field, 5.0))
    assert_same_at(field, heading, 4.0)
    r = sweep_rings(field)
    u, v = to_sweep(r.x, r.y, heading)
    turn = (u - u[r.prv]) * (u[r.nxt] - u) <= 0.0
    status, *_ = cell_kernels.sweep_cells(
        u, v, turn, _cuts(u[turn]), r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv
    )
    assert status == 0


@cache
def local_real_fields() -> list[Polygon]:
    fields = []
    for _, field in real_fields():
        local = field_frame(field).to_local(field)
        fields.append(shapely.orient_polygons(local))
    return fields


@pytest.mark.parametrize("part", range(4))
def test_real_fields_compiled_equal_numpy(part: int) -> None:
    rng = np.random.default_rng(part)
    for field in local_real_fields()[part::4]:
        for heading in np.concatenate([[0.0, 90.0], rng.uniform(0.0, 180.0, 6)]):
            assert_same_at(field, float(heading), 4.0)


def test_warm_up_runs() -> None:
    cell_kernels.warm_up()
    order_kernels.warm_up()
    edge_kernels.warm_up()


def problems(seed: int, count: int) -> list[_Problem]:
    """Random ordering problems: 2 to 40 cells, some with whole-metre costs (ties)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(count):
        m = int(rng.integers(2, 41))
        move = rng.uniform(0.0, 100.0, (m, 4, m, 4))
        first, last, inner = (rng.uniform(0.0, 50.0, (m, 4)) for _ in range(3))
        if k % 3 == 0:
            move, first, last, inner = (np.round(a) for a in (move, first, last, inner))
        if k % 5 == 0:
            move[rng.uniform(size=move.shape) < 0.05] = np.inf  # unreachable, round a hole
        out.append(_Problem(move, first, last, inner))
    return out


def straight_problems(seed: int, count: int) -> list[_Problem]:
    """Ordering problems of straight moves computed as needed: 2 to 150 cells."""
    rng = np.random.default_rng(seed)
    out: list[_Problem] = []
    for k in range(count):
        m = int(rng.integers(2, 151))
        entry, exit_ = (rng.uniform(0.0, 500.0, (m, 4, 2)) for _ in range(2))
        if k % 3 == 0:
            entry, exit_ = np.round(entry), np.round(exit_)
        cells = CellVariants(entry, exit_, rng.uniform(0.0, 50.0, (m, 4)))
        first, last = (rng.uniform(0.0, 50.0, (m, 4)) for _ in range(2))
        out.append(_StraightProblem(cells, first, last))
    return out


def assert_same_searches(problem: _Problem, rng: np.random.Generator) -> None:
    m = len(problem.inner)
    if m <= EXHAUSTIVE_MAX_CELLS:
        orders = _permutations(m)
    else:
        orders = np.stack([rng.permutation(m) for _ in range(20)])
    assert problem.compiled
    assert same_bits(problem.search_costs(orders), problem.costs(orders))
    for order in orders[:5]:
        assert problem.search_variants(order) == problem.variants(order)
    assert np.array_equal(problem.search_greedy(), problem.greedy())
    if m <= LOCAL_SEARCH_MAX_CELLS and not isinstance(problem, _StraightProblem):
        neighbourhood, changed, _ = _neighbourhood(m)
        candidates = orders[0][neighbourhood]
        fast = problem.search_costs(candidates)
        assert same_bits(fast, problem.costs_from(orders[0], candidates, changed))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_order_searches_compiled_equal_numpy(seed: int) -> None:
    rng = np.random.default_rng(300 + seed)
    for problem in [*problems(seed, 60), *straight_problems(seed, 20)]:
        assert_same_searches(problem, rng)


def test_order_searches_of_real_fields_compiled_equal_numpy() -> None:
    rng = np.random.default_rng(7)
    for field in local_real_fields()[::3]:
        for heading in (0.0, 60.0, 120.0):
            plan = plan_heading([field], heading, 4.0, None, None, 2.0)
            cells = plan.variants
            m = len(cells.inner_m)
            if m < 2 or m > LOCAL_SEARCH_MAX_CELLS:
                continue
            ex, en = cells.exit_xy.reshape(m * 4, 2), cells.entry_xy.reshape(m * 4, 2)
            move = np.hypot(ex[:, None, 0] - en[None, :, 0], ex[:, None, 1] - en[None, :, 1])
            start = np.asarray(field.exterior.coords[0])
            first = cells.inner_m + np.hypot(*(cells.entry_xy - start).transpose(2, 0, 1))
            problem = _Problem(move.reshape(m, 4, m, 4), first, np.zeros((m, 4)), cells.inner_m)
            assert_same_searches(problem, rng)


@pytest.mark.parametrize("part", range(2))
def test_tangent_pairs_compiled_equal_numpy(part: int) -> None:
    rng = np.random.default_rng(400 + part)
    fields = [f for f in local_real_fields() if f.interiors or len(f.exterior.coords) > 40]
    teeth = [(x, 0.0 if i % 2 == 0 else 2.0) for i, x in enumerate(range(0, 62, 2))]
    fields.append(Polygon([*teeth, (60, 0), (60, 30), (0, 30)]))  # collinear corners
    for field in fields[part::2]:
        oriented = shapely.orient_polygons(field)
        corners = CornerVisibility(oriented, FieldInterior(oriented))
        n = len(corners.nodes)
        if n < 2:
            continue
        i, j = np.triu_indices(n, k=1)
        if len(i) > 20_000:
            pick = rng.choice(len(i), 20_000, replace=False)
            i, j = i[pick], j[pick]
        fast = corners.tangent(i, j)
        assert np.array_equal(fast, corners.tangent_numpy(i, j))


def assert_same_scores(parts: list[Polygon], headings_deg: FloatArray, d: float) -> None:
    rings = [np.asarray(r.coords)[:-1] for p in parts for r in (p.exterior, *p.interiors)]
    xy = np.concatenate(rings)
    nxt = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
    sizes = [len(r) for r in rings]
    scratch = np.empty((_SCRATCH_ARRAYS, len(headings_deg), len(xy)))
    fast = _score_block(xy, nxt, sizes, headings_deg, d, len(parts), scratch)
    slow = _score_block_numpy(xy, nxt, sizes, headings_deg, d, len(parts), scratch.copy())
    for name in ("working_m", "pieces", "turn_backs", "missed_m2", "turns_m"):
        assert same_bits(getattr(fast, name), getattr(slow, name)), name


@pytest.mark.parametrize("part", range(4))
def test_heading_scores_of_real_fields_compiled_equal_numpy(part: int) -> None:
    rng = np.random.default_rng(500 + part)
    headings_deg = np.concatenate([np.arange(0.0, 180.0, 1.0), rng.uniform(0.0, 180.0, 40)])
    for field in local_real_fields()[part::4]:
        assert_same_scores([field], headings_deg, float(rng.choice([1.0, 2.5, 4.0, 7.3])))


@SETTINGS
@given(field=fields_with_holes(max_vertices=60), grid=st.sampled_from([None, 1.0, 5.0]))
def test_heading_scores_of_random_fields_compiled_equal_numpy(
    field: Polygon, grid: float | None
) -> None:
    if grid is not None:  # edges parallel to the lines at 0°, 45°, 90°, 135°
        field = shapely.orient_polygons(shapely.set_precision(field, grid))
        if not isinstance(field, Polygon) or field.is_empty or not field.is_valid:
            return
    assert_same_scores([field], np.arange(0.0, 180.0, 3.0), 4.0)


def test_scan_leaves_an_empty_ring_to_numpy() -> None:
    """The kernel would read an empty ring's first vertex: the numpy scan decides."""
    square = (np.array([0.0, 8.0, 8.0, 0.0]), np.array([0.0, 0.0, 4.0, 4.0]))
    rings = [square, (np.empty(0), np.empty(0))]
    # What a caller gets is the numpy code's answer (here its exception).
    with pytest.raises(IndexError) as numpy_error:
        scan_cells_numpy(rings, 4.0, 2.0)
    with pytest.raises(type(numpy_error.value)):
        _scan_cells(rings, 4.0, 2.0)


def test_heading_scores_in_blocks_compiled_equal_numpy(monkeypatch: pytest.MonkeyPatch) -> None:
    """score_headings over several blocks (the scratch reused, the last block shorter)."""
    t = np.linspace(0.0, 2.0 * np.pi, 1500, endpoint=False)
    radius = 100.0 + 7.0 * np.sin(37.0 * t)
    hole = Polygon([(-20, -20), (20, -20), (20, 20), (-20, 20)])
    field = Polygon(
        np.column_stack([radius * np.cos(t), radius * np.sin(t)]), [hole.exterior.coords]
    )
    field = shapely.orient_polygons(field)
    headings_deg = np.arange(0.0, 180.0, 0.7)
    vertices = len(field.exterior.coords) - 1 + 4
    block = max(1, heading_search._BLOCK_VALUES // vertices)
    assert len(headings_deg) > block and len(headings_deg) % block != 0  # a shorter last block
    fast = heading_search.score_headings([field], headings_deg, 4.0)
    monkeypatch.setattr(heading_search, "_score_block", heading_search._score_block_numpy)
    slow = heading_search.score_headings([field], headings_deg, 4.0)
    for name in ("working_m", "missed_m2", "turns_m"):
        assert same_bits(getattr(fast, name), getattr(slow, name)), name
    for name in ("pieces", "turn_backs"):
        assert np.array_equal(getattr(fast, name), getattr(slow, name)), name
    assert fast.exteriors == slow.exteriors


def nan_problems(seed: int, count: int) -> list[_Problem]:
    """Ordering problems with NaN costs (and inf): np.min's and np.argmin's NaN rules."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(count):
        m = int(rng.integers(2, 12))
        move = rng.uniform(0.0, 100.0, (m, 4, m, 4))
        first, last, inner = (rng.uniform(0.0, 50.0, (m, 4)) for _ in range(3))
        if k % 2 == 0:
            move, first, last, inner = (np.round(a) for a in (move, first, last, inner))
        move[rng.uniform(size=move.shape) < 0.05] = np.inf
        share = (0.02, 0.2, 1.0)[k % 3]  # a few NaNs, many, every move
        move[rng.uniform(size=move.shape) < share] = np.nan
        if k % 4 == 1:
            first[rng.uniform(size=first.shape) < 0.3] = np.nan
        if k % 4 == 2:
            last[rng.uniform(size=last.shape) < 0.3] = np.nan
        if k % 4 == 3:
            inner[rng.uniform(size=inner.shape) < 0.3] = np.nan
        out.append(_Problem(move, first, last, inner))
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_order_searches_with_nan_costs_compiled_equal_numpy(seed: int) -> None:
    rng = np.random.default_rng(600 + seed)
    for problem in nan_problems(seed, 40):
        assert_same_searches(problem, rng)
