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

from planner.lines import to_sweep

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
    if len(headings_deg) <= block:
        return _score_block(xy, nxt, sizes, headings_deg, float(interval_m), len(parts_local))
    scores = [
        _score_block(
            xy, nxt, sizes, headings_deg[a : a + block], float(interval_m), len(parts_local)
        )
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


def _score_block(
    xy: FloatArray,
    nxt: FloatArray,
    sizes: list[int],
    headings_deg: FloatArray,
    d: float,
    exteriors: int,
) -> HeadingScores:
    """:func:`score_headings` at a block of headings: every ring's vertices and their next."""
    u1, v1 = to_sweep(xy[:, 0], xy[:, 1], headings_deg[:, None])
    u2, v2 = to_sweep(nxt[:, 0], nxt[:, 1], headings_deg[:, None])
    first = u1.min(axis=1, keepdims=True) + d / 2.0
    # Lines k = 0, 1, … at first + k·d; an edge from u_a to u_b (u_a < u_b) holds those with
    # u_a <= u < u_b.
    lo, hi = np.minimum(u1, u2), np.maximum(u1, u2)
    k1 = np.maximum(np.ceil((lo - first) / d), 0.0)
    k2 = np.maximum(np.ceil((hi - first) / d), 0.0)
    count = k2 - k1
    du = u2 - u1
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(du != 0.0, (v2 - v1) / du, 0.0)
    sum_k = (k1 + k2 - 1.0) * count / 2.0
    sum_v = count * v1 + slope * (count * (first - u1) + d * sum_k)
    entering = du > 0.0
    working = np.where(entering, -sum_v, sum_v).sum(axis=1)
    dv = np.abs(v2 - v1)
    missed = np.minimum(count * np.abs(slope) * d * d / 8.0, dv * d / 2.0).sum(axis=1)
    edge_m = np.hypot(u2 - u1, dv)
    turns = np.minimum(count * d * np.sqrt(1.0 + slope * slope), edge_m).sum(axis=1) / 2.0
    pieces = np.where(entering, count, 0.0).sum(axis=1).astype(np.int64)

    turn_backs = np.zeros(len(headings_deg), dtype=np.int64)
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
        turn_backs += np.bincount(heading[forward != previous], minlength=len(headings_deg))
    return HeadingScores(
        working_m=working,
        pieces=pieces,
        turn_backs=turn_backs,
        exteriors=exteriors,
        missed_m2=missed,
        turns_m=turns,
    )
