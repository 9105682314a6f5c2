"""Headland passes (planner/headlands.py): the rounds and the spurs into narrow parts."""

from __future__ import annotations

import shapely
from shapely import Polygon

from planner.headlands import headland_ring_sets

#: A 40 m square with a strip 3 m wide and 50 m long off its east side [m].
SQUARE_WITH_STRIP = Polygon(
    [(0, 0), (40, 0), (40, 18), (90, 18), (90, 21), (40, 21), (40, 40), (0, 40)]
)
STRIP = shapely.box(40, 18, 90, 21)


def footprint(rings: list[shapely.LinearRing], interval_m: float) -> shapely.Geometry:
    return shapely.union_all(
        [r.buffer(interval_m / 2, cap_style="flat", join_style="mitre") for r in rings]
    )


def test_a_strip_narrower_than_the_interval_gets_a_spur_round_inside_it() -> None:
    # At 4 m the pass runs 2 m in: the 3 m strip has no room for it.
    (rings,) = headland_ring_sets(
        SQUARE_WITH_STRIP, passes=1, interval_m=4.0, vehicle_width_m=0.85, turning_radius_m=0.35
    )
    assert len(rings) == 2
    spur = rings[1]
    assert spur.within(STRIP.buffer(2.0))  # in the strip and the band beside it
    # Half the vehicle's width from the edges, the body in (less the buffer's polygonal arcs,
    # under 1 mm here, as for the passes themselves).
    assert SQUARE_WITH_STRIP.exterior.distance(spur) >= 0.425 - 1e-3
    tilled = shapely.intersection(footprint(rings, 4.0), STRIP).area
    assert tilled >= 0.95 * STRIP.area


def test_a_field_the_pass_reaches_everywhere_has_no_spur() -> None:
    (rings,) = headland_ring_sets(
        shapely.box(0, 0, 40, 30), passes=2, interval_m=4.0, vehicle_width_m=0.85
    )[:1]
    assert len(rings) == 1


def test_no_spur_where_the_vehicle_cannot_turn_in_the_strip() -> None:
    # A 3 m turning radius needs 6 m to come back: the strip keeps its gap.
    (rings,) = headland_ring_sets(
        SQUARE_WITH_STRIP, passes=1, interval_m=4.0, vehicle_width_m=1.3, turning_radius_m=3.0
    )
    assert len(rings) == 1
