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

Rounds are joined, and the last round to the core (:mod:`planner.spiral_joins`), by forward
Dubins curves at the same radius
(:func:`planner.turns.dubins_turn`): after a full round the vehicle drives on along it until a
lane change to the next round (or the move to the core's first line) fits inside the field for
its body, so the route is one continuous, drivable path: each segment begins where the one
before it ends. Where no curve reaches the core's first line, the core is planned again from
up to :data:`_CORE_ENTRIES` other points of the last round (its start then usually moves to
another corner), and the first plan a curve reaches is driven. Where no such curve is found
(a join that would have to wind round an obstacle), and between two parts of the core, the
join is a chain of turns beside the shortest path's corners (:mod:`planner.move_curves`) or
the vehicle's arcs searched for (:mod:`planner.move_search`); only where neither is found
does it fall back to the shortest move inside the field
(:class:`planner.routing.FieldRouter`), with corners.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import shapely
from shapely import LinearRing, MultiPolygon, Polygon

from planner import general
from planner.errors import InvalidParameterError, PlannerError
from planner.general import RouteBuilder
from planner.headlands import polygon_parts
from planner.line_ends import machine_area
from planner.round_shapes import QUAD_SEGS, RADIUS_SLACK, round_parts
from planner.routing import FieldRouter
from planner.spiral_joins import RoundJoiner, core_pose_key
from planner.turns import SAGITTA_M, turning_radius_m
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
#: Or by this much, where that gives up at most CORE_COARSE_SHARE of its area [m].
CORE_COARSE_TOLERANCE_M = 0.05
#: The share of a core's area the coarse simplification may give up.
CORE_COARSE_SHARE = 0.001
#: ... and the longest piece of the body's room it may take beyond its own strip, as half
#: the piece's perimeter [m].
_LOST_ROOM_M = 1.0
#: Room the body keeps from the boundary in the joins' check, inside R1's 1 cm [m].
_BODY_MARGIN_M = 0.002
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
    pivots = machine.min_turn_radius_m == 0.0
    joiner = RoundJoiner(
        route, router, allowed, radius, loops=pivots, vehicle=None if pivots else machine
    )
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
    joiner: RoundJoiner,
    plan_from: Callable[[tuple[float, float]], general.GeneralPlan],
) -> tuple[general.GeneralPlan, tuple[FloatArray, int] | None]:
    """Return the core plan to drive and its join from the round driven last.

    The core is entered where its plan starts, near the round's entry. Where no curve reaches
    that pose inside the field, the core is planned again (``plan_from(entry)``) from up to
    :data:`_CORE_ENTRIES` other points of the round, which usually moves its start to another
    corner; the first plan a curve reaches is driven (its heading may differ, its coverage is
    the plan's own). Else ``core`` stands, with no join (:meth:`RoundJoiner.add_core` routes it).
    """
    join = joiner.core_join(core.route)
    if join is not None or not joiner.in_round or not core.route.x:
        return core, join
    tried = {core_pose_key(core.route)}
    for entry in joiner.other_entries(_CORE_ENTRIES):
        try:
            other = plan_from(entry)
        except PlannerError:
            continue  # the first plan stands, with its routed join
        key = core_pose_key(other.route)
        if key in tried:
            continue  # the same start: the same join, not found
        tried.add(key)
        other_join = joiner.core_join(other.route)
        if other_join is not None:
            return other, other_join
    return core, None


def _simplified_core(part: Polygon, half_width_m: float) -> list[Polygon]:
    """Return a core part with fewer vertices: shrunk and simplified by a tolerance.

    The core's boundary follows the rounds' arcs, a vertex every few centimetres, and the
    router between its cells grows with the square of its corners (4 of a 21 ha field's
    5 s). Shrunk by the tolerance and simplified by as much, it stays inside ``part``
    (the core lies half an interval inside the last round). It is simplified by
    :data:`CORE_COARSE_TOLERANCE_M` where that costs little (:func:`_coarse_core`: a
    large core), else by :data:`CORE_TOLERANCE_M`. Where that would part it,
    or leave a piece too narrow for the body that was not, ``part`` is kept as it is; so
    is a part of at most :data:`CORE_SIMPLE_VERTICES` vertices, which routes fast as it is
    (on a strip the body barely fits, 2 mm off each side would cost coverage: 0.5 pp of a
    0.86 m strip).
    """
    if shapely.get_num_coordinates(part) <= CORE_SIMPLE_VERTICES:
        return [part]
    coarse = _coarse_core(part, half_width_m)
    if coarse is not None:
        return [coarse]
    shrunk = _shrunk(part, CORE_TOLERANCE_M)
    if len(shrunk) == 1 and not shrunk[0].buffer(-half_width_m).is_empty:
        return shrunk
    return [part]


def _coarse_core(part: Polygon, half_width_m: float) -> Polygon | None:
    """Return ``part`` shrunk and simplified by :data:`CORE_COARSE_TOLERANCE_M`, if that holds.

    It holds where the part stays one piece, gives up at most :data:`CORE_COARSE_SHARE`
    of its area, and takes from the body's room (``half_width_m`` [m] in from the
    boundary) no piece longer than :data:`_LOST_ROOM_M` (half its perimeter) beyond twice
    the tolerance of the room left: an arm of the core just wider than the body would
    lose its line, not a strip of 5 cm. A shorter neck may still go, and part the body's
    room in two while the core stays whole. None where it does not hold.
    """
    tolerance_m = CORE_COARSE_TOLERANCE_M
    shrunk = _shrunk(part, tolerance_m)
    if len(shrunk) != 1 or float(part.area) - float(shrunk[0].area) > (
        CORE_COARSE_SHARE * part.area
    ):
        return None
    room_before = part.buffer(-half_width_m)
    # The boundary moved in by up to twice the tolerance (the shrink, then the simplify;
    # more at a sharp inner corner, which can only make the test reject more).
    room_after = shrunk[0].buffer(-half_width_m).buffer(2.0 * tolerance_m, join_style="mitre")
    lost = shapely.get_parts(room_before.difference(room_after))
    if any(piece.length / 2.0 > _LOST_ROOM_M for piece in lost):
        return None
    return shrunk[0]


def _shrunk(part: Polygon, tolerance_m: float) -> list[Polygon]:
    """Return ``part`` shrunk by ``tolerance_m`` [m] and simplified by as much, in parts."""
    return polygon_parts(part.buffer(-tolerance_m, join_style="mitre").simplify(tolerance_m))


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
