"""A last resort for a move no curve serves: a search over the vehicle's arcs.

A move between two line ends (or between a spiral's rounds and its core) whose curve is
neither the vehicle's own turn nor a chain of turns beside the shortest path's corners
(:mod:`planner.move_curves`) is searched for here, as a hybrid A* search does (Dolgov et
al., "Practical search techniques in path planning for autonomous driving", 2008): from
poses along the line it leaves, steps of the vehicle's tightest arcs either way and
straight ahead, on a grid of positions and headings, until the vehicle's own turn from a
pose reached to a pose along the line it joins stays inside the machine area. Every step is
an arc of the turning radius or a straight, forward, so the path's curvature never exceeds
``1 / radius``; the last piece is the vehicle's own turn (a Reeds–Shepp curve, reversing,
for a vehicle that may reverse).

Written here rather than taken from a planning library: it runs on the planner's own turns
and inside tests, and it is deterministic (R7), where sampling planners (OMPL's) are random
and a large dependency for the few moves per plan that need it.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from planner.routing import FieldRouter
from planner.turns import (
    SAGITTA_M,
    STEP_M,
    TurnCurves,
    TurnEnds,
    dubins_turn,
    turning_radius_m,
    vehicle_turns,
)
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]

#: One step of the search: this arc length, in turning radii.
STEP_R = 0.6
#: The grid's cells: this size, in turning radii, and this many headings round.
CELL_R = 0.5
HEADINGS = 36
#: The search gives up after this many poses expanded. On the 223 real fields at 4 m with
#: the small tractor (44bdf87) the drives ask for 7 moves and it finds 2, within 200 poses;
#: the 5 it does not find, all on one field, cost 0.12-0.21 s each. In the spirals' cores
#: (``bench.spiral_times``' 25 fields, both tractors) 3 of the 16 it finds come out
#: otherwise when it stops at 250: the limit stays.
MOST_EXPANSIONS = 1000
#: The vehicle's turn to the line it joins is tried from every this many poses expanded.
SHOT_EVERY = 4
#: Weighted A*: the heuristic (the straight distance to the nearest goal) counts this much
#: more, which finds a path in far fewer steps, not the shortest.
HEURISTIC_WEIGHT = 1.5
#: A step on an arc costs this much more than one straight ahead, and a step that turns the
#: other way from the step before (or straightens) this many steps more: fewer wiggles.
TURN_COST = 0.1
SWITCH_COST = 0.5
#: A metre of line given up (a pulled-back end or a pushed-on start) costs as much as this
#: many metres driven: coverage first.
PULL_WEIGHT = 10.0
#: The steering of the search's three steps, in the order of :func:`_steps`' shapes.
_STEERING = (1, 0, -1)  # left, straight, right


@dataclass(frozen=True, slots=True)
class SearchedMove:
    """A move found by :func:`search_move`.

    Attributes
    ----------
    points : ndarray, shape (k, 2)
        From the pulled-back end of the line it leaves to the pushed-on start of the line
        it joins, local [m]; at most ``STEP_M`` apart.
    pulled_back_m, pushed_on_m : float
        How much earlier the line it leaves ends, and how much later the line it joins
        starts [m].
    """

    points: FloatArray
    pulled_back_m: float
    pushed_on_m: float


class _Node(NamedTuple):
    """A pose the search reached, and how."""

    x: float
    y: float
    yaw: float
    cost: float  # length driven, plus the pull-back weighted and the turning penalties
    parent: int  # index of the node it was reached from, -1 for a start
    points: FloatArray  # from the parent's pose (excluded) to this one, local [m]
    pulled_back_m: float  # of the start it comes from
    steer: int  # of the step that reached it: +1 left, 0 straight, -1 right


def search_move(
    ends: TurnEnds,
    pulls_back_m: FloatArray,
    pushes_on_m: FloatArray,
    *,
    router: FieldRouter,
    vehicle: Vehicle,
    most_expansions: int = MOST_EXPANSIONS,
) -> SearchedMove | None:
    """Search for a path of the vehicle's arcs for one move; None if none is found.

    Parameters
    ----------
    ends : TurnEnds
        One move: the end of the line it leaves and the start of the line it joins, with
        their headings, local [m] and [rad].
    pulls_back_m, pushes_on_m : ndarray
        The pulls the move may give the line it leaves and the pushes the line it joins
        [m], at least one each (0: none): the search starts from each pulled-back end (each
        costing :data:`PULL_WEIGHT` times its pull) and ends at any pushed-on start.
    router : FieldRouter
        The machine area the path stays in.
    vehicle : Vehicle
        Its turning radius (or half its track if it pivots) bounds the path's curvature.
    most_expansions : int, optional
        Poses expanded before the search gives up.

    Returns
    -------
    SearchedMove or None

    Raises
    ------
    ValueError
        If ``pulls_back_m`` or ``pushes_on_m`` is empty.
    """
    if len(pulls_back_m) == 0 or len(pushes_on_m) == 0:
        raise ValueError("search_move needs at least one pull-back and one push-on (0: none)")
    radius_m = turning_radius_m(vehicle)
    step_m = STEP_R * radius_m
    cell_m = CELL_R * radius_m
    x0, y0, yaw0 = float(ends.x0[0]), float(ends.y0[0]), float(ends.yaw0[0])
    x1, y1, yaw1 = float(ends.x1[0]), float(ends.y1[0]), float(ends.yaw1[0])
    goals = np.column_stack([x1 + pushes_on_m * math.cos(yaw1), y1 + pushes_on_m * math.sin(yaw1)])
    goal_costs = PULL_WEIGHT * pushes_on_m
    shapes, shape_yaw = _steps(radius_m, step_m)

    def estimate(x: float, y: float) -> float:
        return float((np.hypot(goals[:, 0] - x, goals[:, 1] - y) + goal_costs).min())

    def cell(x: float, y: float, yaw: float) -> tuple[int, int, int]:
        # Positions from the move's start (so the path does not depend on where the field
        # lies), headings rounded to the nearest of HEADINGS.
        return (
            math.floor((x - x0) / cell_m),
            math.floor((y - y0) / cell_m),
            round(yaw / (2.0 * math.pi) * HEADINGS) % HEADINGS,
        )

    nodes: list[_Node] = []
    cheapest: dict[tuple[int, int, int], float] = {}  # the least cost reaching each cell
    frontier: list[tuple[float, int]] = []

    def reach(node: _Node) -> None:
        key = cell(node.x, node.y, node.yaw)
        if cheapest.get(key, math.inf) <= node.cost:
            return
        cheapest[key] = node.cost
        nodes.append(node)
        priority = node.cost + HEURISTIC_WEIGHT * estimate(node.x, node.y)
        heapq.heappush(frontier, (priority, len(nodes) - 1))

    for pull in pulls_back_m.tolist():
        x, y = x0 - pull * math.cos(yaw0), y0 - pull * math.sin(yaw0)
        reach(_Node(x, y, yaw0, PULL_WEIGHT * pull, -1, np.array([[x, y]]), pull, 0))

    expanded = 0
    while frontier and expanded < most_expansions:
        _, at = heapq.heappop(frontier)
        node = nodes[at]
        if cheapest[cell(node.x, node.y, node.yaw)] < node.cost:
            continue  # its cell was reached more cheaply since
        if expanded % SHOT_EVERY == 0:
            found = _shot(
                at, nodes, goals=goals, goal_yaw=yaw1, goal_costs=goal_costs,
                router=router, vehicle=vehicle,
            )  # fmt: skip
            if found is not None:
                points, g = found
                return SearchedMove(points, node.pulled_back_m, float(pushes_on_m[g]))
        expanded += 1
        # The step shapes run along +x from the origin; rows are points, so the matrix
        # that turns them by the node's heading is the transpose of the usual one.
        cos_yaw, sin_yaw = math.cos(node.yaw), math.sin(node.yaw)
        moved = shapes @ np.array([[cos_yaw, sin_yaw], [-sin_yaw, cos_yaw]])
        moved += np.array([node.x, node.y])  # (3, samples, 2)
        held = router.holds_points(moved.reshape(-1, 2)).reshape(moved.shape[:2]).all(axis=1)
        for k in np.flatnonzero(held).tolist():
            steer = _STEERING[k]
            turning = TURN_COST * abs(steer) + SWITCH_COST * (steer != node.steer)
            end = moved[k, -1]
            reach(
                _Node(
                    float(end[0]),
                    float(end[1]),
                    node.yaw + float(shape_yaw[k]),
                    node.cost + step_m * (1.0 + turning),
                    at,
                    moved[k],
                    node.pulled_back_m,
                    steer,
                )  # fmt: skip
            )
    return None


def _steps(radius_m: float, step_m: float) -> tuple[FloatArray, FloatArray]:
    """Return the search's three steps from the origin heading along +x: left, straight, right.

    Returns their points, shape (3, samples, 2) (the origin excluded; at most ``STEP_M``
    apart and close enough that a chord of an arc stays within ``SAGITTA_M`` of it), and
    the heading each turns by [rad].
    """
    arc_step = min(STEP_M, 2.0 * radius_m * math.acos(max(-1.0, 1.0 - SAGITTA_M / radius_m)))
    samples = max(1, math.ceil(step_m / arc_step))
    along = np.arange(1, samples + 1) * (step_m / samples)
    turned = along / radius_m
    shapes = [
        np.column_stack([radius_m * np.sin(turned), side * radius_m * (1.0 - np.cos(turned))])
        if side
        else np.column_stack([along, np.zeros_like(along)])
        for side in _STEERING
    ]
    return np.stack(shapes), np.array(_STEERING, dtype=float) * step_m / radius_m


def _shot(
    at: int,
    nodes: list[_Node],
    *,
    goals: FloatArray,
    goal_yaw: float,
    goal_costs: FloatArray,
    router: FieldRouter,
    vehicle: Vehicle,
) -> tuple[FloatArray, int] | None:
    """Return the path to node ``at`` and on by the vehicle's turn to a goal, if inside.

    The goals are tried cheapest first (turn length plus the goal's cost); also returns
    the goal's index. None if no turn from the node stays inside.
    """
    node = nodes[at]
    count = len(goals)
    ends = TurnEnds(
        np.full(count, node.x), np.full(count, node.y), np.full(count, node.yaw),
        goals[:, 0], goals[:, 1], np.full(count, goal_yaw),
    )  # fmt: skip
    turns: TurnCurves
    if vehicle.can_reverse:
        turns = vehicle_turns(ends, vehicle)
    else:
        # Every Dubins word: near the goal a straight or an S-bend is what fits, where the
        # vehicle's U-turns between lines would try only loops (its bulbs).
        turns = dubins_turn(ends, radius_m=turning_radius_m(vehicle))
    order = np.argsort(turns.length_m + goal_costs, kind="stable")
    pieces: list[FloatArray] = []
    back = at
    while back >= 0:
        pieces.append(nodes[back].points)
        back = nodes[back].parent
    driven = np.vstack(pieces[::-1])
    for g in order.tolist():
        curve = turns.curve(g)
        if len(curve) < 2 or not router.holds_points(curve).all():
            continue
        points = np.vstack([driven, curve[1:]])
        if router.inside_path(points):
            return points, g
    return None
