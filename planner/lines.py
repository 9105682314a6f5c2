"""Tillage lines: where the parallel passes lie in a cell, for one heading or many at once.

Lines are computed in a *sweep frame* per heading: ``v`` runs along the lines and ``u``
across them, so every line is ``u = const`` from ``v_lo`` to ``v_hi``. A cell is a polygon that
each such line crosses once (convex, or monotone across the sweep), so a line's ends lie on
the cell's lower and upper chains. Positions follow R2 and R3: the first line ``interval/2``
inside the cell, the next ones ``interval`` apart, and the last ``interval/2`` inside the far
side, nearer its neighbour if need be.

All headings are evaluated together (one ragged array of lines): the angle search touches
each line of each heading a few times in numpy, never in a Python loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Relative slack when counting lines, so a width of exactly k intervals gives k lines.
_COUNT_EPS = 1e-9


def to_sweep(
    x: npt.ArrayLike, y: npt.ArrayLike, heading_deg: npt.ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Rotate local ``x, y`` [m] into the sweep frame ``u, v`` of ``heading_deg``.

    ``v`` points along the heading (degrees clockwise from north), ``u`` to its right.
    Arrays broadcast: headings of shape ``(A, 1)`` with points of shape ``(m,)`` give
    ``(A, m)``.

    Examples
    --------
    >>> [float(round(c, 9)) for c in to_sweep(0.0, 1.0, 90.0)]   # north is left of east
    [-1.0, 0.0]
    """
    theta = np.radians(heading_deg)
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    return x * cos_t - y * sin_t, x * sin_t + y * cos_t


def from_sweep(
    u: npt.ArrayLike, v: npt.ArrayLike, heading_deg: float
) -> tuple[FloatArray, FloatArray]:
    """Rotate sweep-frame ``u, v`` [m] of ``heading_deg`` back to local ``x, y``."""
    theta = math.radians(heading_deg)
    cos_t, sin_t = math.cos(theta), math.sin(theta)
    u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
    return u * cos_t + v * sin_t, -u * sin_t + v * cos_t


def line_counts(width_m: FloatArray, interval_m: float) -> IntArray:
    """Count the lines that cover a width [m] at ``interval_m`` (R2, R3).

    Examples
    --------
    >>> line_counts(np.array([3.0, 16.0, 16.5]), 4.0).tolist()
    [1, 4, 5]
    """
    extra = np.ceil((width_m - interval_m) / interval_m - _COUNT_EPS)
    return np.where(width_m <= interval_m, 1, extra.astype(np.int64) + 1).astype(np.int64)


def line_positions(u_min: float, u_max: float, interval_m: float) -> FloatArray:
    """Positions across the sweep of a cell's lines [m] (R2, R3).

    Examples
    --------
    >>> line_positions(0.0, 16.5, 4.0).tolist()
    [2.0, 6.0, 10.0, 14.0, 14.5]
    """
    d = float(interval_m)
    width = u_max - u_min
    n = int(line_counts(np.array([width]), d)[0])
    if width <= d:
        return np.array([(u_min + u_max) / 2.0])
    u = u_min + d / 2.0 + d * np.arange(n, dtype=float)
    u[-1] = u_max - d / 2.0
    return u


@dataclass(frozen=True, slots=True)
class LineScan:
    """The lines of one cell at many headings, as one ragged array.

    Lines of heading ``a`` are ``offsets[a]:offsets[a + 1]``, left to right (increasing
    ``u``). Coordinates are in each heading's own sweep frame.

    Attributes
    ----------
    headings_deg : ndarray, shape (A,)
    offsets : ndarray, shape (A + 1,)
    u, v_lo, v_hi : ndarray, shape (L,)
        Position across, and the two ends along, each line [m].
    """

    headings_deg: FloatArray
    offsets: IntArray
    u: FloatArray
    v_lo: FloatArray
    v_hi: FloatArray

    @property
    def counts(self) -> IntArray:
        """Number of lines per heading."""
        return np.diff(self.offsets)

    def heading_of_line(self) -> IntArray:
        """Index into ``headings_deg`` of every line."""
        return np.repeat(np.arange(len(self.headings_deg)), self.counts)


def scan_cell(ring_xy: FloatArray, headings_deg: FloatArray, interval_m: float) -> LineScan:
    """Place the lines of one cell for every heading in ``headings_deg``.

    Parameters
    ----------
    ring_xy : ndarray, shape (m, 2)
        The cell's exterior, counter-clockwise, without the closing vertex, local [m].
        Each line must cross it once (a convex cell, or one monotone across the sweep).
    headings_deg : ndarray, shape (A,)
        Line headings, degrees clockwise from north.
    interval_m : float
        Distance between lines [m].

    Returns
    -------
    LineScan
        One entry per heading.

    Examples
    --------
    >>> ring = np.array([[0.0, 0.0], [16.0, 0.0], [16.0, 20.0], [0.0, 20.0]])
    >>> scan = scan_cell(ring, np.array([0.0]), 4.0)
    >>> scan.u.tolist(), scan.v_lo.tolist(), scan.v_hi.tolist()
    ([2.0, 6.0, 10.0, 14.0], [0.0, 0.0, 0.0, 0.0], [20.0, 20.0, 20.0, 20.0])
    """
    headings_deg = np.asarray(headings_deg, dtype=float)
    u_ring, v_ring = to_sweep(ring_xy[:, 0], ring_xy[:, 1], headings_deg[:, None])
    scan = scan_cells(list(zip(u_ring, v_ring, strict=True)), interval_m)
    return LineScan(
        headings_deg=headings_deg, offsets=scan.offsets, u=scan.u, v_lo=scan.v_lo, v_hi=scan.v_hi
    )


