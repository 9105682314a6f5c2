"""Turns: how the vehicle gets from the end of one line to the start of the next.

One function per turn type (Fields2Cover's ``PP_DubinsCurves`` and ``PP_ReedsSheppCurves``),
each taking many turns at once and returning the curves the vehicle drives, in local metres,
with points at most ``step_m`` apart (0.5 m) and close enough that the chords stay within
:data:`SAGITTA_M` of the arcs:

- :func:`pivot_turn`: a vehicle that pivots about a braked wheel (a walk-behind hand tractor).
  Its axle centre moves on a circle of radius ``track / 2`` round the stopped wheel, so a
  pivot is an arc of that radius and the vehicle is a Dubins car with radius ``track / 2``:
  two pivots shift the axle sideways by one track, the straight between them makes up the
  rest of the spacing; below one track, the extra manoeuvre is the Ω of three pivots (or,
  if it may reverse, the Reeds–Shepp manoeuvre with a short reverse).
- :func:`dubins_turn`: forward only, the shortest of the six Dubins words (Dubins 1957) at
  the minimum turning radius; closed forms after Shkel & Lumelsky (2001), vectorised.
- :func:`bulb_turn`: the Ω (bulb) turn, the CCC words only, for a radius larger than half
  the spacing.
- :func:`reeds_shepp_turn`: forwards and backwards (Reeds & Shepp 1990), one path per turn
  from the ``rsplan`` library.

Poses are ``(x, y, yaw)`` with ``yaw`` in radians counter-clockwise from +x (the textbook
convention of these curves), local [m].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Largest distance between two points of an exported turn [m] (product.md R1).
STEP_M = 0.5
#: Largest gap between an arc and its chords [m]: R1 allows 1 cm.
SAGITTA_M = 0.01
#: The six Dubins words; each letter's sign: +1 left, -1 right, 0 straight.
DUBINS_WORDS: dict[str, tuple[int, int, int]] = {
    "LSL": (1, 0, 1),
    "RSR": (-1, 0, -1),
    "LSR": (1, 0, -1),
    "RSL": (-1, 0, 1),
    "RLR": (-1, 1, -1),
    "LRL": (1, -1, 1),
}
BULB_WORDS = ("RLR", "LRL")


@dataclass(frozen=True, slots=True)
class TurnEnds:
    """Where many turns start and end: poses, local [m] and [rad].

    Attributes
    ----------
    x0, y0, yaw0 : ndarray, shape (T,)
        End of the line the vehicle leaves, and its heading there.
    x1, y1, yaw1 : ndarray, shape (T,)
        Start of the next line, and the heading it is driven in.
    """

    x0: FloatArray
    y0: FloatArray
    yaw0: FloatArray
    x1: FloatArray
    y1: FloatArray
    yaw1: FloatArray

    def __len__(self) -> int:
        """Return the number of turns."""
        return len(self.x0)

    def take(self, which: npt.NDArray[np.int64]) -> TurnEnds:
        """Return the turns ``which``, in that order."""
        return TurnEnds(
            self.x0[which], self.y0[which], self.yaw0[which],
            self.x1[which], self.y1[which], self.yaw1[which],
        )  # fmt: skip


@dataclass(frozen=True, slots=True)
class TurnCurves:
    """Driven curves of many turns, as one ragged array.

    Attributes
    ----------
    xy : ndarray, shape (P, 2)
        The points of every turn, start and end included, local [m].
    offsets : ndarray, shape (T + 1,)
        Turn ``k`` is ``xy[offsets[k]:offsets[k + 1]]``.
    length_m : ndarray, shape (T,)
        Length driven [m] (forwards plus backwards).
    turn_rad : ndarray, shape (T,)
        Total heading change [rad], for the time the vehicle spends turning.
    radius_m : float
        Radius of the arcs [m]: curvature never above ``1 / radius_m``.
    """

    xy: FloatArray
    offsets: IntArray
    length_m: FloatArray
    turn_rad: FloatArray
    radius_m: float

    def curve(self, k: int) -> FloatArray:
        """Points of turn ``k``, shape (p, 2)."""
        return self.xy[self.offsets[k] : self.offsets[k + 1]]

    def __len__(self) -> int:
        """Return the number of turns."""
        return len(self.offsets) - 1

    def point_counts(self) -> IntArray:
        """Points of each turn, shape (T,).

        ``np.diff(offsets)``'s values, by slices subtracted: without its overhead on a few
        turns (called every fitting round).
        """
        return self.offsets[1:] - self.offsets[:-1]


def pivot_turn(
    ends: TurnEnds, *, track_m: float, can_reverse: bool = False, step_m: float = STEP_M
) -> TurnCurves:
    """Plan the turns of a vehicle that pivots about a braked wheel, as it really moves.

    Pulling one clutch stops that wheel and the other drives round it: the axle centre moves
    on a circle of radius ``track_m / 2`` about the stopped wheel. Two quarter pivots at a
    headland therefore shift the axle sideways by exactly one track, and the straight move
    between them supplies the rest of the spacing; at a spacing below one track the vehicle
    needs another manoeuvre: forward only, the Ω of three pivots (turn away, round, back);
    with ``can_reverse``, a pivot, a short reverse and a pivot (Reeds–Shepp).

    Parameters
    ----------
    ends : TurnEnds
    track_m : float
        Distance between the wheels [m], > 0.
    can_reverse : bool
        Whether the vehicle may back up.
    step_m : float
        Largest distance between points [m].

    Returns
    -------
    TurnCurves
        Arcs of radius ``track_m / 2``.

    Examples
    --------
    A 4 m U-turn of a 0.7 m-track hand tractor: two quarter pivots and 3.3 m straight.

    >>> ends = TurnEnds(*(np.array([v]) for v in (0.0, 0.0, math.pi / 2, 4.0, 0.0, -math.pi / 2)))
    >>> turn = pivot_turn(ends, track_m=0.7)
    >>> round(float(turn.length_m[0]), 3), round(float(turn.curve(0)[:, 1].max()), 3)
    (4.4, 0.35)
    """
    radius = track_m / 2.0
    if can_reverse:
        return reeds_shepp_turn(ends, radius_m=radius, step_m=step_m)
    return dubins_turn(ends, radius_m=radius, step_m=step_m)


def dubins_turn(
    ends: TurnEnds,
    *,
    radius_m: float,
    step_m: float = STEP_M,
    words: tuple[str, ...] = tuple(DUBINS_WORDS),
) -> TurnCurves:
    """Shortest forward-only turns with a minimum turning radius (Dubins curves).

    Every turn tries the words in ``words`` in closed form and keeps the shortest; all turns
    are solved together in numpy.

    Parameters
    ----------
    ends : TurnEnds
    radius_m : float
        Minimum turning radius [m], > 0.
    step_m : float
        Largest distance between points [m].
    words : tuple of str
        Dubins words allowed (``LSL``, ``RSR``, ``LSR``, ``RSL``, ``RLR``, ``LRL``).

    Returns
    -------
    TurnCurves

    Examples
    --------
    A 10 m U-turn at a 3 m radius: two quarter circles and 4 m straight.

    >>> ends = TurnEnds(*(np.array([v]) for v in (0.0, 0.0, math.pi / 2, 10.0, 0.0, -math.pi / 2)))
    >>> round(float(dubins_turn(ends, radius_m=3.0).length_m[0]), 4)
    13.4248
    """
    signs, params = dubins_words(ends, radius_m=radius_m, words=words)
    return _sample(ends, signs, params * radius_m, radius_m, step_m)


def dubins_turn_length_m(
    ends: TurnEnds, *, radius_m: float, words: tuple[str, ...] = tuple(DUBINS_WORDS)
) -> FloatArray:
    """Lengths of :func:`dubins_turn`'s curves, without sampling them [m].

    Examples
    --------
    >>> ends = TurnEnds(*(np.array([v]) for v in (0.0, 0.0, math.pi / 2, 10.0, 0.0, -math.pi / 2)))
    >>> round(float(dubins_turn_length_m(ends, radius_m=3.0)[0]), 4)
    13.4248
    """
    _, params = dubins_words(ends, radius_m=radius_m, words=words)
    return np.asarray(np.abs(params * radius_m).sum(axis=1), dtype=float)


def bulb_turn(ends: TurnEnds, *, radius_m: float, step_m: float = STEP_M) -> TurnCurves:
    """Ω (bulb) turns: away, round and back, for a radius larger than half the spacing.

    A vehicle whose turning circle is wider than the spacing cannot reach the next line by
    two turns in one direction; it swings out the other way first. These are the Dubins CCC
    words (``RLR``, ``LRL``).

    Examples
    --------
    A 2 m spacing at a 3 m radius: the bulb reaches 3 + √(36 − 16) ≈ 7.47 m past the line end.

    >>> ends = TurnEnds(*(np.array([v]) for v in (0.0, 0.0, math.pi / 2, 2.0, 0.0, -math.pi / 2)))
    >>> round(float(bulb_turn(ends, radius_m=3.0).curve(0)[:, 1].max()), 2)
    7.47
    """
    return dubins_turn(ends, radius_m=radius_m, step_m=step_m, words=BULB_WORDS)


def reeds_shepp_turn(ends: TurnEnds, *, radius_m: float, step_m: float = STEP_M) -> TurnCurves:
    """Shortest turns forwards and backwards with a minimum turning radius (Reeds–Shepp).

    One path per turn from ``rsplan`` (Built Robotics' implementation of Reeds & Shepp
    1990, shortest path kept), sampled here like the other turns.

    Examples
    --------
    Below twice the radius, backing up beats the bulb:

    >>> ends = TurnEnds(*(np.array([v]) for v in (0.0, 0.0, math.pi / 2, 2.0, 0.0, -math.pi / 2)))
    >>> backing = reeds_shepp_turn(ends, radius_m=3.0)
    >>> bool(backing.length_m[0] < bulb_turn(ends, radius_m=3.0).length_m[0])
    True
    """
    from rsplan.planner import path as rs_path  # pure Python; imported on first use only

    n = len(ends)
    signs = np.zeros((n, 5), dtype=np.int64)
    lengths = np.zeros((n, 5))
    backwards = np.zeros((n, 5), dtype=bool)
    kinds = {"left": 1, "right": -1, "straight": 0}
    for k in range(n):
        path = rs_path(
            (float(ends.x0[k]), float(ends.y0[k]), float(ends.yaw0[k])),
            (float(ends.x1[k]), float(ends.y1[k]), float(ends.yaw1[k])),
            radius_m,
            0.0,
            step_m,
            length_tolerance=0.0,
        )
        for s, segment in enumerate(path.segments[:5]):
            signs[k, s] = kinds[segment.type]
            lengths[k, s] = abs(float(segment.length))
            backwards[k, s] = segment.direction < 0
    return _sample(ends, signs, np.where(backwards, -lengths, lengths), radius_m, step_m)


def dubins_words(
    ends: TurnEnds, *, radius_m: float, words: tuple[str, ...] = tuple(DUBINS_WORDS)
) -> tuple[IntArray, FloatArray]:
    """Find the shortest Dubins word of every turn: segment signs and normalised lengths.

    Compiled (:func:`planner.fit_kernels.dubins_words`);
    :func:`planner.turn_references.dubins_words_numpy` is the reference it equals bit for bit.

    Returns
    -------
    signs : ndarray of int, shape (T, 3)
        +1 left arc, -1 right arc, 0 straight.
    params : ndarray, shape (T, 3)
        Segment lengths divided by ``radius_m`` (arc angles [rad] for arcs).
    """
    from planner import fit_kernels  # numba: imported by the first plan that needs it

    unknown = [w for w in words if w not in DUBINS_WORDS]
    if unknown:
        raise ValueError(f"unknown Dubins word {unknown[0]!r}")
    codes = np.array([_WORD_INDEX[w] for w in words], dtype=np.int64)
    best, params = fit_kernels.dubins_words(
        ends.x0, ends.y0, ends.yaw0, ends.x1, ends.y1, ends.yaw1, radius_m, codes
    )
    if len(best) and best.min() < 0:
        raise ValueError("no Dubins word joins these poses")  # only if ``words`` is narrowed
    return _WORD_SIGNS[codes[best]], params


#: Each Dubins word's index in :data:`DUBINS_WORDS`, and the signs of its three segments.
_WORD_INDEX = {word: k for k, word in enumerate(DUBINS_WORDS)}
_WORD_SIGNS = np.array(list(DUBINS_WORDS.values()), dtype=np.int64)


def turn_depth_m(
    curves: TurnCurves, x0: FloatArray, y0: FloatArray, yaw0: FloatArray
) -> FloatArray:
    """How far each turn reaches beyond its start, along the start heading [m]."""
    k = np.repeat(np.arange(len(curves)), curves.point_counts())
    along = (curves.xy[:, 0] - x0[k]) * np.cos(yaw0[k]) + (curves.xy[:, 1] - y0[k]) * np.sin(
        yaw0[k]
    )
    depth = np.full(len(curves), -np.inf)
    np.maximum.at(depth, k, along)
    return depth


def _sample(
    ends: TurnEnds, signs: IntArray, lengths: FloatArray, radius_m: float, step_m: float
) -> TurnCurves:
    """Integrate and sample segments (sign: arc direction; signed length: backwards < 0).

    The points come from :func:`planner.fit_kernels.sample_turns`, which equals
    :func:`planner.turn_references.sample_numpy` bit for bit.
    """
    from planner import fit_kernels  # numba: imported by the first plan that needs it

    arc_step = min(step_m, 2.0 * radius_m * math.acos(max(-1.0, 1.0 - SAGITTA_M / radius_m)))
    xy, offsets = fit_kernels.sample_turns(
        ends.x0, ends.y0, ends.yaw0, ends.x1, ends.y1, signs, lengths, radius_m, arc_step, step_m
    )
    size = np.abs(lengths)
    turning = np.where(signs != 0, size / radius_m, 0.0).sum(axis=1)
    return TurnCurves(xy, offsets, size.sum(axis=1), turning, float(radius_m))


def driving_time_s(
    x: FloatArray, y: FloatArray, *, speed_mps: float, turn_rate_dps: float
) -> float:
    """Time to drive a polyline [s]: at ``speed_mps``, slower where it turns.

    A vertex between two short steps (at most :data:`STEP_M`, a sampled turn) is on an arc:
    the steps beside it take ``max(length / speed, heading change / turn rate)``. A vertex
    between longer steps is a corner the vehicle turns on the spot: its angle at the turn
    rate comes on top.

    Examples
    --------
    >>> round(driving_time_s(np.array([0.0, 0, 4, 4]), np.array([0.0, 10, 10, 0]),
    ...                      speed_mps=0.56, turn_rate_dps=45.0), 2)   # two right angles
    46.86
    """
    from planner import fit_kernels  # numba: imported by the first plan that needs it

    # Compiled: the steps and corners as driving_time_numpy (turn_references) finds them.
    per_step, corner = fit_kernels.driving_times(
        x, y, speed_mps, math.radians(turn_rate_dps), STEP_M + 1e-9
    )
    if len(per_step) == 0:
        return 0.0
    return float(per_step.sum()) + float(corner.sum()) / math.radians(turn_rate_dps)


def turning_radius_m(vehicle: Vehicle) -> float:
    """Radius of the vehicle's tightest arc [m]: its minimum, or half its track if it pivots.

    Examples
    --------
    >>> from planner.vehicles import resolve_vehicle
    >>> turning_radius_m(resolve_vehicle("hand_tractor")), turning_radius_m(
    ...     resolve_vehicle("small_tractor"))
    (0.35, 3.0)
    """
    if vehicle.min_turn_radius_m > 0.0:
        return float(vehicle.min_turn_radius_m)
    return float(vehicle.track_m) / 2.0


#: Turns of the same shape are found when there are at least this many (below, finding
#: them costs more than it saves).
_SHAPES_FROM = 16


def vehicle_turns(
    ends: TurnEnds, vehicle: Vehicle, *, step_m: float = STEP_M, shared_shapes: bool = True
) -> TurnCurves:
    """Plan the turns ``vehicle`` drives between the given ends: the right type per turn.

    A vehicle that pivots (``min_turn_radius_m`` 0) takes :func:`pivot_turn`; one with a
    radius takes :func:`reeds_shepp_turn` if it may reverse, else :func:`dubins_turn`, or
    :func:`bulb_turn` where the lines are less than two radii apart.

    A turn depends only on where its end is relative to its start (and the two headings):
    along one edge of a field every U-turn is the same, so each distinct shape is planned
    once, from the origin, and translated to its turns. ``shared_shapes=False`` skips that
    search for callers whose turns all differ (the candidate moves between cells, each
    with its own pulls): every turn is planned as its own shape, to the same points.
    """
    n = len(ends)
    if n < _SHAPES_FROM or not shared_shapes:  # every turn its own shape
        zero = np.zeros(n)
        dx, dy = ends.x1 - ends.x0, ends.y1 - ends.y0
        planned = _forward_turns(dx, dy, ends.yaw0, ends.yaw1, None, ends, vehicle, step_m)
        if planned is not None:
            return planned
        shapes = _vehicle_turns(TurnEnds(zero, zero, ends.yaw0, dx, dy, ends.yaw1), vehicle, step_m)
        return _translate(shapes, None, ends)
    relative = np.stack([ends.x1 - ends.x0, ends.y1 - ends.y0, ends.yaw0, ends.yaw1])
    # Every shape is planned from the origin, then moved onto its ends, and turns share a
    # shape only if their relative ends are the same to the last bit: so a turn's shape
    # depends on its own relative ends alone, not on where the field lies nor on which turns
    # are planned with it. (Equally long Reeds–Shepp words, mirror images of each other, go
    # either way with the last bit: shared to 1e-9, a field fitted at many headings at once
    # pulled some line ends back 0.2 m further than fitted alone. Rounded to 1e-9 instead, a
    # straight move bent into a 37 m Dubins loop.)
    # Distinct rows by one stable lexsort (np.unique on rows is many times slower).
    order = np.lexsort(relative[::-1])
    fresh = np.ones(n, dtype=bool)
    fresh[1:] = (np.diff(relative[:, order], axis=1) != 0.0).any(axis=0)
    first = order[fresh]  # each shape's first turn: lexsort keeps equal keys in order
    shape_of = np.empty(n, dtype=np.int64)
    shape_of[order] = np.cumsum(fresh) - 1
    dx, dy, yaw0, yaw1 = relative[:, first]
    planned = _forward_turns(dx, dy, yaw0, yaw1, shape_of, ends, vehicle, step_m)
    if planned is not None:
        return planned
    zero = np.zeros(len(first))
    shapes = _vehicle_turns(TurnEnds(zero, zero, yaw0, dx, dy, yaw1), vehicle, step_m)
    return _translate(shapes, shape_of, ends)


def _forward_turns(
    dx: FloatArray,
    dy: FloatArray,
    yaw0: FloatArray,
    yaw1: FloatArray,
    shape_of: IntArray | None,
    ends: TurnEnds,
    vehicle: Vehicle,
    step_m: float,
) -> TurnCurves | None:
    """Plan a forward-only vehicle's turns in one call; None if it may reverse or there are none.

    Shape ``s`` runs from the origin to ``(dx, dy)[s]``; turn ``k`` is shape ``shape_of[k]``
    (None: shape ``k``) moved onto its ends. The same points as ``_vehicle_turns`` and
    :func:`_translate` give (:func:`planner.turn_kernels.planned_turns`), without their
    numpy calls on a few turns each.
    """
    if vehicle.can_reverse or len(dx) == 0:
        return None
    from planner import turn_kernels  # numba: imported by the first plan that needs it

    radius = turning_radius_m(vehicle)
    if vehicle.min_turn_radius_m > 0.0:  # bulbs below two radii (a pivot: Dubins throughout)
        narrow = np.hypot(dx, dy) < 2.0 * radius - 1e-9
    else:
        narrow = np.zeros(len(dx), dtype=bool)
    arc_step = min(step_m, 2.0 * radius * math.acos(max(-1.0, 1.0 - SAGITTA_M / radius)))
    planned = turn_kernels.planned_turns(
        dx,
        dy,
        yaw0,
        yaw1,
        narrow,
        radius,
        arc_step,
        step_m,
        np.arange(len(dx)) if shape_of is None else shape_of,
        (ends.x0, ends.y0, ends.x1, ends.y1),
    )
    if planned is None:
        raise ValueError("no Dubins word joins these poses")  # as dubins_words
    xy, offsets, signs, lengths = planned
    size = np.abs(lengths)
    length = size.sum(axis=1)
    turning = np.where(signs != 0, size / radius, 0.0).sum(axis=1)
    if shape_of is not None:
        length, turning = length[shape_of], turning[shape_of]
    return TurnCurves(xy, offsets, length, turning, float(radius))


def _translate(shapes: TurnCurves, shape_of: IntArray | None, ends: TurnEnds) -> TurnCurves:
    """Turn ``k`` is ``shapes``' turn ``shape_of[k]`` moved to start at its own start.

    ``shape_of`` None: turn ``k`` is shape ``k``, and ``shapes`` (the caller's own) is moved
    in place.
    """
    from planner import fit_kernels  # numba: imported by the first plan that needs it

    curves = shapes if shape_of is None else take_turns(shapes, shape_of)
    # Each curve moved by its start, and starting and ending exactly on its own line ends
    # (compiled: turn_references.translate_numpy is the reference).
    fit_kernels.translate_turns(curves.xy, curves.offsets, ends.x0, ends.y0, ends.x1, ends.y1)
    return curves


def no_turns(vehicle: Vehicle) -> TurnCurves:
    """Return an empty set of the vehicle's turns (a cell of one line)."""
    return TurnCurves(
        np.zeros((0, 2)), np.zeros(1, dtype=np.int64), np.zeros(0), np.zeros(0),
        turning_radius_m(vehicle),
    )  # fmt: skip


def take_turns(curves: TurnCurves, ids: IntArray) -> TurnCurves:
    """Return the turns ``ids`` of ``curves`` (any order, repeats allowed), as a new array."""
    sizes = curves.point_counts()[ids]
    offsets = np.zeros(len(ids) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    point = np.repeat(curves.offsets[ids] - offsets[:-1], sizes) + np.arange(offsets[-1])
    return TurnCurves(
        curves.xy[point], offsets, curves.length_m[ids], curves.turn_rad[ids], curves.radius_m
    )


def turn_range(curves: TurnCurves, first: int, stop: int) -> TurnCurves:
    """Return the turns ``first … stop - 1`` of ``curves`` (views where it can)."""
    begin, end = int(curves.offsets[first]), int(curves.offsets[stop])
    return TurnCurves(
        curves.xy[begin:end],
        curves.offsets[first : stop + 1] - begin,
        curves.length_m[first:stop],
        curves.turn_rad[first:stop],
        curves.radius_m,
    )


def concat_turns(a: TurnCurves, b: TurnCurves) -> TurnCurves:
    """Return the turns of ``a`` followed by those of ``b`` (the same vehicle)."""
    return TurnCurves(
        np.concatenate([a.xy, b.xy]),
        np.concatenate([a.offsets, b.offsets[1:] + a.offsets[-1]]),
        np.concatenate([a.length_m, b.length_m]),
        np.concatenate([a.turn_rad, b.turn_rad]),
        a.radius_m,
    )


def _vehicle_turns(ends: TurnEnds, vehicle: Vehicle, step_m: float) -> TurnCurves:
    radius = turning_radius_m(vehicle)
    if vehicle.min_turn_radius_m <= 0.0:
        return pivot_turn(
            ends, track_m=vehicle.track_m, can_reverse=vehicle.can_reverse, step_m=step_m
        )
    if vehicle.can_reverse:
        return reeds_shepp_turn(ends, radius_m=radius, step_m=step_m)
    spacing = np.hypot(ends.x1 - ends.x0, ends.y1 - ends.y0)
    narrow = spacing < 2.0 * radius - 1e-9
    if not narrow.any():
        return dubins_turn(ends, radius_m=radius, step_m=step_m)
    if narrow.all():
        return bulb_turn(ends, radius_m=radius, step_m=step_m)
    wide = dubins_turn(_subset(ends, ~narrow), radius_m=radius, step_m=step_m)
    bulbs = bulb_turn(_subset(ends, narrow), radius_m=radius, step_m=step_m)
    return _merge(wide, bulbs, ~narrow)


def _subset(ends: TurnEnds, keep: npt.NDArray[np.bool_]) -> TurnEnds:
    return TurnEnds(
        ends.x0[keep], ends.y0[keep], ends.yaw0[keep], ends.x1[keep], ends.y1[keep], ends.yaw1[keep]
    )


def _merge(a: TurnCurves, b: TurnCurves, from_a: npt.NDArray[np.bool_]) -> TurnCurves:
    """Interleave two sets of turns: turn ``k`` from ``a`` where ``from_a[k]``, else ``b``."""
    n = len(from_a)
    size_a, size_b = a.point_counts(), b.point_counts()
    sizes = np.empty(n, dtype=np.int64)
    sizes[from_a], sizes[~from_a] = size_a, size_b
    offsets = np.concatenate(([0], np.cumsum(sizes))).astype(np.int64)
    xy = np.empty((offsets[-1], 2))
    owner = np.repeat(np.arange(n), sizes)
    xy[from_a[owner]] = a.xy
    xy[~from_a[owner]] = b.xy
    length = np.empty(n)
    turn = np.empty(n)
    length[from_a], length[~from_a] = a.length_m, b.length_m
    turn[from_a], turn[~from_a] = a.turn_rad, b.turn_rad
    return TurnCurves(xy, offsets, length, turn, a.radius_m)
