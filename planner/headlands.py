"""Headland passes: rounds parallel to the boundary, for turning room and the edges lines miss.

Pass ``i`` (from 0, outermost) runs ``(i + 1/2) · interval`` inside the boundary, so its
footprint fills the band from ``i · interval`` to ``(i + 1) · interval``; the tillage lines
then cover what lies inside the last band.
"""

from __future__ import annotations

from shapely import LinearRing, Polygon

from planner.errors import InvalidParameterError


def inner_field(field_local: Polygon, *, passes: int, interval_m: float) -> Polygon:
    """Return the part of ``field_local`` left for tillage lines inside ``passes`` rounds.

    Raises
    ------
    InvalidParameterError
        If the field is too narrow for that many passes.

    Examples
    --------
    >>> from shapely import box
    >>> inner_field(box(0, 0, 40, 20), passes=2, interval_m=4.0).bounds
    (8.0, 8.0, 32.0, 12.0)
    """
    if passes == 0:
        return field_local
    inner = field_local.buffer(-passes * interval_m, join_style="mitre")
    if not isinstance(inner, Polygon) or inner.is_empty:
        raise InvalidParameterError(
            "headland_passes",
            f"the field is too narrow for {passes} headland pass(es) at {interval_m:g} m",
        )
    return inner


def headland_rings(field_local: Polygon, *, passes: int, interval_m: float) -> list[LinearRing]:
    """Return the centre lines of the headland passes, outermost first, counter-clockwise."""
    rings: list[LinearRing] = []
    for i in range(passes):
        offset = field_local.buffer(-(i + 0.5) * interval_m, join_style="mitre")
        if not isinstance(offset, Polygon) or offset.is_empty:
            raise InvalidParameterError(
                "headland_passes",
                f"the field is too narrow for {passes} headland pass(es) at {interval_m:g} m",
            )
        ring = offset.exterior
        rings.append(ring if ring.is_ccw else LinearRing(list(ring.coords)[::-1]))
    return rings
