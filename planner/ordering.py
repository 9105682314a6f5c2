"""Line order: the four ways to run a cell's lines back and forth, and their path lengths.

A variant is (which side first) × (which end first): ``left_up`` starts at the leftmost line
(smallest ``u``) driving towards ``v_hi``; ``left_down`` starts it towards ``v_lo``;
``right_up`` and ``right_down`` start at the rightmost line. Consecutive lines alternate
direction and are joined at the ends they share (Vasquez-Gomez et al. 2020).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from planner.lines import LineScan, line_counts, to_sweep

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

VARIANTS = ("left_up", "left_down", "right_up", "right_down")


@dataclass(frozen=True, slots=True)
class VariantLengths:
    """Path lengths of the four variants at every heading of a scan [m].

    Attributes
    ----------
    working : ndarray, shape (A,)
        Along the lines; the same for every variant.
    turns : ndarray, shape (A, 4)
        Straight connections between consecutive line ends.
    transit : ndarray, shape (A, 4)
        Start leg plus finish leg (zero where the point is not given).
    total : ndarray, shape (A, 4)
        Whole path per heading and variant [m]; summed once, on construction (the heading
        search reads it several times).
    """

    working: FloatArray
    turns: FloatArray
    transit: FloatArray
    total: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "total", self.working[:, None] + self.turns + self.transit)


@dataclass(frozen=True, slots=True)
class HeadingAggregates:
    """What the four variants' lengths depend on, per heading (all shape (A,)).

    Turn sums are split by where the turn is (top: ``v_hi`` ends, bottom: ``v_lo`` ends) and
    by the parity of the line it leaves, since alternating lines turn alternately.
    """

    headings_deg: FloatArray
    counts: IntArray
    working: FloatArray
    top_even: FloatArray
    top_odd: FloatArray
    bottom_even: FloatArray
    bottom_odd: FloatArray
    u_first: FloatArray
    lo_first: FloatArray
    hi_first: FloatArray
    u_last: FloatArray
    lo_last: FloatArray
    hi_last: FloatArray


def variant_lengths(
    scan: LineScan,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
) -> VariantLengths:
    """Score the four variants of every heading in ``scan``, line by line.

    This is the direct method (and the reference for :func:`score_headings`, which gets
    the same numbers without visiting every line).

    Parameters
    ----------
    scan : LineScan
        Lines of one cell at A headings.
    start_xy, finish_xy : tuple of float or None
        Where the tractor comes from and must end, local [m]; None if free.

    Returns
    -------
    VariantLengths

    Examples
    --------
    >>> from planner.lines import scan_cell
    >>> ring = np.array([[0.0, 0.0], [16.0, 0.0], [16.0, 20.0], [0.0, 20.0]])
    >>> lengths = variant_lengths(scan_cell(ring, np.array([0.0]), 4.0), (0.0, -5.0), None)
    >>> lengths.total.round(3).tolist()   # 80 m of lines + 12 m of turns + the start leg
    [[97.385, 117.08, 106.866, 120.653]]
    """
    return combine_variants(aggregate_scan(scan), start_xy, finish_xy)


def aggregate_scan(scan: LineScan) -> HeadingAggregates:
    """Per-heading aggregates of a scan, visiting every line."""
    n_headings = len(scan.headings_deg)
    heading = scan.heading_of_line()
    counts = scan.counts
    working = np.bincount(heading, scan.v_hi - scan.v_lo, minlength=n_headings).astype(float)
    k = np.arange(len(scan.u)) - scan.offsets[heading]
    here = np.nonzero(k < counts[heading] - 1)[0]
    du = scan.u[here + 1] - scan.u[here]
    top = np.hypot(du, scan.v_hi[here + 1] - scan.v_hi[here])
    bottom = np.hypot(du, scan.v_lo[here + 1] - scan.v_lo[here])
    even = (k[here] % 2) == 0
    h = heading[here]
    first, last = scan.offsets[:-1], scan.offsets[1:] - 1
    return HeadingAggregates(
        headings_deg=scan.headings_deg,
        counts=counts,
        working=working,
        top_even=np.bincount(h, top * even, minlength=n_headings).astype(float),
        top_odd=np.bincount(h, top * ~even, minlength=n_headings).astype(float),
        bottom_even=np.bincount(h, bottom * even, minlength=n_headings).astype(float),
        bottom_odd=np.bincount(h, bottom * ~even, minlength=n_headings).astype(float),
        u_first=scan.u[first],
        lo_first=scan.v_lo[first],
        hi_first=scan.v_hi[first],
        u_last=scan.u[last],
        lo_last=scan.v_lo[last],
        hi_last=scan.v_hi[last],
    )


def score_headings(
    ring_xy: FloatArray,
    headings_deg: FloatArray,
    interval_m: float,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
    sweep: tuple[FloatArray, FloatArray] | None = None,
) -> tuple[VariantLengths, IntArray]:
    """Score the four variants at every heading in O(vertices) per heading.

    Along one chain edge the line ends are linear in ``u``, so over the edge's run of
    regularly spaced lines the sum of the ends is an arithmetic series and every turn has
    the same length; only the turns that cross a vertex, and the last line (which may sit
    nearer its neighbour), are computed one by one. The result equals
    ``variant_lengths(scan_cell(...))`` without placing a single line, which is what keeps
    the angle search fast on fields of a thousand lines.

    Parameters
    ----------
    ring_xy : ndarray, shape (m, 2)
        The cell's exterior, counter-clockwise, not closed, local [m]; sweep-monotone.
    headings_deg : ndarray, shape (A,)
    interval_m : float
    start_xy, finish_xy : tuple of float or None
    sweep : tuple of ndarray, optional
        ``to_sweep`` of the ring at ``headings_deg[:, None]``, if the caller has it already.

    Returns
    -------
    lengths : VariantLengths
    counts : ndarray of int, shape (A,)
        Lines per heading.
    """
    headings = np.asarray(headings_deg, dtype=float)
    if sweep is None:
        sweep = to_sweep(ring_xy[:, 0], ring_xy[:, 1], headings[:, None])
    u_ring, v_ring = sweep
    from planner import kernels  # numba: imported by the first plan that needs it

    n, rows = kernels.length_aggregates(u_ring, v_ring, float(interval_m))
    # combine_variants compiled (planner.fit_kernels.combine_variants: the same numbers).
    from planner import fit_kernels

    turns, transit = fit_kernels.combine_variants(headings, n, rows[1:], start_xy, finish_xy)
    return VariantLengths(working=rows[0], turns=turns, transit=transit), n


def convex_aggregates(
    ring_xy: FloatArray, headings_deg: FloatArray, interval_m: float
) -> HeadingAggregates:
    """:func:`score_headings`' aggregates in numpy: the reference for its compiled loop.

    :func:`planner.kernels.length_aggregates` computes the same numbers one heading at a
    time; ``tests/planner/test_kernels.py`` holds them equal bit for bit.
    """
    d = float(interval_m)
    n_headings = len(headings_deg)
    m = len(ring_xy)
    # Each edge's two ends, rotated together: columns 0..m-1 the vertices, m..2m-1 the next ones.
    both_ends = np.concatenate([ring_xy, ring_xy[1:], ring_xy[:1]])
    u_all, v_all = to_sweep(
        both_ends[:, 0], both_ends[:, 1], np.asarray(headings_deg, dtype=float)[:, None]
    )
    u_ring, v_ring, u2, v2 = u_all[:, :m], v_all[:, :m], u_all[:, m:], v_all[:, m:]
    u_min, u_max = u_ring.min(axis=1), u_ring.max(axis=1)
    width = u_max - u_min
    n = line_counts(width, d)
    narrow = width <= d
    p0 = np.where(narrow, (u_min + u_max) / 2.0, u_min + d / 2.0)
    p_last = np.where(narrow, p0, u_max - d / 2.0)
    regular = n - 1  # lines 0 … n-2 sit on the grid p0 + k·d; line n-1 at p_last
    penult = regular - 1
    p_penult = p0 + penult * d

    # Every edge not parallel to the lines, both chains at once: group = chain · A + heading,
    # chain 0 the lower (u increasing along the counter-clockwise ring), 1 the upper.
    a, e = (u2 != u_ring).nonzero()  # methods, not np.* wrappers: fixed cost
    ua, ub, va, vb = u_ring[a, e], u2[a, e], v_ring[a, e], v2[a, e]
    group = a + n_headings * (ub < ua)
    slope = (vb - va) / (ub - ua)
    intercept = va - slope * ua
    lo, hi = np.minimum(ua, ub), np.maximum(ua, ub)
    pa, reg = p0[a], regular[a]
    k1 = np.clip(np.ceil((lo - pa) / d), 0, reg).astype(np.int64)
    k2 = np.clip(np.ceil((hi - pa) / d), 0, reg).astype(np.int64)
    c = k2 - k1

    def per_group(values: FloatArray) -> FloatArray:
        return np.bincount(group, values, minlength=2 * n_headings).astype(float)

    total = per_group(c * intercept + slope * (c * pa + d * c * (k1 + k2 - 1) / 2.0))
    # Turns between two lines of the same edge are all d·√(1 + slope²) long.
    same = np.maximum(c - 1, 0)
    evens = np.where(same > 0, (k2 - 2) // 2 - (k1 - 1) // 2, 0)
    step = d * np.sqrt(1.0 + slope * slope)
    even = per_group(evens * step)
    odd = per_group((same - evens) * step)
    # Turns into an edge's first line from the last line of the edge before it.
    used = (c > 0).nonzero()[0]
    order = used[np.lexsort((k1[used], group[used]))]
    follows = group[order[1:]] == group[order[:-1]]
    into, prev = order[1:][follows], order[:-1][follows]
    p_into = p0[a[into]] + k1[into] * d
    jump = np.hypot(
        d,
        (intercept[into] + slope[into] * p_into) - (intercept[prev] + slope[prev] * (p_into - d)),
    )
    jump_even = (k1[into] - 1) % 2 == 0
    even += np.bincount(group[into], jump * jump_even, minlength=2 * n_headings)
    odd += np.bincount(group[into], jump * ~jump_even, minlength=2 * n_headings)
    # The first, next-to-last and last lines, read off the edges that hold them.
    v_first = np.zeros(2 * n_headings)
    v_penult = np.zeros(2 * n_headings)
    v_last = np.zeros(2 * n_headings)
    holds = (lo <= p_last[a]) & (p_last[a] < hi)
    v_last[group[holds]] = intercept[holds] + slope[holds] * p_last[a[holds]]
    holds = (c > 0) & (k1 <= penult[a]) & (penult[a] < k2)
    v_penult[group[holds]] = intercept[holds] + slope[holds] * p_penult[a[holds]]
    holds = (c > 0) & (k1 == 0)
    v_first[:] = v_last  # with one line, the first is the last
    v_first[group[holds]] = intercept[holds] + slope[holds] * p0[a[holds]]
    # The turn into the last line, per chain: rows are (lower, upper).
    final = np.hypot(p_last - p_penult, (v_last - v_penult).reshape(2, n_headings))
    final = np.where(n >= 2, final, 0.0)
    final_even = penult % 2 == 0
    even += np.where(final_even, final, 0.0).ravel()
    odd += np.where(final_even, 0.0, final).ravel()
    total += v_last

    A = n_headings  # noqa: N806 - the two chains' halves
    return HeadingAggregates(
        headings_deg=np.asarray(headings_deg, dtype=float),
        counts=n,
        working=total[A:] - total[:A],
        top_even=even[A:],
        top_odd=odd[A:],
        bottom_even=even[:A],
        bottom_odd=odd[:A],
        u_first=p0,
        lo_first=v_first[:A],
        hi_first=v_first[A:],
        u_last=p_last,
        lo_last=v_last[:A],
        hi_last=v_last[A:],
    )


def combine_variants(
    agg: HeadingAggregates,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
) -> VariantLengths:
    """Turn per-heading aggregates into the four variants' lengths."""
    left_up = agg.top_even + agg.bottom_odd  # line 0 drives up, so it turns at the top
    left_down = agg.bottom_even + agg.top_odd
    # Run from the right, line n-1-j drives up iff j is even: with n odd the turns swap.
    n_odd = (agg.counts % 2) == 1
    right_up = np.where(n_odd, left_down, left_up)
    right_down = np.where(n_odd, left_up, left_down)
    turns = _columns(left_up, left_down, right_up, right_down)
    entry_u, entry_v, exit_u, exit_v = _ends(agg)
    transit = np.zeros(turns.shape)
    theta = np.radians(agg.headings_deg)
    cos_t, sin_t = np.cos(theta)[:, None], np.sin(theta)[:, None]
    for point, (pu_at, pv_at) in ((start_xy, (entry_u, entry_v)), (finish_xy, (exit_u, exit_v))):
        if point is not None:
            pu = point[0] * cos_t - point[1] * sin_t
            pv = point[0] * sin_t + point[1] * cos_t
            transit += np.hypot(pu_at - pu, pv_at - pv)
    return VariantLengths(working=agg.working, turns=turns, transit=transit)


