"""Headland passes: rounds parallel to the boundary, for turning room and the edges lines miss.

Pass ``i`` (from 0, outermost) runs ``(i + 1/2) · interval`` inside the boundary and around
every hole, so its footprint fills the band from ``i · interval`` to ``(i + 1) · interval``;
the tillage lines then cover what lies inside the last band.
"""

from __future__ import annotations

import shapely
from shapely import LinearRing, Polygon

from planner.errors import InvalidParameterError

#: Inner-area parts smaller than this are dropped (slivers between headland passes) [m²].
_SLIVER_M2 = 1e-6
#: A narrow part the passes miss gets a spur round if it is at least this many interval²
#: (smaller gaps are corners the rounds cut, not worth a detour).
SPUR_MIN_INTERVALS2 = 1.0
#: ... and if the spur round covers at least this share of it.
SPUR_MIN_SHARE = 0.5
#: A spur round runs at least this far inside the field (a vehicle of no width) [m].
_SPUR_MIN_DEPTH_M = 0.05


def inner_parts(
    field_local: Polygon, *, passes: int, interval_m: float, vehicle_width_m: float = 0.0
) -> list[Polygon]:
    """Return the area left for tillage lines inside ``passes`` headland rounds.

    With no passes it is the machine area: the field eroded by half the vehicle's width (R1).
    A narrow neck can split it into several parts; they come oriented (exterior
    counter-clockwise), largest first.
    """
    half = vehicle_width_m / 2.0
    if passes == 0:
        inner = field_local.buffer(-half) if half > 0.0 else field_local
    else:
        depth = first_pass_offset_m(interval_m, vehicle_width_m) + (passes - 0.5) * interval_m
        inner = field_local.buffer(-max(depth, half), join_style="mitre")
    return polygon_parts(inner)


def polygon_parts(geometry: shapely.Geometry) -> list[Polygon]:
    """Return the polygons of ``geometry`` bar slivers, oriented, largest first."""
    parts = [
        shapely.orient_polygons(p)
        for p in shapely.get_parts(geometry)
        if isinstance(p, Polygon) and p.area > _SLIVER_M2
    ]
    parts.sort(key=lambda p: (-p.area, p.bounds))
    return parts


def first_pass_offset_m(interval_m: float, vehicle_width_m: float) -> float:
    """How far inside the boundary the outermost headland pass runs [m].

    Half the interval (its footprint then touches the bund), or half the vehicle's width
    if that is more (the body stays in, R1).
    """
    return max(interval_m, vehicle_width_m) / 2.0


def headland_ring_sets(
    field_local: Polygon,
    *,
    passes: int,
    interval_m: float,
    vehicle_width_m: float = 0.0,
    turning_radius_m: float = 0.0,
) -> list[list[LinearRing]]:
    """Centre lines of the headland passes, outermost pass first: each pass's rings.

    Pass ``i`` runs ``first_pass_offset_m + i · interval_m`` inside the boundary, around the
    exterior and around every hole (grown by the same distance), so its footprint fills the
    band from ``i · interval_m`` to ``(i + 1) · interval_m`` (further in if the vehicle is
    wider than the interval). With a turning radius ``r`` every corner is rounded so that
    the vehicle can drive it: the ring bounds ``(field ⊖ a) ⊕ r`` with
    ``a = max(offset + r, 2r)``: its straight runs lie ``a - r`` inside, its convex corners
    are arcs of radius ``r`` and its reflex corners arcs of radius ``a - r ≥ r`` (so a pass
    nearer the boundary than ``r`` moves in to ``r``).

    Raises
    ------
    InvalidParameterError
        If the field is too narrow for that many passes (the area inside them may be empty:
        then the plan is the passes alone).
    """
    sets: list[list[LinearRing]] = []
    first = first_pass_offset_m(interval_m, vehicle_width_m)
    r = float(turning_radius_m)
    outermost: shapely.Geometry | None = None
    for i in range(passes):
        depth = first + i * interval_m
        if r > 0.0:
            offset = field_local.buffer(-max(depth + r, 2.0 * r)).buffer(r)
        else:
            offset = field_local.buffer(-depth, join_style="mitre")
        rings = [
            ring
            for p in shapely.get_parts(offset)
            if isinstance(p, Polygon) and p.area > _SLIVER_M2
            for ring in (p.exterior, *p.interiors)
        ]
        if not rings:
            raise InvalidParameterError(
                "headland_passes",
                f"the field is too narrow for {passes} headland pass(es) at {interval_m:g} m",
            )
        sets.append(rings)
        outermost = offset if outermost is None else outermost
    if outermost is None:
        return sets
    sets[0] = sets[0] + spur_rings(
        field_local,
        outermost,
        interval_m=interval_m,
        vehicle_width_m=vehicle_width_m,
        turning_radius_m=r,
    )
    return sets


def spur_rings(
    field_local: Polygon,
    outermost: shapely.Geometry,
    *,
    interval_m: float,
    vehicle_width_m: float,
    turning_radius_m: float,
) -> list[LinearRing]:
    """Return rounds for the narrow parts of the headland band that the passes miss.

    Where the field is narrower than twice the first pass's depth (a strip between two
    fields, a long tip) no pass runs, and its rounding cuts sharp tips back further; the
    footprints of the passes and the area left for lines leave such parts untilled. Each
    part of at least :data:`SPUR_MIN_INTERVALS2` interval² gets a round of its own, as near
    its edge as the body may go (half the vehicle's width), rounded as the passes are: the
    vehicle drives out along one side and back along the other. Such a part is narrower
    than one interval, so the two footprints, reaching half an interval in from each side,
    meet in the middle. A part the round would not cover by :data:`SPUR_MIN_SHARE` keeps
    its gap (too narrow for the vehicle to turn in).

    Parameters
    ----------
    field_local : Polygon
    outermost : Geometry
        What the outermost pass encloses: its footprint and what lies inside it (the inner
        passes, the lines) reach half an interval beyond it.
    interval_m, vehicle_width_m, turning_radius_m : float
        As for :func:`headland_ring_sets` [m].

    Returns
    -------
    list of LinearRing
        Driven with the outermost pass; none for a field the passes reach everywhere.
    """
    d = float(interval_m)
    r = float(turning_radius_m)
    half_footprint = d / 2.0
    reached = shapely.buffer(outermost, half_footprint, join_style="mitre")
    missed = shapely.difference(field_local, reached)
    depth = max(vehicle_width_m / 2.0, _SPUR_MIN_DEPTH_M)
    spurs: list[LinearRing] = []
    for part in shapely.get_parts(missed):
        if not isinstance(part, Polygon) or part.area < SPUR_MIN_INTERVALS2 * d * d:
            continue
        # The part and the band beside it: its round runs along the field's edges, not
        # along the cut where the passes' footprints end.
        room = part.buffer(half_footprint).intersection(field_local)
        if r > 0.0:
            inside = room.buffer(-max(depth + r, 2.0 * r)).buffer(r)
        else:
            inside = room.buffer(-depth, join_style="mitre")
        rings = [
            piece.exterior
            for piece in shapely.get_parts(inside)
            if isinstance(piece, Polygon) and piece.area > _SLIVER_M2
        ]
        if not rings:
            continue
        covered = shapely.union_all(
            [ring.buffer(half_footprint, cap_style="flat", join_style="mitre") for ring in rings]
        )
        if covered.intersection(part).area >= SPUR_MIN_SHARE * part.area:
            spurs.extend(rings)
    return spurs
