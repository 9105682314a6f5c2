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


def inner_parts(field_local: Polygon, *, passes: int, interval_m: float) -> list[Polygon]:
    """Return the area left for tillage lines inside ``passes`` headland rounds.

    A narrow neck can split it into several parts; they come oriented (exterior
    counter-clockwise), largest first.
    """
    if passes == 0:
        inner = field_local
    else:
        inner = field_local.buffer(-passes * interval_m, join_style="mitre")
    parts = [
        shapely.orient_polygons(p)
        for p in shapely.get_parts(inner)
        if isinstance(p, Polygon) and p.area > _SLIVER_M2
    ]
    parts.sort(key=lambda p: (-p.area, p.bounds))
    return parts


def headland_ring_sets(
    field_local: Polygon, *, passes: int, interval_m: float
) -> list[list[LinearRing]]:
    """Centre lines of the headland passes, outermost pass first: each pass's rings.

    Pass ``i`` runs ``(i + 1/2) · interval_m`` inside the boundary, around the exterior and
    around every hole (grown by the same distance), so its footprint fills the band from
    ``i · interval_m`` to ``(i + 1) · interval_m``.

    Raises
    ------
    InvalidParameterError
        If the field is too narrow for that many passes (the area inside them may be empty:
        then the plan is the passes alone).
    """
    sets: list[list[LinearRing]] = []
    for i in range(passes):
        offset = field_local.buffer(-(i + 0.5) * interval_m, join_style="mitre")
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
    return sets
