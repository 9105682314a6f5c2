"""The spiral's route built round by round: each round driven once, and drivable joins.

After a full round the vehicle drives on along it until a lane change to the next round (or
the move to the core's first line) fits inside the field for its body: a forward Dubins
curve (:func:`planner.turns.dubins_turn`), so the route is one continuous, drivable path.
Where no such curve is found, and between two parts of the core, the join is a chain of the
vehicle's turns beside the shortest path's corners (:mod:`planner.move_curves`), else its
arcs searched for (:mod:`planner.move_search`), and only failing both the shortest move
inside the field (:class:`planner.routing.FieldRouter`), with corners. The rounds and the
core are :mod:`planner.spiral`'s.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import numpy.typing as npt
import shapely
from scipy.spatial import cKDTree  # type: ignore[import-untyped]
from shapely import LinearRing

from planner.move_curves import drivable_moves
from planner.move_search import search_move
from planner.round_corners import corner_loops
from planner.round_shapes import resample_ring, round_step_m
from planner.route_builder import RouteBuilder, densify
from planner.routing import FieldRouter
from planner.turns import STEP_M, TurnEnds, dubins_turn, dubins_turn_length_m
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]

#: Poses a join's search expands at most (a spiral asks for few: more than a move between
#: cells may).
SEARCHED_POSES = 5000

#: Candidate joins checked exactly (chords and all), cheapest first.
_EXACT_CHECKS = 32
#: Candidate joins sampled and tested in the first batch (each next batch is 4 times larger).
_FIRST_BATCH = 64
#: ... and at most this many (each can be hundreds of points).
_LAST_BATCH = 4096
#: The first test of a batch looks at one point in this many.
_SPARSE_STRIDE = 16


class RoundJoiner:
    """Builds the route: rounds driven once round, and drivable joins between them."""

    def __init__(
        self,
        route: RouteBuilder,
        router: FieldRouter,
        allowed: shapely.Geometry,
        radius: float,
        *,
        loops: bool = False,
        vehicle: Vehicle | None = None,
    ) -> None:
        self.route = route
        self.router = router
        self.allowed = allowed
        self.radius = radius
        self.step = round_step_m(radius)
        self.loops = loops  # corner loops (planner.round_corners) in every round
        #: A vehicle with a turning radius: where no curve joins, its arcs are searched.
        self.vehicle = vehicle
        #: The rounds as driven, in pieces that do not overlap themselves, in order.
        self.driven: list[FloatArray] = []
        #: The round being driven, its points from the entry on, and its round index.
        self.ring: FloatArray | None = None
        self.ring_index: int | None = None

    def position(self) -> tuple[float, float] | None:
        """Where the vehicle is once the current round is driven (its entry point)."""
        if self.ring is not None:
            return float(self.ring[0, 0]), float(self.ring[0, 1])
        return self.route.here()

    def add_round(self, ring: LinearRing, index: int) -> None:
        """Drive ``ring`` once round (the exterior anticlockwise, holes clockwise)."""
        points = resample_ring(ring, self.step)
        if self.loops:
            points = corner_loops(
                points, radius_m=self.radius, allowed=self.allowed, step_m=self.step
            )
        if self.ring is None:
            here = self.route.here()
            entry = 0 if here is None else _nearest(points, np.asarray(here))
            ordered = np.roll(points, -entry, axis=0)
            if here is None:
                self._start_at(ordered[0])
            else:
                self.route.append("transit", None, np.asarray([here, ordered[0]]), "headland")
            self.ring, self.ring_index = ordered, index
            return
        curve, extra, arrive = self._join_to_ring(points)
        self._leave_round(extra, curve)
        self.ring, self.ring_index = np.roll(points, -arrive, axis=0), index

    def add_core(self, core: RouteBuilder, join: tuple[FloatArray, int] | None) -> None:
        """Append the core's route, joined to the round driven last by ``join``.

        ``join``: :meth:`core_join`'s curve and extra points; None where no curve reaches
        the core (:meth:`_fallback_move` joins it).
        """
        if not core.x:
            return
        start = _core_start(core)
        first = np.array([core.x[start], core.y[start]])
        if self.ring is not None:
            first_yaw = _core_pose(core)[1]
            curve, extra = (
                join if join is not None else (self._fallback_from_round(first, first_yaw), 0)
            )
            self._leave_round(extra, curve, last_role=core.roles[start])
            self.ring = None
            self.route.lines[-1] = core.lines[start]
        elif self.route.x and self.route.roles[-1] == "start":
            self.route.append("transit", None, np.asarray([self.route.here(), first]), "turn")
            self.route.roles[-1] = core.roles[start]
            self.route.lines[-1] = core.lines[start]
        elif self.route.x:
            # Between two parts of the core: from where the last one's route ends, heading on.
            here = (self.route.x[-1], self.route.y[-1])
            core_yaw = _core_pose(core)[1]
            here_yaw = core_yaw  # a route of one point: the vehicle may face any way there
            if len(self.route.x) > 1:
                here_yaw = math.atan2(here[1] - self.route.y[-2], here[0] - self.route.x[-2])
            move = self._fallback_move(here, (first[0], first[1]), poses=(here_yaw, core_yaw))
            self.route.append("turn", None, move, "turn")
            self.route.roles[-1] = core.roles[start]
            self.route.lines[-1] = core.lines[start]
        else:
            self._start_at(first)
            self.route.roles[-1] = core.roles[start]
            self.route.lines[-1] = core.lines[start]
        offset = len(self.route.x) - 1
        route = self.route
        route.x.extend(core.x[start + 1 :])
        route.y.extend(core.y[start + 1 :])
        route.roles.extend(core.roles[start + 1 :])
        route.lines.extend(core.lines[start + 1 :])
        for kind, index, a, b in core.segments:
            if a < start:
                continue  # the core's start leg: replaced by the move above
            route.segments.append((kind, index, a - start + offset, b - start + offset))

    @property
    def in_round(self) -> bool:
        """Whether a round is being driven (the core is then joined to it)."""
        return self.ring is not None

    def core_join(self, core: RouteBuilder) -> tuple[FloatArray, int] | None:
        """Find the drivable join from the round driven last to ``core``'s first pose.

        Returns the curve and the extra points driven on along the round before it
        (:meth:`_best`); None where no curve reaches the pose inside the field, and where
        no round is being driven or the core is empty (nothing to join).
        """
        if self.ring is None or not core.x:
            return None
        first, yaw_rad = _core_pose(core)
        dep_xy, dep_yaw, along = self._departures()
        n = len(dep_xy)
        k = self._best(
            dep_xy, dep_yaw, along, np.repeat(first[None, :], n, axis=0), np.full(n, yaw_rad)
        )
        return None if k is None else (self._curve, k)

    def other_entries(self, count: int) -> list[tuple[float, float]]:
        """Up to ``count`` points spread along the round driven last, its entry left out."""
        if self.ring is None:
            return []
        n = len(self.ring)
        picks = np.unique((np.arange(1, count + 1) * n) // (count + 1))
        return [(float(self.ring[i, 0]), float(self.ring[i, 1])) for i in picks if i > 0]

    def finish(self) -> None:
        """Drive the last round once round if nothing follows it."""
        if self.ring is not None:
            self._leave_round(0, None)
            self.ring = None

    # -- internals --------------------------------------------------------------------------

    def _start_at(self, xy: FloatArray) -> None:
        self.route.x.append(float(xy[0]))
        self.route.y.append(float(xy[1]))
        self.route.roles.append("headland")
        self.route.lines.append(None)

    def _leave_round(
        self, extra: int, curve: FloatArray | None, *, last_role: str | None = None
    ) -> None:
        """Append the current round (once round plus ``extra`` points) and the join after it."""
        assert self.ring is not None
        n = len(self.ring)
        along = self.ring[np.arange(n + extra + 1) % n]
        self.route.append("round", self.ring_index, along, "headland")
        # Once round from the entry (closed: GEOS fills the inside of a line that overlaps
        # itself, 2,672 m² for a 1,133 m² round of rwanda_2021-6), then on past the entry.
        self.driven.append(along[: n + 1])
        if extra:
            self.driven.append(along[n : n + extra + 1])
        if curve is not None and len(curve) > 1:
            self.route.append("turn", None, curve, "turn", last_role=last_role)  # type: ignore[arg-type]

    def _departures(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Candidate points to leave the current round: after the loop, on along it."""
        assert self.ring is not None
        n = len(self.ring)
        extra = np.arange(n)
        xy = self.ring[extra % n]
        before = self.ring[(extra - 1) % n]
        yaw = np.arctan2(xy[:, 1] - before[:, 1], xy[:, 0] - before[:, 0])
        # Distance driven on along the round past its entry [m].
        along = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))))
        return xy, yaw, along

    def _best(
        self,
        dep_xy: FloatArray,
        dep_yaw: FloatArray,
        along: FloatArray,
        to_xy: FloatArray,
        to_yaw: FloatArray,
    ) -> int | None:
        """Index of the cheapest candidate join that keeps the body inside (None if none).

        Its curve is left in ``self._curve``.

        The candidates are taken cheapest first (curve length plus the distance driven on
        along the round), in batches that grow: the joins' lengths are closed forms, but
        sampling a curve and testing its points is not, and a large field's round offers
        tens of thousands of candidates of which one of the first few usually fits.
        """
        ends = TurnEnds(dep_xy[:, 0], dep_xy[:, 1], dep_yaw, to_xy[:, 0], to_xy[:, 1], to_yaw)
        cost = dubins_turn_length_m(ends, radius_m=self.radius) + along
        order = np.argsort(cost, kind="stable")
        exact_left = _EXACT_CHECKS
        start, batch = 0, _FIRST_BATCH
        while start < len(order) and exact_left > 0:
            take = order[start : start + batch]
            start, batch = start + batch, min(4 * batch, _LAST_BATCH)
            curves = dubins_turn(ends.take(take), radius_m=self.radius)
            # A join to another ring of the level can cross the field, hundreds of points
            # long; most that leave the body's room do so for many of them. Test one point
            # in _SPARSE_STRIDE first, then every point of the curves that passed.
            owner = np.repeat(np.arange(len(curves)), curves.point_counts())
            sparse = curves.xy[::_SPARSE_STRIDE]
            bad = np.zeros(len(curves), dtype=bool)
            outside = ~shapely.contains_xy(self.allowed, sparse[:, 0], sparse[:, 1])
            bad[owner[::_SPARSE_STRIDE][outside]] = True
            test = ~bad[owner]
            outside = ~shapely.contains_xy(self.allowed, curves.xy[test, 0], curves.xy[test, 1])
            bad[owner[test][outside]] = True
            # The points are inside; the cheapest curves whose chords are too (exact check).
            for k in np.flatnonzero(~bad)[:exact_left]:
                exact_left -= 1
                curve = curves.curve(int(k))
                if shapely.covers(self.allowed, shapely.LineString(curve)):
                    self._curve = curve.copy()
                    return int(take[k])
        return None

    def _join_to_ring(self, points: FloatArray) -> tuple[FloatArray, int, int]:
        """Join the current round to the ring ``points``: curve, extra points, arrival index."""
        dep_xy, dep_yaw, along = self._departures()
        ahead = np.array([0.0, 1.0, 2.0, 4.0]) * self.radius + 2.0 * STEP_M
        nxt = np.roll(points, -1, axis=0)
        ring_yaw = np.arctan2(nxt[:, 1] - points[:, 1], nxt[:, 0] - points[:, 0])
        tree = cKDTree(points)
        heading_xy = np.stack([np.cos(dep_yaw), np.sin(dep_yaw)], axis=1)
        near = int(np.searchsorted(along, 4.0 * self.radius + 20.0))  # first: close by
        for limit in (min(len(dep_xy), max(near, 2)), len(dep_xy)):
            # Each departure up to ``limit`` with the ring's points nearest to it and to
            # points ahead of it: most joins are found close by, so the far departures
            # (thousands on a large field's round) are only looked up if none is.
            i = np.tile(np.arange(limit), len(ahead))
            probes = dep_xy[i] + np.repeat(ahead, limit)[:, None] * heading_xy[i]
            j = tree.query(probes)[1]
            k = self._best(dep_xy[i], dep_yaw[i], along[i], points[j], ring_yaw[j])
            if k is not None:
                return self._curve, int(i[k]), int(j[k])
        # No Dubins join found: a chain of turns, the arcs searched, or the shortest move.
        target = _nearest(points, self.ring[0]) if self.ring is not None else 0
        assert self.ring is not None
        after = points[(target + 1) % len(points)] - points[target]
        target_yaw = math.atan2(after[1], after[0])
        return self._fallback_from_round(points[target], target_yaw), 0, target

    def _fallback_from_round(self, xy: FloatArray, yaw: float) -> FloatArray:
        """Return the move from the current round's entry to pose ``xy``, ``yaw``.

        Where no curve reaches it (:meth:`_fallback_move`).
        """
        assert self.ring is not None
        entry = self.ring[0]
        arrival = entry - self.ring[-1]  # the vehicle comes round to its entry
        return self._fallback_move(
            (float(entry[0]), float(entry[1])),
            (float(xy[0]), float(xy[1])),
            poses=(math.atan2(arrival[1], arrival[0]), yaw),
        )

    def _fallback_move(
        self,
        here: tuple[float, float],
        there: tuple[float, float],
        *,
        poses: tuple[float, float],
    ) -> FloatArray:
        """Return a move where no curve joins, as points at most :data:`STEP_M` apart.

        ``poses``: the headings at ``here`` and ``there`` [rad]. With a vehicle with a
        turning radius, a chain of its turns beside the shortest path's corners
        (:func:`planner.move_curves.drivable_moves`, the lines kept whole), else its arcs
        searched for (:func:`planner.move_search.search_move`), the body inside either way.
        Else, or if neither is found, the shortest move inside the field, with its corners
        (a vehicle with a turning radius cannot take them), exported as densely as every
        other turn (R1).
        """
        if self.vehicle is not None:
            ends = TurnEnds(*(np.array([v]) for v in (*here, poses[0], *there, poses[1])))
            none = np.zeros(1)
            # At the spiral's own radius (with its slack), as its Dubins joins: rounded on
            # export, the curve still bends no tighter than the vehicle's radius.
            vehicle = replace(self.vehicle, min_turn_radius_m=self.radius)
            chained = drivable_moves(
                ends, back_room_m=none, on_room_m=none, router=self.router, vehicle=vehicle
            ).curves[0]
            if chained is not None and shapely.covers(self.allowed, shapely.LineString(chained)):
                return chained
            found = search_move(
                ends, none, none, router=self.router, vehicle=vehicle,
                most_expansions=SEARCHED_POSES,
            )  # fmt: skip
            if found is not None and shapely.covers(self.allowed, shapely.LineString(found.points)):
                return found.points
        return densify(self.router.path(here, there), STEP_M)


def _core_start(core: RouteBuilder) -> int:
    """Index of the core route's first point past its own start leg (replaced by the join)."""
    return 1 if core.roles and core.roles[0] == "start" else 0


def _core_pose(core: RouteBuilder) -> tuple[FloatArray, float]:
    """Where the core's route starts, local [m], and its heading there [rad]."""
    start = _core_start(core)
    first = np.array([core.x[start], core.y[start]])
    nxt = np.array([core.x[start + 1], core.y[start + 1]])
    return first, math.atan2(*(nxt - first)[::-1])


def core_pose_key(core: RouteBuilder) -> tuple[float, float, float]:
    """Return the core's first pose as a key: two plans that start alike are joined alike."""
    first, yaw_rad = _core_pose(core)
    return float(first[0]), float(first[1]), yaw_rad


def _nearest(points: FloatArray, xy: FloatArray) -> int:
    return int(np.argmin(np.hypot(points[:, 0] - xy[0], points[:, 1] - xy[1])))
