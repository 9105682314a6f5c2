"""The ``spiral`` pattern: rounds parallel to the boundary, inward, then the core back and forth.

Round ``i`` (from 0, outermost) runs ``o_i = max(d/2, w/2) + i · d`` inside the boundary and
around every hole (``d`` the interval, ``w`` the vehicle's width), so its footprint fills the
band from ``o_i - d/2`` to ``o_i + d/2``, as the headland passes do (:mod:`planner.headlands`).

Every round is a curve the vehicle drives (R1): the region it encloses is made regular for
the turning radius ``R`` (:func:`planner.round_shapes.regular_region`): nothing of it lies
outside the field eroded by ``o_i``, so the body stays inside, and its boundary bends no
tighter than ``R`` either way, so convex corners become arcs of radius ``R`` and the round
swings wide of the field's inner (reflex) corners and of small holes. Rounds go inward while
the area inside them stays in one piece per piece of the field (a narrowing neck would
otherwise scatter the rounds into many small loops); the core left inside the last round is
then covered back and forth by the boustrophedon planner
(:func:`planner.general.plan_general`) for the same vehicle.

A vehicle that pivots (no turning radius) drives each corner of a round that turns 60–135°
as a loop about its outer wheel (:func:`planner.round_corners.corner_loops`), which tills the
corner that a pivot about the inner wheel would leave; the loop is taken where the body stays
inside.

Rounds are joined, and the last round to the core, by forward Dubins curves at the same radius
(:func:`planner.turns.dubins_turn`): after a full round the vehicle drives on along it until a
lane change to the next round (or the move to the core's first line) fits inside the field for
its body, so the route is one continuous, drivable path: each segment begins where the one
before it ends. Where no curve reaches the core's first line, the core is planned again from
up to :data:`_CORE_ENTRIES` other points of the last round (its start then usually moves to
another corner), and the first plan a curve reaches is driven. Only where no such curve is
found (a join that would have to wind round an obstacle) does the join fall back to the
shortest move inside the field (:class:`planner.routing.FieldRouter`), with corners.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import shapely
from scipy.spatial import cKDTree  # type: ignore[import-untyped]
from shapely import LinearRing, MultiPolygon, Polygon

from planner import general
from planner.errors import InvalidParameterError, PlannerError
from planner.general import RouteBuilder
from planner.headlands import polygon_parts
from planner.line_ends import machine_area
from planner.round_corners import corner_loops
from planner.round_shapes import (
    QUAD_SEGS,
    RADIUS_SLACK,
    resample_ring,
    round_parts,
    round_step_m,
)
from planner.route_builder import densify
from planner.routing import FieldRouter
from planner.turns import (
    SAGITTA_M,
    STEP_M,
    TurnEnds,
    dubins_turn,
    dubins_turn_length_m,
    turning_radius_m,
)
from planner.types import Objective, Vehicle
from planner.vehicles import resolve_vehicle

FloatArray = npt.NDArray[np.float64]

#: At most this many rounds (a field 2 × MAX_ROUNDS intervals wide is all rounds).
MAX_ROUNDS = 200
#: Points of a driven round this close to the line through their neighbours are left out
#: of its footprint [m].
FOOTPRINT_TOLERANCE_M = 1e-4
#: The core's boundary is simplified by this much, inside itself [m].
CORE_TOLERANCE_M = 0.002
#: ... if it has more vertices than this.
CORE_SIMPLE_VERTICES = 400
#: Room the body keeps from the boundary in the joins' check, inside R1's 1 cm [m].
_BODY_MARGIN_M = 0.002
#: Candidate joins checked exactly (chords and all), cheapest first.
_EXACT_CHECKS = 32
#: Candidate joins sampled and tested in the first batch (each next batch is 4 times larger).
_FIRST_BATCH = 64
#: ... and at most this many (each can be hundreds of points).
_LAST_BATCH = 4096
#: The first test of a batch looks at one point in this many.
_SPARSE_STRIDE = 16
#: Where no curve reaches the core's start, it is planned from this many other points of
#: the last round.
_CORE_ENTRIES = 4


@dataclass(frozen=True, slots=True)
class SpiralPlan:
    """A spiral route in local metres.

    Attributes
    ----------
    route : RouteBuilder
        Waypoints, roles and segments (rounds are ``round`` segments with their index); the
        finish leg is not in it yet.
    round_count : int
        Rounds driven (every ring of every level counts once).
    line_count : int
        Tillage lines of the core.
    heading_deg : float
        Heading of the core's lines (0 if there is no core).
    coverage_ratio : float
        R4: the rounds' and the core lines' footprints over the field.
    cells_local : list of Polygon
        The core's cells.
    """

    route: RouteBuilder
    round_count: int
    line_count: int
    heading_deg: float
    coverage_ratio: float
    cells_local: list[Polygon]


def order_spiral(
    field_local: Polygon,
    *,
    interval_m: float,
    start_xy: tuple[float, float] | None = None,
    finish_xy: tuple[float, float] | None = None,
    objective: Objective = "shortest_path",
    vehicle: Vehicle | None = None,
    implement_width_m: float | None = None,
) -> SpiralPlan:
    """Cover ``field_local`` with inward rounds joined into one path, the core back and forth.

    Parameters
    ----------
    field_local : Polygon
        Valid field, local frame [m], holes allowed.
    interval_m : float
        Distance between rounds and between the core's lines [m].
    start_xy, finish_xy : tuple of float, optional
        Where the tractor comes from and must end, local [m].
    objective : {"shortest_path", "fewest_lines"}
        For the core's heading search.
    vehicle : Vehicle, optional
        The machine (default the hand tractor): its half-width keeps the body inside, its
        turning radius bounds the rounds' curvature.
    implement_width_m : float, optional
        What one pass tills [m], for the coverage; default ``interval_m``.

    Returns
    -------
    SpiralPlan

    Examples
    --------
    A 40 m × 24 m field at 4 m: three rounds, then the 16 m × 0 m core is nothing; the hand
    tractor pivots about its outer wheel at each corner (a loop, :mod:`planner.round_corners`)
    and so tills the corners too. A small tractor (3 m radius) drives two rounds and two core
    lines, and leaves the corners its arcs cut off.

    >>> plan = order_spiral(shapely.box(0, 0, 40, 24), interval_m=4.0)
    >>> plan.round_count, plan.line_count, round(plan.coverage_ratio, 3)
    (3, 0, 1.0)
    >>> plan = order_spiral(shapely.box(0, 0, 40, 24), interval_m=4.0, vehicle="small_tractor")
    >>> plan.round_count, plan.line_count, round(plan.coverage_ratio, 3)
    (2, 2, 0.892)
    """
    field_local = shapely.orient_polygons(field_local)
    d = float(interval_m)
    machine = resolve_vehicle(vehicle)
    implement = d if implement_width_m is None else float(implement_width_m)
    area = machine_area(field_local, machine)  # raises if the vehicle does not fit
    router = FieldRouter(area if isinstance(area, Polygon) else field_local)
    radius = turning_radius_m(machine) * RADIUS_SLACK
    half = machine.width_m / 2.0
    # Where the body may be: the joins are checked against it.
    allowed = field_local.buffer(-(half - _BODY_MARGIN_M), quad_segs=QUAD_SEGS)
    shapely.prepare(allowed)
    # Round 0 runs d/2 inside the boundary; a body wider than the interval needs more, and
    # then the sagitta of the round's chords too: round the field's inner corners a chord
    # cuts towards the bund by up to that much, which would use up R1's 1 cm.
    first_m = max(d / 2.0, half + SAGITTA_M)
    levels, regions = _round_levels(field_local, first_m, d, radius)
    core_parts: list[Polygon] = []
    if regions:
        core_parts = polygon_parts(regions[-1].buffer(-d / 2.0, quad_segs=QUAD_SEGS))
    elif first_m > d / 2.0:  # no round fits: the core is all the body may reach
        core_parts = polygon_parts(field_local.buffer(-(first_m - d / 2.0), quad_segs=QUAD_SEGS))
    else:
        core_parts = polygon_parts(field_local)
    # A core piece narrower than the body holds no line it could drive: the rounds cover it.
    core_parts = [p for p in core_parts if not p.buffer(-half).is_empty]
    core_parts = [q for p in core_parts for q in _simplified_core(p, half)]

    route = RouteBuilder()
    if start_xy is not None:
        route.append("transit", None, np.array([start_xy]), "start")
    # A vehicle that pivots tills each sharp corner of a round with a loop the other way.
    joiner = _Joiner(route, router, allowed, radius, loops=machine.min_turn_radius_m == 0.0)
    round_index = 0
    for rings in levels:
        for ring in _nearest_first(rings, joiner.position()):
            joiner.add_round(ring, round_index)
            round_index += 1

    def _core_plan(part: Polygon, start: tuple[float, float] | None) -> general.GeneralPlan:
        return general.plan_general(
            part,
            interval_m=d,
            start_xy=start,
            finish_xy=finish_xy,
            fixed_heading_deg=None,
            objective=objective,
            headland_passes=0,
            vehicle=machine,
            implement_width_m=implement,
        )

    heading = 0.0
    line_count = 0
    cells: list[Polygon] = []
    kept: list[Polygon] = []
    core_covered = 0.0
    refused: InvalidParameterError | None = None
    for part in core_parts:
        try:
            core = _core_plan(part, joiner.position())
        except InvalidParameterError as error:
            refused = refused or error
            continue  # a core too small for the vehicle's turns: the rounds cover round it
        core, join = _entered_core(core, joiner, functools.partial(_core_plan, part))
        joiner.add_core(core.route, join)
        heading = core.heading_deg
        line_count += core.line_count
        cells.extend(core.cells_local)
        kept.append(part)
        core_covered += core.lines_coverage_ratio * float(part.area)
    joiner.finish()
    if round_index == 0 and not kept:
        if refused is not None:
            raise refused  # nothing fits: the core's error names the vehicle and the field
        raise InvalidParameterError(
            "vehicle",
            f"a {turning_radius_m(machine):g} m turning radius leaves no round or line "
            "in this field",
        )

    field_area = float(field_local.area)
    covered = core_covered
    if levels:
        band = field_local.difference(shapely.union_all(kept)) if kept else field_local
        # Each round as driven, from where it is joined to where it is left (flat caps).
        # Its points lie every few decimetres along straight runs: dropping those in line to
        # 0.1 mm leaves the footprint's area as it was (0.05 m² of 16 ha) and makes the union
        # of a large field's rounds ten times faster (its vertices 30 times fewer).
        footprints = shapely.union_all(
            [
                shapely.LineString(points)
                .simplify(FOOTPRINT_TOLERANCE_M, preserve_topology=False)
                .buffer(implement / 2.0, cap_style="flat", join_style="mitre")
                for points in joiner.driven
            ]
        )
        covered += float(shapely.intersection(band, footprints).area)
    return SpiralPlan(
        route=route,
        round_count=round_index,
        line_count=line_count,
        heading_deg=heading,
        coverage_ratio=min(covered / field_area, 1.0),
        cells_local=cells,
    )


def _entered_core(
    core: general.GeneralPlan,
    joiner: _Joiner,
    plan_from: Callable[[tuple[float, float]], general.GeneralPlan],
) -> tuple[general.GeneralPlan, tuple[FloatArray, int] | None]:
    """Return the core plan to drive and its join from the round driven last.

    The core is entered where its plan starts, near the round's entry. Where no curve reaches
    that pose inside the field, the core is planned again (``plan_from(entry)``) from up to
    :data:`_CORE_ENTRIES` other points of the round, which usually moves its start to another
    corner; the first plan a curve reaches is driven (its heading may differ, its coverage is
    the plan's own). Else ``core`` stands, with no join (:meth:`_Joiner.add_core` routes it).
    """
    join = joiner.core_join(core.route)
    if join is not None or not joiner.in_round or not core.route.x:
        return core, join
    tried = {_core_pose_key(core.route)}
    for entry in joiner.other_entries(_CORE_ENTRIES):
        try:
            other = plan_from(entry)
        except PlannerError:
            continue  # the first plan stands, with its routed join
        key = _core_pose_key(other.route)
        if key in tried:
            continue  # the same start: the same join, not found
        tried.add(key)
        other_join = joiner.core_join(other.route)
        if other_join is not None:
            return other, other_join
    return core, None


def _simplified_core(part: Polygon, half_width_m: float) -> list[Polygon]:
    """Return a core part with fewer vertices: shrunk and simplified by CORE_TOLERANCE_M.

    The core's boundary follows the rounds' arcs, a vertex every few centimetres, and the
    router between its cells grows with the square of its corners (4 of a 21 ha field's
    5 s). Shrunk by the tolerance and simplified by as much, it stays within a fraction of a
    millimetre of ``part`` (simplifying may cut a corner that far out; the core lies half an
    interval inside the last round). Where that would part it, or leave a piece too narrow
    for the body that was not, ``part`` is kept as it is; so is a part of at most
    :data:`CORE_SIMPLE_VERTICES` vertices, which routes fast as it is (on a strip the body
    barely fits, 2 mm off each side would cost coverage: 0.5 pp of a 0.86 m strip).
    """
    if shapely.get_num_coordinates(part) <= CORE_SIMPLE_VERTICES:
        return [part]
    shrunk = polygon_parts(
        part.buffer(-CORE_TOLERANCE_M, join_style="mitre").simplify(CORE_TOLERANCE_M)
    )
    if len(shrunk) == 1 and not shrunk[0].buffer(-half_width_m).is_empty:
        return shrunk
    return [part]


def _round_levels(
    field_local: Polygon, first_m: float, d: float, radius_m: float
) -> tuple[list[list[LinearRing]], list[Polygon | MultiPolygon]]:
    """Return the rings of every round level, outermost first, and the regions they enclose.

    A level is kept while its region exists and is in no more pieces than the field's first
    offset, or than the first round's region if a pinch too tight for the radius parted it
    (a neck that splits a later level ends the rounds there).
    """
    levels: list[list[LinearRing]] = []
    regions: list[Polygon | MultiPolygon] = []
    pieces = len(polygon_parts(field_local.buffer(-first_m, quad_segs=QUAD_SEGS)))
    for i in range(MAX_ROUNDS):
        offset = field_local.buffer(-(first_m + i * d), quad_segs=QUAD_SEGS)
        if offset.is_empty:
            break
        parts = round_parts(offset, radius_m)
        if i == 0:
            # A pinch too tight for the radius parts the first round: its pieces are the
            # field's pieces from here on.
            pieces = max(pieces, len(parts))
        if not parts or len(parts) > pieces:
            break
        levels.append([ring for p in parts for ring in (p.exterior, *p.interiors)])
        regions.append(parts[0] if len(parts) == 1 else MultiPolygon(parts))
    return levels, regions


def _nearest_first(rings: list[LinearRing], here: tuple[float, float] | None) -> list[LinearRing]:
    """Order the rings of one level: each next the nearest to where the last began."""
    left = list(rings)
    ordered: list[LinearRing] = []
    while left:
        if here is None:
            k = 0
        else:
            point = shapely.Point(here)
            k = min(range(len(left)), key=lambda i: (left[i].distance(point), i))
        ring = left.pop(k)
        ordered.append(ring)
        if here is not None:
            nearest = ring.interpolate(ring.project(shapely.Point(here)))
            here = (float(nearest.x), float(nearest.y))
    return ordered


class _Joiner:
    """Builds the route: rounds driven once round, and drivable joins between them."""

    def __init__(
        self,
        route: RouteBuilder,
        router: FieldRouter,
        allowed: shapely.Geometry,
        radius: float,
        *,
        loops: bool = False,
    ) -> None:
        self.route = route
        self.router = router
        self.allowed = allowed
        self.radius = radius
        self.step = round_step_m(radius)
        self.loops = loops  # corner loops (planner.round_corners) in every round
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

        ``join``: :meth:`core_join`'s curve and extra points; None for the routed move (with
        corners) where no curve reaches the core.
        """
        if not core.x:
            return
        start = _core_start(core)
        first = np.array([core.x[start], core.y[start]])
        if self.ring is not None:
            curve, extra = join if join is not None else (self._routed_from_round(first), 0)
            self._leave_round(extra, curve, last_role=core.roles[start])
            self.ring = None
            self.route.lines[-1] = core.lines[start]
        elif self.route.x and self.route.roles[-1] == "start":
            self.route.append("transit", None, np.asarray([self.route.here(), first]), "turn")
            self.route.roles[-1] = core.roles[start]
            self.route.lines[-1] = core.lines[start]
        elif self.route.x:
            here = (self.route.x[-1], self.route.y[-1])
            self.route.append("turn", None, self._routed(here, (first[0], first[1])), "turn")
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
        # No drivable join found: the shortest move inside the field, with corners.
        target = _nearest(points, self.ring[0]) if self.ring is not None else 0
        assert self.ring is not None
        return self._routed_from_round(points[target]), 0, target

    def _routed_from_round(self, xy: FloatArray) -> FloatArray:
        """Return the routed move from the current round's entry to ``xy`` (no curve reaches it)."""
        assert self.ring is not None
        return self._routed(tuple(self.ring[0]), (float(xy[0]), float(xy[1])))

    def _routed(self, here: tuple[float, float], there: tuple[float, float]) -> FloatArray:
        """Return the shortest move inside the field, as points at most :data:`STEP_M` apart.

        The fallback where no drivable curve joins: it keeps the path's corners (a vehicle
        with a turning radius cannot take them: a known weakness), but is exported as densely
        as every other turn (R1).
        """
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


def _core_pose_key(core: RouteBuilder) -> tuple[float, float, float]:
    """Return the core's first pose as a key: two plans that start alike are joined alike."""
    first, yaw_rad = _core_pose(core)
    return float(first[0]), float(first[1]), yaw_rad


def _nearest(points: FloatArray, xy: FloatArray) -> int:
    return int(np.argmin(np.hypot(points[:, 0] - xy[0], points[:, 1] - xy[1])))