def scan_cells(
    rings: list[tuple[FloatArray, FloatArray]], interval_m: float, *, edge_m: float | None = None
) -> LineScan:
    """Place the lines of many sweep-monotone cells at once, as one ragged array.

    Each line takes its ends from the lower-chain edge (``u`` increasing along the
    counter-clockwise ring) and the upper-chain edge (``u`` decreasing) whose ``u``-range holds
    it. Counting the lines left of a value arithmetically makes the edges' ranges tile the
    lines exactly, so each line gets one of each.

    Parameters
    ----------
    rings : list of (ndarray, ndarray)
        Each cell's exterior ``(u, v)`` in the sweep frame, counter-clockwise, not closed [m].
    interval_m : float
    edge_m : float, optional
        How far inside each cell's ends the outermost lines lie [m]; ``interval_m / 2`` (R3)
        by default. A cell of the machine area (the field eroded by half the vehicle) takes
        less, so that its lines still lie half an interval inside the field.

    Returns
    -------
    LineScan
        One entry per cell (``headings_deg`` is all zeros: the cells are already in a sweep
        frame).

    Examples
    --------
    >>> square = (np.array([0.0, 16.0, 16.0, 0.0]), np.array([0.0, 0.0, 20.0, 20.0]))
    >>> tri = (np.array([20.0, 26.0, 20.0]), np.array([0.0, 0.0, 6.0]))
    >>> scan = scan_cells([square, tri], 4.0)
    >>> scan.offsets.tolist(), scan.u.tolist(), scan.v_hi.tolist()
    ([0, 4, 6], [2.0, 6.0, 10.0, 14.0, 22.0, 24.0], [20.0, 20.0, 20.0, 20.0, 4.0, 2.0])
    """
    d = float(interval_m)
    sizes = np.array([len(u) for u, _ in rings])
    u1 = np.concatenate([u for u, _ in rings])
    v1 = np.concatenate([v for _, v in rings])
    cell_of_edge = np.repeat(np.arange(len(rings)), sizes)
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    # Each vertex's successor round its own ring.
    following = np.arange(1, len(u1) + 1)
    following[starts + sizes - 1] = starts
    u2, v2 = u1[following], v1[following]
    u_min = np.minimum.reduceat(u1, starts)
    u_max = np.maximum.reduceat(u1, starts)
    edge = d / 2.0 if edge_m is None else float(edge_m)
    width = u_max - u_min
    n = line_counts(width - 2.0 * edge + d, d)
    offsets = np.concatenate(([0], np.cumsum(n))).astype(np.int64)
    c_of_line = np.repeat(np.arange(len(rings)), n)
    k = np.arange(offsets[-1]) - offsets[c_of_line]
    narrow = width - 2.0 * edge <= 0.0
    first = np.where(narrow, (u_min + u_max) / 2.0, u_min + edge)
    last = np.where(narrow, first, u_max - edge)
    u = np.where(k == n[c_of_line] - 1, last[c_of_line], first[c_of_line] + k * d)
    v_lo = np.empty_like(u)
    v_hi = np.empty_like(u)
    for lower, target in ((True, v_lo), (False, v_hi)):
        e = np.nonzero((u2 > u1) if lower else (u2 < u1))[0]
        lo, hi = (u1[e], u2[e]) if lower else (u2[e], u1[e])
        c = cell_of_edge[e]
        k1 = _lines_left_of(lo, first[c], last[c], n[c], d)
        k2 = _lines_left_of(hi, first[c], last[c], n[c], d)
        per_edge = k2 - k1
        edge_of = np.repeat(np.arange(len(e)), per_edge)
        within = np.arange(per_edge.sum()) - np.repeat(np.cumsum(per_edge) - per_edge, per_edge)
        line = offsets[c[edge_of]] + k1[edge_of] + within
        ee = e[edge_of]
        target[line] = v1[ee] + (u[line] - u1[ee]) * (v2[ee] - v1[ee]) / (u2[ee] - u1[ee])
    return LineScan(headings_deg=np.zeros(len(rings)), offsets=offsets, u=u, v_lo=v_lo, v_hi=v_hi)


def _lines_left_of(
    value: FloatArray, first: FloatArray, last: FloatArray, n: IntArray, d: float
) -> IntArray:
    """Count a cell's line positions strictly left of ``value``."""
    regular = np.clip(np.ceil((value - first) / d), 0, n - 1).astype(np.int64)
    return regular + (last < value).astype(np.int64)
