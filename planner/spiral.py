"""The ``spiral`` pattern: rounds parallel to the boundary, inward, then the core back and forth.

Round ``i`` (from 0, outermost) runs ``(i + 1/2) · interval`` inside the boundary and around
every hole, so its footprint fills the band from ``i · interval`` to ``(i + 1) · interval``, as
the headland passes do (:mod:`planner.headlands`). Rounds go inward while the area inside them
stays in one piece per piece of the field (a narrowing neck would otherwise scatter the rounds
into many small loops); the core left inside the last round is then covered back and forth by
the boustrophedon planner (:func:`planner.general.plan_general`). Every round is driven once
around, entered at its point nearest the tractor, and every move between rounds and into the
core is routed inside the field (:class:`planner.routing.FieldRouter`), so the route is one
continuous path: each segment begins where the one before it ends.

The vehicle's body stays inside the field (R1): when half its width is more than half an
interval, every round moves inward by the difference (the field is shrunk by it first), and
the core is planned for the same vehicle (its lines pulled back from the core's edge, its
turns ones the vehicle can drive). The rounds' corners are driven as the polygon's vertices:
a vehicle with a turning radius rounds them off itself (the spiral fits no turn curves).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import shapely
from shapely import LinearRing, MultiPolygon, Polygon

from planner import general
from planner.general import RouteBuilder
from planner.line_ends import machine_area
from planner.routing import FieldRouter
from planner.types import Objective, Vehicle
from planner.vehicles import resolve_vehicle

FloatArray = npt.NDArray[np.float64]

#: At most this many rounds (a field 2 × MAX_ROUNDS intervals wide is all rounds).
MAX_ROUNDS = 200
#: Rounds and core parts smaller than this are dropped (slivers of the offsets) [m²].
_SLIVER_M2 = 1e-6


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
        The machine (default the hand tractor): its half-width keeps the body inside.
    implement_width_m : float, optional
        What one pass tills [m], for the coverage; default ``interval_m``.

    Returns
    -------
    SpiralPlan

    Examples
    --------
    A 40 m × 24 m field at 4 m: three rounds, then the 16 m × 0 m core is nothing.

    >>> plan = order_spiral(shapely.box(0, 0, 40, 24), interval_m=4.0)
    >>> plan.round_count, plan.line_count, round(plan.coverage_ratio, 3)
    (3, 0, 1.0)
    """
    field_local = shapely.orient_polygons(field_local)
    d = float(interval_m)
    machine = resolve_vehicle(vehicle)
    implement = d if implement_width_m is None else float(implement_width_m)
    area = machine_area(field_local, machine)  # raises if the vehicle does not fit
    router = FieldRouter(area if isinstance(area, Polygon) else field_local)
    # Round 0 runs d/2 inside the boundary; a body wider than the interval needs more.
    inset_m = max(0.0, machine.width_m / 2.0 - d / 2.0)
    work: Polygon | MultiPolygon = field_local
    if inset_m > 0.0:
        inset = _parts(field_local.buffer(-inset_m, join_style="mitre"))
        work = inset[0] if len(inset) == 1 else MultiPolygon(inset)
    levels = _round_levels(work, d)
    core_parts = _parts(work.buffer(-len(levels) * d, join_style="mitre"))
    # A core piece narrower than the body holds no line it could drive: the rounds cover it.
    core_parts = [p for p in core_parts if not p.buffer(-machine.width_m / 2.0).is_empty]

    route = RouteBuilder()
    if start_xy is not None:
        route.append("transit", None, np.array([start_xy]), "start")
    round_index = 0
    for rings in levels:
        for ring in _nearest_first(rings, route.here()):
            _add_round(route, ring, round_index, router)
            round_index += 1

    heading = 0.0
    line_count = 0
    cells: list[Polygon] = []
    core_covered = 0.0
    for part in core_parts:
        here = route.here()
        core = general.plan_general(
            part,
            interval_m=d,
            start_xy=here,
            finish_xy=finish_xy,
            fixed_heading_deg=None,
            objective=objective,
            headland_passes=0,
            vehicle=machine,
            implement_width_m=implement,
        )
        _join(route, core.route, router)
        heading = core.heading_deg
        line_count += core.line_count
        cells.extend(core.cells_local)
        core_covered += core.lines_coverage_ratio * float(part.area)

    field_area = float(field_local.area)
    covered = core_covered
    if levels:
        band = field_local.difference(shapely.union_all(core_parts)) if core_parts else field_local
        footprints = shapely.union_all(
            [
                ring.buffer(implement / 2.0, cap_style="flat", join_style="mitre")
                for rings in levels
                for ring in rings
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


def _parts(geometry: shapely.Geometry) -> list[Polygon]:
    parts = [
        shapely.orient_polygons(p)
        for p in shapely.get_parts(geometry)
        if isinstance(p, Polygon) and p.area > _SLIVER_M2
    ]
    parts.sort(key=lambda p: (-p.area, p.bounds))
    return parts


def _round_levels(field_local: Polygon | MultiPolygon, d: float) -> list[list[LinearRing]]:
    """Return the rings of every round level, outermost first.

    A level is kept while its centre line exists and the area inside its band is in no more
    pieces than the field (a neck that splits it ends the rounds there).
    """
    levels: list[list[LinearRing]] = []
    pieces = len(_parts(field_local))
    for i in range(MAX_ROUNDS):
        centre = _parts(field_local.buffer(-(i + 0.5) * d, join_style="mitre"))
        if not centre or len(centre) > pieces:
            break
        levels.append([ring for p in centre for ring in (p.exterior, *p.interiors)])
        inner = _parts(field_local.buffer(-(i + 1) * d, join_style="mitre"))
        if not inner or len(inner) > pieces:
            break
    return levels


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
        here = _entry(ring, here)
    return ordered


def _entry(ring: LinearRing, here: tuple[float, float] | None) -> tuple[float, float]:
    if here is None:
        x0, y0 = ring.coords[0]
        return float(x0), float(y0)
    point = ring.interpolate(ring.project(shapely.Point(here)))
    return float(point.x), float(point.y)


def _add_round(route: RouteBuilder, ring: LinearRing, index: int, router: FieldRouter) -> None:
    """Drive ``ring`` once round from its point nearest the tractor, joined by a routed move."""
    here = route.here()
    entry = _entry(ring, here)
    coords = np.asarray(ring.coords)[:-1]
    along = shapely.line_locate_point(ring, shapely.points(coords))
    at = float(ring.project(shapely.Point(entry)))
    order = np.argsort((along - at) % ring.length, kind="stable")
    points = [entry]
    points += [(float(c[0]), float(c[1])) for c in coords[order] if np.hypot(*(c - entry)) > 1e-9]
    points.append(entry)
    if here is not None:
        if route.roles[-1] == "start":
            route.append("transit", None, np.asarray([here, entry]), "headland")
        else:
            route.append("turn", None, router.path(here, entry), "turn", last_role="headland")
    elif not route.x:
        route.x.append(entry[0])
        route.y.append(entry[1])
        route.roles.append("headland")
        route.lines.append(None)
    route.append("round", index, np.asarray(points), "headland")


def _join(route: RouteBuilder, core: RouteBuilder, router: FieldRouter) -> None:
    """Append the core's route, reached by a routed move from the route's last point."""
    if not core.x:
        return
    start = 1 if core.roles and core.roles[0] == "start" else 0  # the core's own start leg
    first = (core.x[start], core.y[start])
    offset = len(route.x)
    here = route.here()
    if here is not None and route.roles[-1] != "start":
        route.append("turn", None, router.path(here, first), "turn")
        route.roles[-1] = core.roles[start]
        route.lines[-1] = core.lines[start]
        offset = len(route.x) - 1
    elif here is not None:
        route.append("transit", None, np.asarray([here, first]), core.roles[start])
        route.lines[-1] = core.lines[start]
        offset = len(route.x) - 1
    else:
        route.x.append(first[0])
        route.y.append(first[1])
        route.roles.append(core.roles[start])
        route.lines.append(core.lines[start])
        offset = 0
    route.x.extend(core.x[start + 1 :])
    route.y.extend(core.y[start + 1 :])
    route.roles.extend(core.roles[start + 1 :])
    route.lines.extend(core.lines[start + 1 :])
    for kind, index, a, b in core.segments:
        if a < start:
            continue  # the core's start leg: replaced by the move above
        route.segments.append((kind, index, a - start + offset, b - start + offset))
