"""A convex field's long edges: their directions, and the edge-by-edge coverage estimate.

The search's estimate of fitted coverage counts lines, not the slope of the boundary they end
on; on a large field a vehicle with wide turns pulls its ends back far more on slanted edges.
:func:`given_up_by_edges` estimates, edge by edge, what a heading gives up; where the estimate
fails, the planner fits the long edges' directions (:func:`edge_headings`) in full
(:mod:`planner.fitted_choice`, :mod:`planner.general`).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import shapely
from shapely import Polygon

from planner.angles import COVERAGE_SLACK, candidate_headings
from planner.heading_coverage import convex_coverage
from planner.lines import to_sweep
from planner.turn_reach import edge_loss_m2, end_reach_m
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]


#: The edge-by-edge estimate is trusted on fields at least this many turns' reach across
#: (it ignores the overlap of the strips at corners, which a small field is made of).
_EDGE_ESTIMATE_MIN_REACHES = 20.0


def given_up_by_edges(
    field_local: Polygon, heading_deg: float, interval_m: float, vehicle: Vehicle
) -> float | None:
    """Coverage the heading gives up by the edge-by-edge estimate [pp], None if beyond R5.

    Scored at every candidate heading (:func:`planner.angles.candidate_headings`): straight
    lines' coverage in closed form less :func:`planner.turn_reach.edge_loss_m2`. None also
    where that estimate does not hold (a field only a few turns across).
    """
    ring = np.asarray(shapely.orient_polygons(field_local).exterior.coords)[:-1]
    headings = np.append(candidate_headings(ring), heading_deg)
    u_ring, _ = to_sweep(ring[:, 0], ring[:, 1], headings[:, None])
    # The field's least width (a convex field's is across one of its edges).
    width = float(np.ptp(u_ring, axis=1).min())
    reach = end_reach_m(vehicle, float(interval_m)) + vehicle.width_m
    if width < _EDGE_ESTIMATE_MIN_REACHES * reach:
        return None
    area = float(field_local.area)
    estimate = convex_coverage(ring, headings, interval_m)
    estimate -= edge_loss_m2(vehicle, interval_m, ring, headings) / area
    given_up = float(estimate.max() - estimate[-1])
    if given_up > COVERAGE_SLACK:
        return None
    return max(given_up, 0.0) * 100.0


#: Edge directions planned in full when the search's estimate fails, longest edges first.
MAX_EDGE_CHECKS = 16


def edge_headings(ring_xy: FloatArray) -> FloatArray:
    """Directions of the longest :data:`MAX_EDGE_CHECKS` edges of a ring [deg, 0–180).

    Examples
    --------
    >>> edge_headings(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]])).tolist()
    [63.434948823, 90.0, 0.0]
    """
    dx = np.roll(ring_xy[:, 0], -1) - ring_xy[:, 0]
    dy = np.roll(ring_xy[:, 1], -1) - ring_xy[:, 1]
    length = np.hypot(dx, dy)
    longest = np.argsort(-length, kind="stable")[:MAX_EDGE_CHECKS]
    longest = longest[length[longest] > 0]
    return np.asarray(np.round(np.degrees(np.arctan2(dx[longest], dy[longest])) % 180.0, 9))
