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
    """Place the lines of a convex cell for every heading in ``headings_deg``.

    Parameters
    ----------
    ring_xy : ndarray, shape (m, 2)
        The cell's exterior, counter-clockwise, without the closing vertex, local [m].
        Each line must cross it once (a convex cell).
    headings_deg : ndarray, shape (A,)
        Line headings, degrees clockwise from north.
    interval_m : float
        Distance between lines [m].

    Returns
    -------
    LineScan

    Examples
    --------
    >>> ring = np.array([[0.0, 0.0], [16.0, 0.0], [16.0, 20.0], [0.0, 20.0]])
    >>> scan = scan_cell(ring, np.array([0.0]), 4.0)
    >>> scan.u.tolist(), scan.v_lo.tolist(), scan.v_hi.tolist()
    ([2.0, 6.0, 10.0, 14.0], [0.0, 0.0, 0.0, 0.0], [20.0, 20.0, 20.0, 20.0])
    """
    headings_deg = np.asarray(headings_deg, dtype=float)
    d = float(interval_m)
    # Ring vertices in every heading's sweep frame: shape (A, m).
    u_ring, v_ring = to_sweep(ring_xy[:, 0], ring_xy[:, 1], headings_deg[:, None])
    u_min, u_max = u_ring.min(axis=1), u_ring.max(axis=1)
    width = u_max - u_min
    n = line_counts(width, d)
    offsets = np.concatenate(([0], np.cumsum(n))).astype(np.int64)
    a_of_line = np.repeat(np.arange(len(headings_deg)), n)
    k = np.arange(offsets[-1]) - offsets[a_of_line]
    narrow = width <= d
    # Regular positions from the near side; the last line d/2 inside the far side (R2, R3).
    first = np.where(narrow, (u_min + u_max) / 2.0, u_min + d / 2.0)
    last = np.where(narrow, first, u_max - d / 2.0)
    u = np.where(k == n[a_of_line] - 1, last[a_of_line], first[a_of_line] + k * d)

    # Each line takes its ends from the lower-chain edge (u increasing) and the upper-chain
    # edge (u decreasing) whose u-range holds it. Counting lines left of a value
    # arithmetically makes the edges' ranges tile [0, n) exactly, so each line gets one of each.
    u1, v1 = u_ring, v_ring
    u2, v2 = np.roll(u_ring, -1, axis=1), np.roll(v_ring, -1, axis=1)
    v_lo = np.empty_like(u)
    v_hi = np.empty_like(u)
    for lower, (lo, hi), target in (
        (True, (u1, u2), v_lo),
        (False, (u2, u1), v_hi),
    ):
        mask = (u2 > u1) if lower else (u2 < u1)
        a_idx, e_idx = np.nonzero(mask)
        k1 = _lines_left_of(lo[a_idx, e_idx], first[a_idx], last[a_idx], n[a_idx], d)
        k2 = _lines_left_of(hi[a_idx, e_idx], first[a_idx], last[a_idx], n[a_idx], d)
        per_edge = k2 - k1
        edge_of = np.repeat(np.arange(len(a_idx)), per_edge)
        within = np.arange(per_edge.sum()) - np.repeat(np.cumsum(per_edge) - per_edge, per_edge)
        line = offsets[a_idx[edge_of]] + k1[edge_of] + within
        ea, ee = a_idx[edge_of], e_idx[edge_of]
        eu1, ev1, eu2, ev2 = u1[ea, ee], v1[ea, ee], u2[ea, ee], v2[ea, ee]
        target[line] = ev1 + (u[line] - eu1) * (ev2 - ev1) / (eu2 - eu1)
    return LineScan(headings_deg=headings_deg, offsets=offsets, u=u, v_lo=v_lo, v_hi=v_hi)


def _lines_left_of(
    value: FloatArray, first: FloatArray, last: FloatArray, n: IntArray, d: float
) -> IntArray:
    """How many of a heading's line positions lie strictly left of ``value``."""
    regular = np.clip(np.ceil((value - first) / d), 0, n - 1).astype(np.int64)
    return regular + (last < value).astype(np.int64)
