"""A last resort for a move between cells that no curve serves: a search over the vehicle's arcs.

A move whose curve is neither the vehicle's own turn nor a chain of turns beside the shortest
path's corners (:mod:`planner.move_curves`), even with lines dropped
(:class:`planner.cell_moves._LineDrops`), is searched for here, as a hybrid A* search does
(Dolgov et al., "Practical search techniques in path planning for autonomous driving",
2008): from poses along the line it leaves, steps of the vehicle's tightest arcs either way
and straight ahead, on a grid of positions and headings, until the vehicle's own turn from
the pose reached to a pose along the line it joins stays inside the machine area. Every
step is an arc of the turning radius or a straight, so the path's curvature never exceeds
``1 / radius``; it is forward only (a vehicle that may reverse drives it too).

Written here rather than taken from a planning library: it is a hundred lines on the
planner's own turns and inside tests, and deterministic (R7), where sampling planners
(OMPL's) are random and a large dependency for the few moves per plan that need it.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from planner.routing import FieldRouter
from planner.turns import (
    SAGITTA_M,
    STEP_M,
    TurnEnds,
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
#: the small tractor it finds as many moves as with 20 times more (3 of the 14 its drives
#: ask for), and the 11 it does not find cost about 0.03 s each.
MOST_EXPANSIONS = 1000
#: The vehicle's turn to the line it joins is tried from every this many poses expanded.
SHOT_EVERY = 4
#: Weighted A*: the heuristic counts this much more, which finds a path in far fewer steps
#: (at most this factor longer than the grid's shortest).
HEURISTIC_WEIGHT = 1.5
#: A step on an arc costs this much more than one straight ahead, and a step that turns the
#: other way from the step before (or straightens) this many steps more: fewer wiggles.
TURN_COST = 0.1
SWITCH_COST = 0.5
#: A metre of line given up (a pulled-back end or a pushed-on start) costs as much as this
#: many metres driven: coverage first.
PULL_WEIGHT = 10.0


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


def search_move(
    ends: TurnEnds,
    pulls_back_m: FloatArray,
    pushes_on_m: FloatArray,
    *,
    router: FieldRouter,
    vehicle: Vehicle,
    most_expansions: int = MOST_EXPANSIONS,
) -> SearchedMove | None:
    """Search for a forward path of the vehicle's arcs for one move; None if none is found.

    Parameters
    ----------
    ends : TurnEnds
        One move: the end of the line it leaves and the start of the line it joins, with
        their headings, local [m] and [rad].
    pulls_back_m, pushes_on_m : ndarray
        The pulls the move may give the line it leaves and the pushes the line it joins,
        least first [m]: the search starts from each pulled-back end (each costing
        :data:`PULL_WEIGHT` times its pull) and ends at any pushed-on start.
    router : FieldRouter
        The machine area the path stays in.
    vehicle : Vehicle
        Its turning radius (or half its track if it pivots) bounds the path's curvature.
    most_expansions : int, optional
        Poses expanded before the search gives up.

    Returns
    -------
    SearchedMove or None
    """
    radius = turning_radius_m(vehicle)
    step_m = STEP_R * radius
    cell_m = CELL_R * radius
    arc_step = min(STEP_M, 2.0 * radius * math.acos(max(-1.0, 1.0 - SAGITTA_M / radius)))
    samples = max(1, math.ceil(step_m / arc_step))
    x0, y0, yaw0 = float(ends.x0[0]), float(ends.y0[0]), float(ends.yaw0[0])
    x1, y1, yaw1 = float(ends.x1[0]), float(ends.y1[0]), float(ends.yaw1[0])
    goals = np.column_stack(
        [
            x1 + pushes_on_m * math.cos(yaw1),
            y1 + pushes_on_m * math.sin(yaw1),
            np.full(len(pushes_on_m), yaw1),
        ]
    )
    # Each step's arcs from the origin heading along +x: left, straight, right.
    t = np.arange(1, samples + 1) * (step_m / samples)
    turned = t / radius
    shapes = []
    for side in (1.0, 0.0, -1.0):
        if side == 0.0:
            shapes.append(np.column_stack([t, np.zeros_like(t)]))
        else:
            shapes.append(
                np.column_stack([radius * np.sin(turned), side * radius * (1.0 - np.cos(turned))])
            )
    shape_xy = np.stack(shapes)  # (3, samples, 2)
    shape_yaw = np.array([step_m / radius, 0.0, -step_m / radius])

    # Nodes: pose, cost so far, parent, the points from the parent's pose (exclusive), the
    # pull of the start it comes from, and its step's steering (+1 left, 0, -1 right).
    poses: list[tuple[float, float, float]] = []
    costs: list[float] = []
    parents: list[int] = []
    pieces: list[FloatArray] = []
    pulls: list[float] = []
    steers: list[int] = []
    best_at: dict[tuple[int, int, int], float] = {}
    frontier: list[tuple[float, int]] = []

    def key(x: float, y: float, yaw: float) -> tuple[int, int, int]:
        return (
            math.floor(x / cell_m),
            math.floor(y / cell_m),
            int(round(yaw / (2.0 * math.pi) * HEADINGS)) % HEADINGS,
        )

    goal_costs = PULL_WEIGHT * pushes_on_m

    def heuristics(at: FloatArray) -> list[float]:
        # The straight distance to the cheapest goal: cheap, and with the weight it finds
        # the moves of real fields in few steps.
        distance_m = np.hypot(
            at[:, None, 0] - goals[None, :, 0], at[:, None, 1] - goals[None, :, 1]
        )
        return list((distance_m + goal_costs).min(axis=1).tolist())

    def push(
        pose: tuple[float, float, float],
        cost: float,
        parent: int,
        piece: FloatArray,
        pull: float,
        steer: int,
        estimate: float,
    ) -> None:
        cell = key(*pose)
        if best_at.get(cell, math.inf) <= cost:
            return
        best_at[cell] = cost
        poses.append(pose)
        costs.append(cost)
        parents.append(parent)
        pieces.append(piece)
        pulls.append(pull)
        steers.append(steer)
        node = len(poses) - 1
        heapq.heappush(frontier, (cost + HEURISTIC_WEIGHT * estimate, node))

    starts = np.column_stack(
        [
            x0 - pulls_back_m * math.cos(yaw0),
            y0 - pulls_back_m * math.sin(yaw0),
            np.full(len(pulls_back_m), yaw0),
        ]
    )
    for start, pull, estimate in zip(
        starts, pulls_back_m.tolist(), heuristics(starts), strict=True
    ):
        pose = (float(start[0]), float(start[1]), yaw0)
        push(pose, PULL_WEIGHT * pull, -1, start[None, :2].copy(), pull, 0, estimate)

    expanded = 0
    while frontier and expanded < most_expansions:
        _, node = heapq.heappop(frontier)
        x, y, yaw = poses[node]
        if best_at.get(key(x, y, yaw), math.inf) < costs[node]:
            continue  # reached more cheaply since
        if expanded % SHOT_EVERY == 0:
            found = _shot(node, poses, parents, pieces, goals, pushes_on_m, router, vehicle)
            if found is not None:
                points, push_m = found
                return SearchedMove(points, pulls[node], push_m)
        expanded += 1
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
        rotation = np.array([[cos_yaw, sin_yaw], [-sin_yaw, cos_yaw]])
        moved = shape_xy @ rotation + np.array([x, y])  # (3, samples, 2)
        held = np.flatnonzero(
            router.holds_points(moved.reshape(-1, 2)).reshape(3, samples).all(axis=1)
        )
        if len(held) == 0:
            continue
        reached = np.column_stack([moved[held, -1], yaw + shape_yaw[held]])
        for k, estimate in zip(held.tolist(), heuristics(reached), strict=True):
            end = moved[k, -1]
            steer = 1 - k  # left, straight, right
            step_cost = step_m * (
                1.0 + TURN_COST * abs(steer) + SWITCH_COST * (steer != steers[node])
            )
            push(
                (float(end[0]), float(end[1]), yaw + float(shape_yaw[k])),
                costs[node] + step_cost,
                node,
                moved[k],
                pulls[node],
                steer,
                estimate,
            )
    return None


def _shot(
    node: int,
    poses: list[tuple[float, float, float]],
    parents: list[int],
    pieces: list[FloatArray],
    goals: FloatArray,
    pushes_on_m: FloatArray,
    router: FieldRouter,
    vehicle: Vehicle,
) -> tuple[FloatArray, float] | None:
    """Return the path to ``node``, on by the vehicle's turn to the cheapest goal inside.

    Also the push-on of that goal [m]; None if no turn from ``node`` stays inside.
    """
    x, y, yaw = poses[node]
    count = len(goals)
    turns = vehicle_turns(
        TurnEnds(
            np.full(count, x),
            np.full(count, y),
            np.full(count, yaw),
            goals[:, 0],
            goals[:, 1],
            goals[:, 2],
        ),  # fmt: skip
        vehicle,
    )
    order = np.argsort(turns.length_m + PULL_WEIGHT * pushes_on_m, kind="stable")
    chain: list[FloatArray] = []
    at = node
    while at >= 0:
        chain.append(pieces[at])
        at = parents[at]
    driven = np.vstack(chain[::-1])
    for g in order.tolist():
        curve = turns.curve(g)
        if len(curve) < 2 or not router.holds_points(curve).all():
            continue
        points = np.vstack([driven, curve[1:]])
        if router.inside_path(points):
            return points, float(pushes_on_m[g])
    return None
