"""Coverage (R4) of a convex cell at every candidate heading at once, without placing lines.

R5 ranks headings by coverage first, so the angle search needs the coverage of ~300
headings in well under a millisecond. In the sweep frame of a heading a line's footprint is
the strip ``[u - d/2, u + d/2] × [lo(u_k), hi(u_k)]``; what it misses of the cell is where the
upper chain rises above its value at the line, ``(hi(u) - hi(u_k))+``, and where the lower
chain falls below it. Across a strip that lies within one chain edge of slope ``s`` this is
``|s| d² / 8`` exactly, so the strips inside an edge are counted in closed form per edge; only
the strips that hold a vertex are integrated piece by piece. Near the two ends of the cell a
footprint can miss the cell altogether over part of its strip (a thin, slanted tip), where the
excess would overcount; so the strips are taken per *elementary interval* (between
consecutive vertices of either chain), where both chains are linear and the kept height of
each half strip is ``max(0, h_k − rate · τ)``: closed forms in the line's height ``h_k``, which
is linear in ``k``. Strips that hold a vertex, and the last two lines' (which may overlap, R2),
are integrated exactly, both chains at once. The result is
:func:`planner.coverage.covered_area` at every heading, in O(vertices) per heading.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from planner.lines import line_counts, to_sweep
from planner.turn_reach import end_reach_m, fitting_loss_m2
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def convex_coverage(
    ring_xy: FloatArray,
    headings_deg: FloatArray,
    interval_m: float,
    sweep: tuple[FloatArray, FloatArray] | None = None,
) -> FloatArray:
    """Coverage ratio of a convex cell's lines at every heading (R2, R3 placement; R4).

    Parameters
    ----------
    ring_xy : ndarray, shape (m, 2)
        The cell's exterior, counter-clockwise, not closed, local [m]; convex.
    headings_deg : ndarray, shape (A,)
        Line headings [deg].
    interval_m : float
        Distance between lines and footprint width [m].
    sweep : (ndarray, ndarray), optional
        ``to_sweep(ring_xy[:, 0], ring_xy[:, 1], headings_deg[:, None])``, if the caller has
        it already (the heading search needs the widths too).

    Returns
    -------
    ndarray, shape (A,)
        Covered area over the cell's area, in [0, 1].

    Examples
    --------
    A 16 m × 20 m rectangle is covered completely along its sides; at 45° its corners are not:

    >>> ring = np.array([[0.0, 0.0], [16.0, 0.0], [16.0, 20.0], [0.0, 20.0]])
    >>> convex_coverage(ring, np.array([0.0, 90.0, 45.0]), 4.0).round(4).tolist()
    [1.0, 1.0, 0.9327]
    """
    headings = np.asarray(headings_deg, dtype=float)
    d = float(interval_m)
    area = ring_area_m2(ring_xy)
    u_ring, v_ring = (
        to_sweep(ring_xy[:, 0], ring_xy[:, 1], headings[:, None]) if sweep is None else sweep
    )
    from planner import kernels  # numba: imported by the first plan that needs it

    excess = kernels.coverage_excess(u_ring, v_ring, d)
    if excess is None:  # a ring the kernel cannot vouch for
        excess = convex_excess(u_ring, v_ring, d)
    return np.asarray(np.clip(1.0 - excess / area, 0.0, 1.0))


def estimated_coverage(
    ring_xy: FloatArray,
    headings_deg: FloatArray,
    interval_m: float,
    sweep: tuple[FloatArray, FloatArray],
    *,
    vehicle: Vehicle,
    field_m2: float,
    ring_m2: float | None = None,
) -> FloatArray:
    """Estimate the coverage of fitted lines at every heading: the heading search's score.

    Straight lines' closed-form coverage, less what fitting them for ``vehicle`` will take
    (:func:`planner.turn_reach.fitting_loss_m2`: ends on the machine area, pulled back for the
    turns) over ``field_m2``. Compiled (:func:`planner.kernels.estimated_coverage`), with
    :func:`estimated_coverage_numpy` the reference and the fallback.

    Parameters
    ----------
    ring_xy, headings_deg, interval_m, sweep
        As :func:`convex_coverage` (``sweep`` required).
    vehicle : Vehicle
    field_m2 : float
        The field's area [m²].
    ring_m2 : float, optional
        :func:`ring_area_m2` of ``ring_xy``, if the caller has it (the search scores twice).

    Examples
    --------
    >>> from planner.vehicles import resolve_vehicle
    >>> ring = np.array([[0.0, 0.0], [16.0, 0.0], [16.0, 20.0], [0.0, 20.0]])
    >>> h = np.array([0.0, 90.0])
    >>> sweep = to_sweep(ring[:, 0], ring[:, 1], h[:, None])
    >>> estimated_coverage(ring, h, 4.0, sweep, vehicle=resolve_vehicle("hand_tractor"),
    ...                    field_m2=320.0).round(4).tolist()
    [0.9312, 0.9119]
    """
    from planner import kernels  # numba: imported by the first plan that needs it

    estimate = kernels.estimated_coverage(
        sweep[0],
        sweep[1],
        float(interval_m),
        ring_area_m2(ring_xy) if ring_m2 is None else ring_m2,
        field_m2=field_m2,
        width_m=vehicle.width_m,
        reach_m=end_reach_m(vehicle, float(interval_m)),
    )
    if estimate is None:  # a ring the kernel cannot vouch for
        return estimated_coverage_numpy(
            ring_xy, headings_deg, interval_m, sweep, vehicle=vehicle, field_m2=field_m2
        )
    return estimate


def estimated_coverage_numpy(
    ring_xy: FloatArray,
    headings_deg: FloatArray,
    interval_m: float,
    sweep: tuple[FloatArray, FloatArray],
    *,
    vehicle: Vehicle,
    field_m2: float,
) -> FloatArray:
    """:func:`estimated_coverage` in numpy: the reference for its compiled loop."""
    widths = np.asarray(sweep[0].max(axis=1) - sweep[0].min(axis=1))
    counts = line_counts(widths, interval_m)
    loss = fitting_loss_m2(vehicle, interval_m, counts, widths) / field_m2
    return np.asarray(convex_coverage(ring_xy, headings_deg, interval_m, sweep) - loss)


def ring_area_m2(ring_xy: FloatArray) -> float:
    """Return the shoelace area of a counter-clockwise ring [m²]."""
    x, y = ring_xy[:, 0], ring_xy[:, 1]
    nxt = np.arange(1, len(ring_xy) + 1) % len(ring_xy)  # np.r_ costs more than the rest
    return 0.5 * float(np.dot(x, y[nxt]) - np.dot(y, x[nxt]))


def convex_excess(u_ring: FloatArray, v_ring: FloatArray, d: float) -> FloatArray:
    """Area a convex cell's lines miss at every heading [m²]: :func:`convex_coverage`'s core.

    The reference for :func:`planner.kernels.coverage_excess`, which computes the same
    numbers in a compiled loop.

    Parameters
    ----------
    u_ring, v_ring : ndarray, shape (A, m)
        The ring in the sweep frame of each heading (:func:`planner.lines.to_sweep`).
    d : float
        Interval [m].
    """
    n_headings, m = u_ring.shape
    u_ring = u_ring - u_ring.min(axis=1, keepdims=True)  # every heading's cell starts at 0
    width = u_ring.max(axis=1)
    n = line_counts(width, d)
    narrow = width <= d
    big = 2.0 * float(width.max()) + 1.0
    # The ring from its leftmost vertex: the lower chain runs left to right, then the upper
    # chain right to left, so each chain's edges come sorted without a sort.
    rows = np.arange(n_headings)[:, None]
    # Array methods (.argmin, .nonzero, .repeat, .searchsorted) rather than the np.* wrappers:
    # the wrappers cost more than the work on arrays this small.
    walk = (u_ring.argmin(axis=1)[:, None] + np.arange(m + 1)) % m
    u_w, v_w = u_ring[rows, walk], v_ring[rows, walk]
    chains = []
    for upper in (False, True):
        ua, ub, va, vb = u_w[:, :-1], u_w[:, 1:], v_w[:, :-1], v_w[:, 1:]
        if upper:
            ua, ub, va, vb = ub[:, ::-1], ua[:, ::-1], vb[:, ::-1], va[:, ::-1]
        a, e = (ub > ua).nonzero()
        ua, ub, va, vb = ua[a, e], ub[a, e], va[a, e], vb[a, e]
        slope = (vb - va) / (ub - ua)
        chains.append(_Chain(a * big + ua, va - slope * ua, slope))
    lower, upper_chain = chains

    # Elementary intervals: between consecutive vertices of either chain both are linear.
    cuts = np.sort(u_ring, axis=1)
    x0, x1 = cuts[:, :-1], cuts[:, 1:]
    ih, col = (x1 > x0).nonzero()
    x0, x1 = x0[ih, col], x1[ih, col]
    base = ih * big
    mid = base + (x0 + x1) / 2.0
    k_lo, k_hi = lower.edge_at(mid), upper_chain.edge_at(mid)
    s_lo, s_hi = lower.slope[k_lo], upper_chain.slope[k_hi]
    lo0 = lower.intercept[k_lo] + s_lo * x0
    hi0 = upper_chain.intercept[k_hi] + s_hi * x0
    spans = _Spans(base + x0, x0, x1, lo0, s_lo, hi0, s_hi)

    # Strips 0 … n-3 are [k·d, (k+1)·d] around line k; those inside one interval in closed
    # form: height h_k linear in k, and each half strip loses (rate · τ) of it, τ ≤ d/2.
    last_regular = np.where(narrow, -1, n - 3)[ih]
    k1 = np.ceil(x0 / d)
    k2 = np.minimum(np.floor(x1 / d) - 1.0, last_regular)
    count = np.maximum(k2 - k1 + 1.0, 0.0)
    u_first = k1 * d + d / 2.0
    h_first = (hi0 - lo0) + (s_hi - s_lo) * (u_first - x0)
    step = (s_hi - s_lo) * d
    rates = np.concatenate(
        [
            np.maximum(-s_hi, 0.0) + np.maximum(s_lo, 0.0),  # the half ahead (τ = u − u_k)
            np.maximum(s_hi, 0.0) + np.maximum(-s_lo, 0.0),  # the half behind
        ]
    )
    kept = _half_strips(
        np.concatenate([h_first, h_first]),
        np.concatenate([step, step]),
        np.concatenate([count, count]),
        rates,
        d,
    )
    missed = count * d * h_first + d * step * count * (count - 1.0) / 2.0
    missed -= kept[: len(ih)] + kept[len(ih) :]
    excess: FloatArray = np.bincount(ih, missed, minlength=n_headings).astype(float)

    # Strips that hold a vertex (those an interval starts or ends inside), in order: the
    # first strip of interval i, its last, then interval i+1's.
    z_first, z_last = np.floor(x0 / d), np.ceil(x1 / d) - 1.0
    part_k = _interleave(z_first, z_last)
    partial = _interleave(z_first < k1, z_last > np.floor(x1 / d) - 1.0)
    part_h = ih.repeat(2)
    ok = partial & (part_k >= 0) & (part_k <= last_regular.repeat(2))
    part_h, part_k = part_h[ok], part_k[ok]
    fresh = np.ones(len(part_h), dtype=bool)
    fresh[1:] = (part_h[1:] != part_h[:-1]) | (part_k[1:] != part_k[:-1])
    part_h, part_k = part_h[fresh], part_k[fresh]
    # ... and the last two lines' strips and their overlap (R2), and a narrow cell's one
    # strip: all integrated exactly, in one pass.
    zone_h, z0, z1, u_a, u_b, weight = _end_zones(n, width, narrow, d)
    centre = part_k * d + d / 2.0
    excess += spans.missed(
        np.concatenate([part_h, zone_h]),
        n_headings,
        big,
        np.concatenate([part_k * d, z0]),
        np.concatenate([part_k * d + d, z1]),
        np.concatenate([centre, u_a]),
        np.concatenate([centre, u_b]),
        np.concatenate([np.ones(len(part_h)), weight]),
    )
    return excess


def _interleave(a: npt.NDArray[Any], b: npt.NDArray[Any]) -> npt.NDArray[Any]:
    """``[a0, b0, a1, b1, …]``: ``np.stack([a, b], axis=1).ravel()`` at a third of the cost."""
    out = np.empty(2 * len(a), dtype=a.dtype)
    out[0::2], out[1::2] = a, b
    return out


@dataclass(frozen=True, slots=True)
class _Chain:
    """One chain's edges at every heading, sorted by (heading, left end): ``v = c + s·u``."""

    keys: FloatArray  # heading · big + left end u
    intercept: FloatArray
    slope: FloatArray

    def edge_at(self, keys: FloatArray) -> IntArray:
        """Index of the edge holding each query (heading · big + u); sorted queries are fast."""
        return np.asarray(self.keys.searchsorted(keys, side="right") - 1)


