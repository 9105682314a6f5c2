"""How far a vehicle's turns reach past the line ends, and what that costs the coverage.

:func:`planner.line_ends.fit_lines` pulls line ends back until each turn fits; the heading
search and the choice of headings need the same figures before any line is fitted: how far
a turn between lines at a spacing swings beyond its two ends (:func:`end_reach_m`, and
beside them: :func:`side_reach_m`), and the area the pulled-back ends leave untilled
(:func:`fitting_loss_m2`, and along a slanted edge :func:`edge_loss_m2`).
"""

from __future__ import annotations

import functools
import math

import numpy as np
import numpy.typing as npt

from planner.turns import TurnEnds, vehicle_turns
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@functools.lru_cache(maxsize=256)
def side_reach_m(vehicle: Vehicle, spacings_m: tuple[float, ...]) -> float:
    """How far the vehicle's turns swing out sideways beyond the two lines they join [m].

    Two arcs and a straight stay between the lines; an Ω bulges out by ``radius - spacing/2``
    on each side. Measured on the turns themselves, for every spacing given (cached: the
    same vehicle and interval come back request after request).
    """
    s = np.asarray(spacings_m, dtype=float)
    zero = np.zeros(len(s))
    ends = TurnEnds(zero, zero, zero + math.pi / 2.0, s, zero, zero - math.pi / 2.0)
    curves = vehicle_turns(ends, vehicle)
    owner = np.repeat(np.arange(len(s)), curves.point_counts())
    beyond = np.maximum(-curves.xy[:, 0], curves.xy[:, 0] - s[owner])
    return float(max(beyond.max(initial=0.0), 0.0))


@functools.lru_cache(maxsize=256)
def end_reach_m(vehicle: Vehicle, spacing_m: float) -> float:
    """How far the vehicle's U-turn between lines ``spacing_m`` apart runs past their ends [m].

    Each line end is pulled back by about this much (:func:`fit_lines`).

    Examples
    --------
    >>> from planner.vehicles import resolve_vehicle
    >>> round(end_reach_m(resolve_vehicle("hand_tractor"), 4.0), 3)   # the pivot: half the track
    0.35
    """
    zero = np.zeros(1)
    ends = TurnEnds(zero, zero, zero + math.pi / 2.0, zero + spacing_m, zero, zero - math.pi / 2.0)
    curves = vehicle_turns(ends, vehicle)
    return float(max(curves.xy[:, 1].max(initial=0.0), 0.0))


def fitting_loss_m2(
    vehicle: Vehicle, interval_m: float, line_counts: IntArray, widths_m: FloatArray
) -> FloatArray:
    """Estimate the area the fitting takes from straight lines that end on the boundary [m²].

    Every line loses half the vehicle's width at both ends (it ends on the machine area), and
    every end at a turn the turn's reach past it (:func:`end_reach_m`), each over the strip
    the line alone covers: one interval, but the last line's strip is what is left of the
    field's width after the others (it overlaps its neighbour, R2), so a heading whose last
    line hardly adds a strip is not charged a whole line for it. The heading search subtracts
    this from its closed-form coverage, so that a heading with more, shorter lines is not
    preferred for a coverage it will not have.

    Parameters
    ----------
    vehicle : Vehicle
    interval_m : float
        Line spacing [m].
    line_counts : ndarray of int, shape (H,)
        Lines per heading.
    widths_m : ndarray, shape (H,)
        The field's width across the lines per heading [m].

    Examples
    --------
    >>> from planner.vehicles import resolve_vehicle
    >>> hand = resolve_vehicle("hand_tractor")   # 0.85 m wide, a 0.35 m pivot reach
    >>> fitting_loss_m2(hand, 4.0, np.array([2, 3]), np.array([8.0, 8.5])).round(2).tolist()
    [9.6, 11.6]
    """
    d = float(interval_m)
    n = np.asarray(line_counts, dtype=float)
    # np.clip's bounds as np.maximum and np.minimum (its wrapper costs more than the work); a
    # -0.0 it would make +0.0 adds the same below.
    last = np.minimum(np.maximum(np.asarray(widths_m, dtype=float) - (n - 1.0) * d, 0.0), d)
    strips = np.maximum(n - 1.0, 0.0) * d + last
    # Turn ends: two per line but the first's and the last's one each.
    turn_ends = np.where(n >= 2.0, 2.0 * np.maximum(n - 2.0, 0.0) * d + d + last, 0.0)
    reach = end_reach_m(vehicle, d)
    return np.asarray(strips * vehicle.width_m + turn_ends * reach)