def _ends(agg: HeadingAggregates) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    ends_up = (agg.counts - 1) % 2 == 0  # the last line driven runs the way the first did
    u_f, u_l = agg.u_first, agg.u_last
    lo_f, hi_f, lo_l, hi_l = agg.lo_first, agg.hi_first, agg.lo_last, agg.hi_last
    # Variants in VARIANTS order: left_up, left_down, right_up, right_down.
    entry_u = _columns(u_f, u_f, u_l, u_l)
    entry_v = _columns(lo_f, hi_f, lo_l, hi_l)
    exit_u = entry_u[:, ::-1]
    same = _columns(hi_l, lo_l, hi_f, lo_f)  # where each exits if ends_up
    flipped = _columns(lo_l, hi_l, lo_f, hi_f)
    exit_v = np.where(ends_up[:, None], same, flipped)
    return entry_u, entry_v, exit_u, exit_v


def _columns(*columns: FloatArray) -> FloatArray:
    """``np.stack(columns, axis=1)`` as floats, without stack's per-call cost."""
    out = np.empty((len(columns[0]), len(columns)))
    for j, column in enumerate(columns):
        out[:, j] = column
    return out


def variant_ends(
    scan: LineScan, aggregates: HeadingAggregates | None = None
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Where each variant enters its first line and leaves its last, shape (A, 4) each.

    ``aggregates`` (:func:`aggregate_scan` of ``scan``) saves computing them again.

    Returns
    -------
    entry_u, entry_v, exit_u, exit_v : ndarray, shape (A, 4)
        Sweep-frame coordinates [m], variants in :data:`VARIANTS` order.
    """
    return _ends(aggregate_scan(scan) if aggregates is None else aggregates)


def ordered_line_ends(
    u: FloatArray, v_lo: FloatArray, v_hi: FloatArray, variant: int
) -> tuple[FloatArray, FloatArray, FloatArray, IntArray]:
    """Order one heading's lines as ``variant`` drives them.

    Parameters
    ----------
    u, v_lo, v_hi : ndarray, shape (n,)
        The lines, left to right, sweep frame [m].
    variant : int
        Index into :data:`VARIANTS`.

    Returns
    -------
    u, v_start, v_end : ndarray, shape (n,)
        Each line in driving order, from ``v_start`` to ``v_end``.
    index : ndarray, shape (n,)
        The left-to-right index of each driven line.
    """
    n = len(u)
    index = np.arange(n) if variant < 2 else np.arange(n)[::-1].copy()
    up = (np.arange(n) % 2 == 0) == (variant in (0, 2))
    lo, hi = v_lo[index], v_hi[index]
    return u[index], np.where(up, lo, hi), np.where(up, hi, lo), index


def order_boustrophedon(n: int, variant: int) -> tuple[IntArray, npt.NDArray[np.bool_]]:
    """Drive ``n`` lines back and forth, neighbour after neighbour (today's pattern).

    Returns
    -------
    index : ndarray of int, shape (n,)
        Left-to-right index of each line, in driving order.
    up : ndarray of bool, shape (n,)
        Whether each driven line runs towards ``v_hi``.

    Examples
    --------
    >>> index, up = order_boustrophedon(4, 2)
    >>> index.tolist(), up.tolist()
    ([3, 2, 1, 0], [True, False, True, False])
    """
    index = np.arange(n) if variant < 2 else np.arange(n)[::-1].copy()
    up = (np.arange(n) % 2 == 0) == (variant in (0, 2))
    return index.astype(np.int64), up


def order_snake(n: int, variant: int, *, skip: int) -> tuple[IntArray, npt.NDArray[np.bool_]]:
    """Drive ``n`` lines ``skip`` apart, so that a turning radius needs no loops (snake).

    The lines are taken in ``skip`` interleaved passes across the field, out and back: every
    ``skip``-th line from the first side, then the lines between them on the way back, and so
    on (Fields2Cover's ``SnakeOrder`` with any skip). Consecutive lines are ``skip`` lines
    apart except where one pass hands over to the next.

    Parameters
    ----------
    n : int
    variant : int
        As :data:`VARIANTS`: which side first and which end first.
    skip : int
        Lines from one driven line to the next; 1 is back and forth.

    Returns
    -------
    index, up : ndarray
        As :func:`order_boustrophedon`.

    Examples
    --------
    >>> order_snake(7, 0, skip=2)[0].tolist()
    [0, 2, 4, 6, 5, 3, 1]
    >>> order_snake(8, 0, skip=3)[0].tolist()
    [0, 3, 6, 7, 4, 1, 2, 5]
    """
    if skip <= 1 or n <= 2:
        return order_boustrophedon(n, variant)
    passes = [np.arange(j, n, skip) for j in range(min(skip, n))]
    index = np.concatenate([p if j % 2 == 0 else p[::-1] for j, p in enumerate(passes)])
    if variant >= 2:
        index = n - 1 - index
    up = (np.arange(n) % 2 == 0) == (variant in (0, 2))
    return index.astype(np.int64), up
