"""The plan's curves: which legs the simulator follows as a curve, and where on them it aims.

The paper's tractor steers to the next waypoint and counts it reached within 1 m (its
section 3); its route had the line ends only. A plan's turns, rounds and corner loops are
curves sampled every 0.5 m or less, and tighter than that radius: a hand tractor's corner arc
is 0.36 m in radius, its corner loop 0.72 m across. Counting each of their points reached
within 1 m lets the tractor drive straight across them (the paper field's spiral at 4 m: 106 m
driven of 123 m planned). So on a curve the controller does what a driver does:

- it pursues a point ahead *along the path*, from its projection on the leg it is on, and
  passes a point of the curve when it comes abeam of it, however far off it is;
- it looks ``lookahead_m`` ahead, but never past where the path bends by more than
  ``bend_deg`` from the leg it is on: on a round's straight stretch it aims far ahead and holds
  a steady line; at a corner it aims just round the bend, so it pivots where the plan pivots
  (about the inner wheel for an arc, the outer one for a loop) instead of cutting across.

The paper's law and its 1 m radius stay on everything else: the tillage lines and every leg
longer than 0.5 m, so a line end is still reached within 1 m of the estimate at the end of its
line. Where a curve ends at a line end, the start or the finish (:data:`STOP_ROLES`), that
point is reached within the radius once it is the next one, i.e. once the curve has been
driven to the point before it: the turn is driven, and the line begins where it begins.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

#: A leg this short or shorter, off the tillage lines, is part of a curve [m]: the planner
#: samples turns, rounds and their loops every 0.5 m or less (1 mm of slack for rounding).
CURVE_STEP_M = 0.5 + 1e-3
#: The aim lies at least this far ahead [m]: about a pivot's radius, so that at the sharpest
#: bend it still gives a direction.
MIN_AIM_M = 0.3
#: Waypoints reached the paper's way (within the acceptance radius) even at a curve's end.
STOP_ROLES = frozenset({"start", "line_start", "line_end", "finish"})


@dataclass(frozen=True, slots=True)
class CurvePath:
    """The route as the 10 Hz loop reads it along its curves, in plain lists.

    Index ``k`` is waypoint ``k`` and leg ``k``, from waypoint ``k - 1`` to ``k`` (leg 0 is
    empty), as in the loop's table of legs.

    Attributes
    ----------
    on_curve : list of bool
        Leg ``k`` lies on a curve (:func:`curve_legs`).
    stop : list of bool
        Waypoint ``k`` is reached the paper's way, within the acceptance radius.
    s_m : list of float
        Distance along the route to waypoint ``k`` [m].
    reach_m : list of float
        How far along the route the aim may go from leg ``k`` (:func:`bend_reach_m`) [m].
    """

    on_curve: list[bool]
    stop: list[bool]
    s_m: list[float]
    reach_m: list[float]


def curve_legs(
    roles: Sequence[str], lines: Sequence[int | None], leg_length_m: FloatArray
) -> npt.NDArray[np.bool_]:
    """Return which legs lie on a curve: no longer than :data:`CURVE_STEP_M`, off the lines.

    Parameters
    ----------
    roles, lines : sequences
        Each waypoint's role and tillage line.
    leg_length_m : array
        Length of leg ``k`` (waypoint ``k - 1`` to ``k``) at index ``k - 1`` [m].

    Returns
    -------
    bool array
        One per waypoint: leg ``k`` lies on a curve (False for waypoint 0).

    Examples
    --------
    >>> curve_legs(["line_start", "line_end", "turn", "line_start"], [0, 0, None, 1],
    ...            np.array([0.4, 0.3, 0.2])).tolist()
    [False, False, True, True]
    """
    n = len(roles)
    out = np.zeros(n, dtype=bool)
    for k in range(1, n):
        tillage = (
            roles[k - 1] == "line_start"
            and roles[k] == "line_end"
            and lines[k - 1] is not None
            and lines[k - 1] == lines[k]
        )
        out[k] = not tillage and leg_length_m[k - 1] <= CURVE_STEP_M
    return out


def bend_reach_m(
    x_m: FloatArray, y_m: FloatArray, *, bend_rad: float, lookahead_m: float
) -> FloatArray:
    """For each leg, how far along the route it runs within ``bend_rad`` of that leg's direction.

    Leg ``k``'s reach is the distance along the route to the start of the first later leg
    whose direction has turned (cumulatively, either way) by more than ``bend_rad`` from leg
    ``k``'s: the aim point goes no further. Legs that do not bend so within ``lookahead_m`` of
    leg ``k``'s end reach infinitely far (the look-ahead limits the aim).

    Parameters
    ----------
    x_m, y_m : arrays
        The waypoints, local frame [m].
    bend_rad : float
        Largest bend the aim may look round [rad].
    lookahead_m : float
        Look-ahead distance [m].

    Returns
    -------
    array
        Reach of leg ``k`` at index ``k`` (index 0 unused) [m].

    Examples
    --------
    A 2 m leg north, then a right angle east: the north legs reach the corner.

    >>> reach = bend_reach_m(np.array([0.0, 0.0, 0.0, 1.0]), np.array([0.0, 1.0, 2.0, 2.0]),
    ...                      bend_rad=0.5, lookahead_m=2.5)
    >>> reach.tolist()
    [inf, 2.0, 2.0, inf]
    """
    n = len(x_m)
    dx = np.diff(x_m)
    dy = np.diff(y_m)
    step = np.hypot(dx, dy)
    s = np.concatenate([[0.0], np.cumsum(step)])
    # Each leg's direction (a leg of no length keeps the one before), turning accumulated.
    heading = np.arctan2(dx, dy)
    moving = np.flatnonzero(step > 0.0)
    if len(moving) == 0:
        return np.full(n, math.inf)
    carry = np.maximum.accumulate(np.where(step > 0.0, np.arange(n - 1), 0))
    carry = np.where(carry < moving[0], moving[0], carry)
    turned = np.concatenate([[0.0], np.unwrap(heading[carry])])
    reach = np.full(n, math.inf)
    k = np.arange(1, n)  # legs still looking for their bend
    offset = 1
    while len(k):
        j = k + offset
        inside = j < n
        k, j = k[inside], j[inside]
        inside = s[j - 1] < s[k] + lookahead_m
        k, j = k[inside], j[inside]
        bent = np.abs(turned[j] - turned[k]) > bend_rad
        reach[k[bent]] = s[j[bent] - 1]
        k = k[~bent]
        offset += 1
    return reach


def curve_path(
    x_m: FloatArray,
    y_m: FloatArray,
    roles: Sequence[str],
    lines: Sequence[int | None],
    *,
    bend_rad: float,
    lookahead_m: float,
) -> CurvePath:
    """Return the route's curves, distances and reaches for the 10 Hz loop.

    Parameters
    ----------
    x_m, y_m : arrays
        The waypoints, local frame [m].
    roles, lines : sequences
        Each waypoint's role and tillage line.
    bend_rad : float
        Largest bend the aim may look round [rad].
    lookahead_m : float
        Look-ahead distance [m].
    """
    step = np.hypot(np.diff(x_m), np.diff(y_m))
    s = np.concatenate([[0.0], np.cumsum(step)])
    return CurvePath(
        on_curve=curve_legs(roles, lines, step).tolist(),
        stop=[role in STOP_ROLES for role in roles],
        s_m=s.tolist(),
        reach_m=bend_reach_m(x_m, y_m, bend_rad=bend_rad, lookahead_m=lookahead_m).tolist(),
    )


def aim_point(
    path: CurvePath,
    legs: Sequence[tuple[float, float, float, float, float, float, float]],
    target: int,
    along_m: float,
    *,
    lookahead_m: float,
    min_aim_m: float,
) -> tuple[float, float]:
    """Return the point pursued on a curve [m]: ahead along the route, short of its next bend.

    Parameters
    ----------
    path : CurvePath
    legs : sequence of tuples
        The loop's legs: ``(ax, ay, bx, by, ux, uy, length)`` of leg ``k`` at index ``k``.
    target : int
        The waypoint being steered to (``>= 1``).
    along_m : float
        Along-track distance of the tractor on leg ``target`` [m] (may run past its end).
    lookahead_m : float
        Look-ahead distance [m].
    min_aim_m : float
        The aim lies at least this far ahead, even at a bend (an aim at the tractor's own
        position gives no direction) [m].

    Returns
    -------
    (float, float)
        The aim point, local frame [m].
    """
    s_m = path.s_m
    last = len(s_m) - 1
    s = s_m[target - 1] + max(along_m, 0.0)
    # The leg the tractor's projection lies on, and the aim's distance along the route.
    here = min(bisect_left(s_m, s, target), last)
    aim = min(s + lookahead_m, max(path.reach_m[here], s + min_aim_m))
    leg = min(bisect_left(s_m, aim, here), last)
    ax, ay, _, _, ux, uy, length = legs[leg]
    t = min(max(aim - s_m[leg - 1], 0.0), length)
    return ax + t * ux, ay + t * uy


__all__ = [
    "CURVE_STEP_M",
    "MIN_AIM_M",
    "STOP_ROLES",
    "CurvePath",
    "aim_point",
    "bend_reach_m",
    "curve_legs",
    "curve_path",
]