#: Angles between a boundary edge and the across-lines axis at which the pull-back is
#: tabulated (:func:`_pull_back_table`) [rad]; the last, parallel to the lines, is the limit.
_EDGE_ANGLES_RAD = np.linspace(0.0, math.pi / 2.0, 33)


@functools.lru_cache(maxsize=256)
def _pull_back_table(vehicle: Vehicle, spacing_m: float) -> FloatArray:
    """Pull-back of line ends per metre of boundary, by the edge's angle (:func:`edge_loss_m2`).

    A U-turn between lines ``spacing_m`` apart whose ends lie on a straight boundary of slope
    ``s`` (along the lines, per metre across) must slide back until its highest point, measured
    from that boundary, is at the ends: ``max(v - s u)``. The two senses of the turn (to the
    left and to the right) are averaged, and the result is per metre of edge (``cos`` of the
    angle times the pull-back). Cached: the same vehicle and interval come back.
    """
    slopes = np.tan(_EDGE_ANGLES_RAD[:-1])
    k = len(slopes)
    zero = np.zeros(k)
    reach = np.zeros(k)
    for sense in (1.0, -1.0):
        ends = TurnEnds(
            zero,
            zero,
            zero + math.pi / 2.0,
            zero + spacing_m,
            sense * slopes * spacing_m,
            zero - math.pi / 2.0,
        )
        curves = vehicle_turns(ends, vehicle)
        owner = np.repeat(np.arange(k), curves.point_counts())
        above = curves.xy[:, 1] - sense * slopes[owner] * curves.xy[:, 0]
        need = np.full(k, -np.inf)
        np.maximum.at(need, owner, above)
        reach += np.maximum(need, 0.0) / 2.0
    per_edge_m = np.cos(_EDGE_ANGLES_RAD[:-1]) * reach
    return np.append(per_edge_m, per_edge_m[-1])


def edge_loss_m2(
    vehicle: Vehicle, interval_m: float, ring_xy: FloatArray, headings_deg: FloatArray
) -> FloatArray:
    """Estimate the area fitting takes from straight lines, edge by edge of a convex ring [m²].

    Unlike :func:`fitting_loss_m2` (which counts lines), every boundary edge loses a strip as
    wide as the vehicle's half-width (the machine area), plus the pull-back of the line ends
    on it, which grows with the edge's slope across the lines (:func:`_pull_back_table`). It
    follows the fitted coverage's differences between headings on large fields; it ignores
    the lines left out at the sides and the overlap of the strips at corners, so it overstates
    the loss on fields a few turns wide.

    Parameters
    ----------
    vehicle : Vehicle
    interval_m : float
        Line spacing [m].
    ring_xy : ndarray, shape (m, 2)
        The convex field's exterior, local [m], not closed.
    headings_deg : ndarray, shape (H,)

    Returns
    -------
    ndarray, shape (H,)
    """
    dx = np.roll(ring_xy[:, 0], -1) - ring_xy[:, 0]
    dy = np.roll(ring_xy[:, 1], -1) - ring_xy[:, 1]
    length = np.hypot(dx, dy)
    heading = np.radians(np.asarray(headings_deg, dtype=float))[:, None]
    # The across-lines axis of a heading clockwise from north is (cos h, -sin h).
    across = np.abs(dx * np.cos(heading) - dy * np.sin(heading)) / np.where(length > 0, length, 1)
    angle = np.arccos(np.clip(across, 0.0, 1.0))
    per_m = np.interp(angle, _EDGE_ANGLES_RAD, _pull_back_table(vehicle, float(interval_m)))
    return np.asarray((length * (vehicle.width_m / 2.0 + per_m)).sum(axis=1))
