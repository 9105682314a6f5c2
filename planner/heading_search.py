"""Cheap scores of every candidate heading over a whole (non-convex, holed) field.

Decomposing the field and ordering its cells costs milliseconds per heading; the angle search
tries ~200 headings. So every heading is first scored from the field's *ragged scan*: the lines
``interval`` apart across the whole field, each cut into pieces by the boundary and the holes.
With the exterior counter-clockwise and the holes clockwise, an edge running towards +u (in
the sweep frame) is where a line enters the field and an edge running towards -u where it
leaves, so the total working length is the sum of the exits' ``v`` minus the entries' ``v``,
and the number of line pieces is the number of entry crossings: closed forms per edge, no
intersection of lines at all. Only the best few headings are planned in full.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from shapely import Polygon

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Headings are scored in blocks of about this many (heading, vertex) values.
_BLOCK_VALUES = 1 << 15
#: A move into a new cell is estimated at most this many intervals long.
_NOTCH_HOP = 4.0


@dataclass(frozen=True, slots=True)
class HeadingScores:
    """Estimates per heading.

    Attributes
    ----------
    working_m : ndarray, shape (A,)
        Total length of the line pieces [m].
    pieces : ndarray, shape (A,)
        Number of line pieces (about the number of tillage lines).
    turn_backs : ndarray, shape (A,)
        Vertices (or runs of vertices) where a ring turns back across the sweep: each one
        starts or ends a cell.
    exteriors : int
        Number of polygons: each has two turn-backs (its ends) however it is swept.
    missed_m2 : ndarray, shape (A,)
        Estimate of the area the lines' footprints miss at slanted line ends: ``|s| d² / 8``
        per line end on an edge of slope ``s`` across the sweep (exact for a convex cell's
        inner strips), at most half the edge's extent along the lines times ``d``.
    turns_m : ndarray, shape (A,)
        Estimate of the turns' length: consecutive lines are joined along the boundary at
        alternate ends, so half of ``d·√(1 + s²)`` per line end (at most the edge's length).
    """

    working_m: FloatArray
    pieces: IntArray
    turn_backs: IntArray
    exteriors: int
    missed_m2: FloatArray
    turns_m: FloatArray

    def subset(self, keep: npt.NDArray[np.bool_]) -> HeadingScores:
        """Return the scores of the headings where ``keep`` is true."""
        return HeadingScores(
            self.working_m[keep],
            self.pieces[keep],
            self.turn_backs[keep],
            self.exteriors,
            self.missed_m2[keep],
            self.turns_m[keep],
        )

    def path_estimate_m(self, interval_m: float) -> FloatArray:
        """Working length, the turns, a line's length per extra cell.

        Every turn-back beyond each polygon's two ends splits or joins the sweep: another
        cell, and a move to it about as long as a line (at most :data:`_NOTCH_HOP` intervals).
        """
        mean_piece = self.working_m / np.maximum(self.pieces, 1)
        extra = np.maximum(self.turn_backs - 2 * self.exteriors, 0)
        # The move to a new cell is about a line long, but no longer than a short hop round
        # a notch: a comb's hundreds of teeth are neighbours, not a line apart each.
        move = np.minimum(mean_piece, _NOTCH_HOP * interval_m)
        return np.asarray(self.working_m + self.turns_m + extra * move)


def score_headings(
    parts_local: list[Polygon], headings_deg: FloatArray, interval_m: float
) -> HeadingScores:
    """Score every heading of ``headings_deg`` on the polygons ``parts_local``.

    Parameters
    ----------
    parts_local : list of Polygon
        The area the lines cover (holes allowed), oriented: exteriors counter-clockwise,
        holes clockwise; local [m].
    headings_deg : ndarray, shape (A,)
    interval_m : float

    Returns
    -------
    HeadingScores

    Examples
    --------
    A 40 m × 20 m rectangle at 4 m: north-south lines make 10 pieces of 20 m.

    >>> from shapely import box
    >>> s = score_headings([box(0, 0, 40, 20)], np.array([0.0, 90.0]), 4.0)
    >>> s.working_m.round(6).tolist(), s.pieces.tolist(), s.turn_backs.tolist()
    ([200.0, 200.0], [10, 5], [2, 2])
    """
    headings_deg = np.asarray(headings_deg, dtype=float)
    rings = [np.asarray(r.coords)[:-1] for p in parts_local for r in (p.exterior, *p.interiors)]
    # A long boundary in blocks of headings: arrays of a few hundred thousand numbers stay in
    # the cache (the wavy field's 20,000 vertices at 360 headings were 60 MB an array).
    xy = np.concatenate(rings)
    nxt = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
    sizes = [len(r) for r in rings]
    block = max(1, _BLOCK_VALUES // max(len(xy), 1))
    # The blocks' arrays are written into the same buffers, kept for the whole search: made
    # afresh for every block, the ~160 kB rows of a long boundary were each mapped from the
    # kernel anew (glibc hands allocations above 128 kB back when freed): 217,000 page
    # faults, 0.4 s of the wavy field's 0.7 s in a fresh process.
    scratch = np.empty((_SCRATCH_ARRAYS, min(block, len(headings_deg)), len(xy)))
    d, exteriors = float(interval_m), len(parts_local)
    if len(headings_deg) <= block:
        return _score_block(xy, nxt, sizes, headings_deg, d, exteriors, scratch)
    scores = [
        _score_block(xy, nxt, sizes, headings_deg[a : a + block], d, exteriors, scratch)
        for a in range(0, len(headings_deg), block)
    ]
    return HeadingScores(
        working_m=np.concatenate([s.working_m for s in scores]),
        pieces=np.concatenate([s.pieces for s in scores]),
        turn_backs=np.concatenate([s.turn_backs for s in scores]),
        exteriors=len(parts_local),
        missed_m2=np.concatenate([s.missed_m2 for s in scores]),
        turns_m=np.concatenate([s.turns_m for s in scores]),
    )


#: Arrays of a block's shape that :func:`_score_block` works in.
_SCRATCH_ARRAYS = 11


def _score_block(
    xy: FloatArray,
    nxt: FloatArray,
    sizes: list[int],
    headings_deg: FloatArray,
    d: float,
    exteriors: int,
    scratch: FloatArray,
) -> HeadingScores:
    """:func:`score_headings` at a block of headings, its per-edge terms compiled.

    :func:`planner.edge_kernels.score_terms` computes what :func:`_score_block_numpy`
    computes before its sums, by the same operations; the sums (numpy's pairwise ones) and
    the turn-backs stay here. ``tests/planner/test_cell_kernels.py`` holds the two equal.
    """
    from planner import edge_kernels  # numba: imported by the first plan that needs it

    rows = len(headings_deg)
    theta = np.radians(headings_deg)
    edge_kernels.score_terms(xy, nxt, np.cos(theta), np.sin(theta), d, scratch)
    working, missed, turns, pieces, du = scratch[:5, :rows]
    return HeadingScores(
        working_m=working.sum(axis=1),
        pieces=pieces.sum(axis=1).astype(np.int64),
        turn_backs=_turn_backs(du, sizes),
        exteriors=exteriors,
        missed_m2=missed.sum(axis=1),
        turns_m=turns.sum(axis=1) / 2.0,
    )


def _score_block_numpy(
    xy: FloatArray,
    nxt: FloatArray,
    sizes: list[int],
    headings_deg: FloatArray,
    d: float,
    exteriors: int,
    scratch: FloatArray,
) -> HeadingScores:
    """:func:`score_headings` at a block of headings: every ring's vertices and their next.

    ``scratch`` holds :data:`_SCRATCH_ARRAYS` arrays of at least the block's shape to work
    in: each operation is the one on fresh arrays, in the same order (the same numbers).
    """
    rows = len(headings_deg)
    u1, v1, u2, v2, lo, hi, k1, k2, du, slope, t = scratch[:, :rows]
    theta = np.radians(headings_deg[:, None])
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    for x, y, u, v in ((xy[:, 0], xy[:, 1], u1, v1), (nxt[:, 0], nxt[:, 1], u2, v2)):
        # planner.lines.to_sweep: u = x cos - y sin, v = x sin + y cos.
        np.multiply(x, cos_t, out=u)
        np.multiply(y, sin_t, out=t)
        np.subtract(u, t, out=u)
        np.multiply(x, sin_t, out=v)
        np.multiply(y, cos_t, out=t)
        np.add(v, t, out=v)
    first = u1.min(axis=1, keepdims=True) + d / 2.0
    # Lines k = 0, 1, … at first + k·d; an edge from u_a to u_b (u_a < u_b) holds those with
    # u_a <= u < u_b: k1 = max(ceil((u_a - first) / d), 0), k2 likewise.
    np.minimum(u1, u2, out=lo)
    np.maximum(u1, u2, out=hi)
    for bound, k in ((lo, k1), (hi, k2)):
        np.subtract(bound, first, out=k)
        np.divide(k, d, out=k)
        np.ceil(k, out=k)
        np.maximum(k, 0.0, out=k)
    count = np.subtract(k2, k1, out=lo)  # lo and hi are free from here on
    np.subtract(u2, u1, out=du)
    # slope = (v2 - v1) / du, 0 where du is.
    np.subtract(v2, v1, out=slope)
    with np.errstate(divide="ignore", invalid="ignore"):
        np.divide(slope, du, out=slope)
    slope[du == 0.0] = 0.0
    entering = du > 0.0
    # sum_k = (k1 + k2 - 1) count / 2; sum_v = count v1 + slope (count (first - u1) + d sum_k).
    sum_k = np.add(k1, k2, out=k1)
    np.subtract(sum_k, 1.0, out=sum_k)
    np.multiply(sum_k, count, out=sum_k)
    np.divide(sum_k, 2.0, out=sum_k)
    np.multiply(sum_k, d, out=sum_k)
    np.subtract(first, u1, out=t)
    np.multiply(count, t, out=t)
    np.add(t, sum_k, out=t)
    np.multiply(slope, t, out=t)
    sum_v = np.multiply(count, v1, out=hi)
    np.add(sum_v, t, out=sum_v)
    np.negative(sum_v, out=t, where=entering)
    np.copyto(t, sum_v, where=~entering)
    working = t.sum(axis=1)
    # missed = min(count |slope| d d / 8, |v2 - v1| d / 2), summed.
    dv = np.subtract(v2, v1, out=v1)
    np.abs(dv, out=dv)
    np.abs(slope, out=t)
    np.multiply(count, t, out=t)
    np.multiply(t, d, out=t)
    np.multiply(t, d, out=t)
    np.divide(t, 8.0, out=t)
    np.multiply(dv, d, out=k2)
    np.divide(k2, 2.0, out=k2)
    np.minimum(t, k2, out=t)
    missed = t.sum(axis=1)
    # turns = min(count d sqrt(1 + slope²), hypot(u2 - u1, dv)), summed, halved.
    edge_m = np.hypot(du, dv, out=u2)
    np.multiply(slope, slope, out=t)
    np.add(1.0, t, out=t)
    np.sqrt(t, out=t)
    np.multiply(count, d, out=k2)
    np.multiply(k2, t, out=t)
    np.minimum(t, edge_m, out=t)
    turns = t.sum(axis=1) / 2.0
    np.copyto(t, count)
    t[~entering] = 0.0
    pieces = t.sum(axis=1).astype(np.int64)
    return HeadingScores(
        working_m=working,
        pieces=pieces,
        turn_backs=_turn_backs(du, sizes),
        exteriors=exteriors,
        missed_m2=missed,
        turns_m=turns,
    )


def _turn_backs(du: FloatArray, sizes: list[int]) -> IntArray:
    """Per heading (rows of ``du``, each ring's edges' ``u2 - u1``), where rings turn back."""
    turn_backs = np.zeros(len(du), dtype=np.int64)
    start = 0
    for m in sizes:
        ring_du = du[:, start : start + m]
        start += m
        # Edges parallel to the lines take the direction of the edge before them, so the
        # ring turns back where an edge's direction differs from the last non-parallel
        # edge's before it (round the ring): compare each heading's non-parallel edges
        # with their predecessors among them, the first with the last.
        heading, _ = np.nonzero(ring_du)
        forward = ring_du[ring_du != 0.0] > 0.0
        if not len(forward):
            continue
        previous = np.empty_like(forward)
        previous[1:] = forward[:-1]
        ends = np.flatnonzero(np.diff(heading, append=-1))  # each heading's last edge
        begins = np.concatenate(([0], ends[:-1] + 1))
        previous[begins] = forward[ends]
        turn_backs += np.bincount(heading[forward != previous], minlength=len(du))
    return turn_backs
