"""Line order: the four ways to run a cell's lines back and forth, and their path lengths.

A variant is (which side first) × (which end first): ``left_up`` starts at the leftmost line
(smallest ``u``) driving towards ``v_hi``; ``left_down`` starts it towards ``v_lo``;
``right_up`` and ``right_down`` start at the rightmost line. Consecutive lines alternate
direction and are joined at the ends they share (Vasquez-Gomez et al. 2020).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from planner.lines import LineScan

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
    """

    working: FloatArray
    turns: FloatArray
    transit: FloatArray

    @property
    def total(self) -> FloatArray:
        """Whole path per heading and variant, shape (A, 4) [m]."""
        return self.working[:, None] + self.turns + self.transit


def variant_lengths(
    scan: LineScan,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
) -> VariantLengths:
    """Score the four variants of every heading in ``scan``.

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
    n_headings = len(scan.headings_deg)
    heading = scan.heading_of_line()
    counts = scan.counts
    working = np.bincount(heading, scan.v_hi - scan.v_lo, minlength=n_headings)

    # Turn k joins line k to line k + 1 of the same heading, at the top or at the bottom.
    k = np.arange(len(scan.u)) - scan.offsets[heading]
    has_next = k < counts[heading] - 1
    here = np.nonzero(has_next)[0]
    du = scan.u[here + 1] - scan.u[here]
    top = np.hypot(du, scan.v_hi[here + 1] - scan.v_hi[here])
    bottom = np.hypot(du, scan.v_lo[here + 1] - scan.v_lo[here])
    even = (k[here] % 2) == 0
    h = heading[here]
    top_even = np.bincount(h, top * even, minlength=n_headings)
    top_odd = np.bincount(h, top * ~even, minlength=n_headings)
    bottom_even = np.bincount(h, bottom * even, minlength=n_headings)
    bottom_odd = np.bincount(h, bottom * ~even, minlength=n_headings)
    left_up = top_even + bottom_odd  # line 0 drives up, so it turns at the top
    left_down = bottom_even + top_odd
    # Run from the right, line n-1-j drives up iff j is even: with n odd the turns swap.
    n_odd = (counts % 2) == 1
    right_up = np.where(n_odd, left_down, left_up)
    right_down = np.where(n_odd, left_up, left_down)
    turns = np.stack([left_up, left_down, right_up, right_down], axis=1)

    entry_u, entry_v, exit_u, exit_v = variant_ends(scan)
    transit = np.zeros((n_headings, 4))
    for point, (pu_at, pv_at) in ((start_xy, (entry_u, entry_v)), (finish_xy, (exit_u, exit_v))):
        if point is None:
            continue
        theta = np.radians(scan.headings_deg)
        pu = point[0] * np.cos(theta) - point[1] * np.sin(theta)
        pv = point[0] * np.sin(theta) + point[1] * np.cos(theta)
        transit += np.hypot(pu_at - pu[:, None], pv_at - pv[:, None])
    return VariantLengths(working=working, turns=turns, transit=transit)


def variant_ends(scan: LineScan) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Where each variant enters its first line and leaves its last, shape (A, 4) each.

    Returns
    -------
    entry_u, entry_v, exit_u, exit_v : ndarray, shape (A, 4)
        Sweep-frame coordinates [m], variants in :data:`VARIANTS` order.
    """
    first = scan.offsets[:-1]
    last = scan.offsets[1:] - 1
    ends_up = (scan.counts - 1) % 2 == 0  # the last line driven runs the way the first did
    lo_f, hi_f = scan.v_lo[first], scan.v_hi[first]
    lo_l, hi_l = scan.v_lo[last], scan.v_hi[last]
    u_f, u_l = scan.u[first], scan.u[last]
    entry_u = np.stack([u_f, u_f, u_l, u_l], axis=1)
    entry_v = np.stack([lo_f, hi_f, lo_l, hi_l], axis=1)
    exit_u = np.stack([u_l, u_l, u_f, u_f], axis=1)
    exit_v = np.stack(
        [
            np.where(ends_up, hi_l, lo_l),
            np.where(ends_up, lo_l, hi_l),
            np.where(ends_up, hi_f, lo_f),
            np.where(ends_up, lo_f, hi_f),
        ],
        axis=1,
    )
    return entry_u, entry_v, exit_u, exit_v


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