@dataclass(frozen=True, slots=True)
class _Spans:
    """Elementary intervals ``[x0, x1]`` per heading, both chains linear on each."""

    keys: FloatArray  # heading · big + x0, sorted
    x0: FloatArray
    x1: FloatArray
    lo0: FloatArray
    s_lo: FloatArray
    hi0: FloatArray
    s_hi: FloatArray

    def at(self, keys: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Lower and upper chain at ``u`` (queries ``keys`` = heading · big + u)."""
        i = self.keys.searchsorted(keys, side="right") - 1
        du = u - self.x0[i]
        return self.lo0[i] + self.s_lo[i] * du, self.hi0[i] + self.s_hi[i] * du

    def missed(
        self,
        zone_h: IntArray,
        n_headings: int,
        big: float,
        z0: FloatArray,
        z1: FloatArray,
        u_a: FloatArray,
        u_b: FloatArray,
        weight: FloatArray,
    ) -> FloatArray:
        """Missed area per heading of the strips ``[z0, z1]``, each counted ``weight`` times.

        A strip is covered by the band between both chains' values at ``u_a`` and at ``u_b``:
        the common part of two lines' ends, or one line's if they are the same. Strips are
        cut at the intervals (where a chain has a vertex) and integrated exactly.
        """
        base = zone_h * big
        k = len(u_a)
        lo_ab, hi_ab = self.at(np.concatenate([base + u_a, base + u_b]), np.concatenate([u_a, u_b]))
        bottom, top = np.maximum(lo_ab[:k], lo_ab[k:]), np.minimum(hi_ab[:k], hi_ab[k:])
        first = self.keys.searchsorted(base + z0, side="right") - 1
        stop = self.keys.searchsorted(base + z1, side="left")
        count = stop - first
        z = np.arange(len(z0)).repeat(count)
        i = (first - count.cumsum() + count).repeat(count) + np.arange(int(count.sum()))
        x0, lo_i, s_lo = self.x0[i], self.lo0[i], self.s_lo[i]  # each gathered once
        hi_i, s_hi = self.hi0[i], self.s_hi[i]
        p0 = np.maximum(x0, z0[z])
        p1 = np.minimum(self.x1[i], z1[z])
        du0, du1 = p0 - x0, p1 - x0
        lo0 = lo_i + s_lo * du0
        lo1 = lo_i + s_lo * du1
        hi0 = hi_i + s_hi * du0
        hi1 = hi_i + s_hi * du1
        w = np.maximum(p1 - p0, 0.0)
        cell = w * ((hi0 - lo0) + (hi1 - lo1)) / 2.0
        lost = weight[z] * (cell - _covered_pieces(w, lo0, lo1, hi0, hi1, bottom[z], top[z]))
        return np.asarray(np.bincount(zone_h[z], lost, minlength=n_headings))


def _half_strips(
    h_first: FloatArray, step: FloatArray, count: FloatArray, rate: FloatArray, d: float
) -> FloatArray:
    """Σ_j ∫_0^{d/2} max(0, h_j − rate · τ) dτ over ``count`` strips, h_j = h_first + j·step.

    A strip whose line is at least ``rate · d/2`` long keeps ``h d/2 − rate d²/8``; a shorter
    one keeps the triangle ``h² / (2 rate)``. Heights are linear in ``j``, so the strips of each
    kind are a run, and both sums have closed forms.
    """
    full = rate * d / 2.0
    # Number of strips with h_j >= full: h_j is monotone in j.
    with np.errstate(divide="ignore", invalid="ignore"):
        j_cross = (full - h_first) / step  # h_j = full at j = j_cross
        tri_per = 1.0 / (2.0 * rate)
    rising = step > 0.0
    flat = step == 0.0
    j_cross = np.where(flat, 0.0, j_cross)
    n_full = np.where(
        rising,
        count - np.clip(np.ceil(j_cross), 0.0, count),
        np.clip(np.floor(j_cross) + 1.0, 0.0, count),
    )
    n_full = np.where(flat, np.where(h_first >= full, count, 0.0), n_full)
    n_tri = count - n_full
    # The full strips are the last n_full (rising) or the first n_full (falling).
    j0_full = np.where(rising, n_tri, 0.0)
    j0_tri = np.where(rising, 0.0, n_full)
    sum_full = n_full * h_first + step * _sum_j(j0_full, n_full)
    kept = sum_full * (d / 2.0) - n_full * rate * (d * d / 8.0)
    sum_sq = (
        n_tri * h_first * h_first
        + 2.0 * h_first * step * _sum_j(j0_tri, n_tri)
        + step * step * _sum_j2(j0_tri, n_tri)
    )
    tri = np.where(n_tri > 0, sum_sq * np.where(rate > 0.0, tri_per, 0.0), 0.0)
    return np.asarray(kept + tri)


def _sum_j(j0: FloatArray, c: FloatArray) -> FloatArray:
    """Σ j for j = j0 … j0 + c − 1."""
    return np.asarray(c * j0 + c * (c - 1.0) / 2.0)


def _sum_j2(j0: FloatArray, c: FloatArray) -> FloatArray:
    """Σ j² for j = j0 … j0 + c − 1."""

    def upto(k: FloatArray) -> FloatArray:  # Σ j² for j = 0 … k − 1
        return np.asarray((k - 1.0) * k * (2.0 * k - 1.0) / 6.0)

    return np.asarray(upto(j0 + c) - upto(j0))


def _end_zones(
    n: IntArray, width: FloatArray, narrow: npt.NDArray[np.bool_], d: float
) -> tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Return the last strips per heading: ``(heading, u0, u1, line u, other line u, weight)``.

    Line n-2's strip and line n-1's; where they overlap (R2), both footprints count and
    their common part is taken back (inclusion–exclusion: the two lines' ends need not
    overlap at a slanted tip). A narrow cell has one strip, its whole width.
    """
    wide = (~narrow).nonzero()[0]
    nw, ww = n[wide].astype(float), width[wide]
    p_pen, p_last = (nw - 2.0) * d + d / 2.0, ww - d / 2.0
    thin = narrow.nonzero()[0]
    zone_h = np.concatenate([wide, wide, wide, wide, wide, thin])
    start, overlap_end = (nw - 2.0) * d, (nw - 1.0) * d
    z0 = np.concatenate([start, ww - d, ww - d, ww - d, overlap_end, np.zeros(len(thin))])
    z1 = np.concatenate([ww - d, overlap_end, overlap_end, overlap_end, ww, width[thin]])
    middle = width[thin] / 2.0
    u_a = np.concatenate([p_pen, p_pen, p_last, p_pen, p_last, middle])
    u_b = np.concatenate([p_pen, p_pen, p_last, p_last, p_last, middle])
    k = len(wide)
    weight = np.ones(5 * k + len(thin))
    weight[3 * k : 4 * k] = -1.0
    return zone_h.astype(np.int64), z0, z1, u_a, u_b, weight


def _positive_part(w: FloatArray, g0: FloatArray, g1: FloatArray) -> FloatArray:
    """∫ max(0, g) over a piece of width ``w`` where ``g`` runs linearly from g0 to g1."""
    high, low = np.maximum(g0, g1), np.minimum(g0, g1)
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing = w * high * high / (2.0 * (high - low))
    return np.asarray(
        np.where(low >= 0.0, w * (g0 + g1) / 2.0, np.where(high > 0.0, crossing, 0.0))
    )


def _covered_pieces(
    w: FloatArray,
    lo0: FloatArray,
    lo1: FloatArray,
    hi0: FloatArray,
    hi1: FloatArray,
    a: FloatArray,
    b: FloatArray,
) -> FloatArray:
    """∫ max(0, min(hi, b) − max(lo, a)) over pieces where ``lo`` and ``hi`` are linear.

    The height is linear between where ``hi`` crosses ``b`` and where ``lo`` crosses ``a``, so
    each piece is cut there (at most three sub-pieces) and integrated in closed form.
    """
    d_hi, d_lo = hi1 - hi0, lo1 - lo0
    with np.errstate(divide="ignore", invalid="ignore"):
        t_hi = np.where(d_hi != 0.0, (b - hi0) / d_hi, 0.0)
        t_lo = np.where(d_lo != 0.0, (a - lo0) / d_lo, 0.0)
    t_hi, t_lo = np.clip(t_hi, 0.0, 1.0), np.clip(t_lo, 0.0, 1.0)
    t1, t2 = np.minimum(t_hi, t_lo), np.maximum(t_hi, t_lo)

    def height(t: FloatArray) -> FloatArray:
        return np.asarray(np.minimum(hi0 + t * d_hi, b) - np.maximum(lo0 + t * d_lo, a))

    g0 = np.minimum(hi0, b) - np.maximum(lo0, a)
    g3 = np.minimum(hi1, b) - np.maximum(lo1, a)
    g1, g2 = height(t1), height(t2)
    # The three sub-pieces in one call (fixed numpy cost per call, not per element).
    n = len(w)
    parts = _positive_part(
        np.concatenate([t1 * w, (t2 - t1) * w, (1.0 - t2) * w]),
        np.concatenate([g0, g1, g2]),
        np.concatenate([g1, g2, g3]),
    )
    return np.asarray(parts[:n] + parts[n : 2 * n] + parts[2 * n :])
