"""Moves between cells that a vehicle with a turning radius drives: curves, not corners.

A cell's last line runs to the machine area's edge, and the next cell's first line starts at
it: no forward curve leaves the one or reaches the other inside the field, so the shortest
move between them has corners. Here the two lines give up some of their length instead, as
:func:`planner.line_ends.fit_lines` pulls line ends back for the turns within a cell: the
move leaves the line it ends ``pulled_back_m`` before the line's end and joins the next
line ``pushed_on_m`` after its start, the least total length that lets a curve through
(coverage traded for a path the machine can drive, as R1 asks). The curve is the vehicle's
own turn between the two poses, or a chain of turns through poses beside the shortest
path's corners, each held off its corner by a fraction of the radius on the outside of the
bend (a shortest path hugs the corners it bends round; a curve through the corner would
cut into the hole or the bund there).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from planner.routing import FieldRouter
from planner.turns import TurnCurves, TurnEnds, turning_radius_m, vehicle_turns
from planner.types import Vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
#: A chain through poses beside a route's corners: the poses (x, y, yaw) and the curve
#: from the first to the last, local [m].
Chain = tuple[FloatArray, FloatArray]

#: How far a move may pull back the line it leaves, and push on the start of the line it
#: joins, in turning radii: each pair of these is tried, least total first.
PULL_STEPS_R = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 16.0 / 3.0, 20.0 / 3.0, 25.0 / 3.0, 10.0)
#: A pull found on those steps is tried again at this many parts of the step below it.
REFINE_STEPS = 4
#: How far the poses of a chain sit off the shortest path's corners, in turning radii.
CORNER_OFFSETS_R = (0.5, 1.0, 1.5)
#: The pairs of pulls tried in each batch, by index (most moves need one of the first).
_PAIR_BATCHES = (0, 8, 24, 56, len(PULL_STEPS_R) ** 2)
#: Curves are screened on this many points at either end first (where most leave) ...
_END_POINTS = 6
#: ... then on one point in this many (up to 6 m apart: points are at most 0.5 m apart),
#: before the exact test. The exact test decides, so the stride changes no plan, only the
#: time: of the curves that one in 12 passed, one in 3 turned away a further 4 %, on the
#: 223 real fields with the small tractor, for four times the point tests.
_SCREEN_STRIDE = 12


@dataclass(frozen=True, slots=True)
class DrivenMoves:
    """Curves found for moves between cells, and what they cost the lines they join.

    Attributes
    ----------
    curves : list of ndarray or None
        Each move's points, from its pulled-back start to its pushed-on end, local [m];
        None where no curve was found (the caller routes that move with corners).
    pulled_back_m, pushed_on_m : ndarray, shape (k,)
        How much earlier the line a move leaves ends, and how much later the line it joins
        starts [m] (0 where no curve was found).
    routes : list of ndarray or None
        The shortest path inside the field between each move's unpulled ends, where it was
        needed (every move without a curve has it), local [m].
    """

    curves: list[FloatArray | None]
    pulled_back_m: FloatArray
    pushed_on_m: FloatArray
    routes: list[FloatArray | None]


def pull_pairs_m(radius_m: float) -> FloatArray:
    """Every pair (pull back, push on) [m] a move may cost its lines, cheapest first.

    Sorted by the total, then by the pull-back: the line lengths given up, and among equal
    totals the one that keeps more of the line the move leaves.
    """
    pairs_m, _ = _pull_pairs(radius_m)
    return pairs_m.copy()


@functools.lru_cache(maxsize=64)
def _pull_pairs(radius_m: float) -> tuple[FloatArray, IntArray]:
    """:func:`pull_pairs_m`, and each pair's two steps' indices in :data:`PULL_STEPS_R`.

    Read-only, kept per radius: a plan asks for them on every call of
    :func:`drivable_moves`.
    """
    steps_m = np.asarray(PULL_STEPS_R) * radius_m
    back, on = np.meshgrid(np.arange(len(steps_m)), np.arange(len(steps_m)), indexing="ij")
    step_ids = np.stack([back.ravel(), on.ravel()], axis=1)
    pairs_m = steps_m[step_ids]
    order = np.lexsort((pairs_m[:, 0], pairs_m.sum(axis=1)))
    pairs_m, step_ids = pairs_m[order], step_ids[order]
    pairs_m.flags.writeable = False
    step_ids.flags.writeable = False
    return pairs_m, step_ids


def drivable_moves(
    ends: TurnEnds,
    *,
    back_room_m: FloatArray,
    on_room_m: FloatArray,
    router: FieldRouter,
    vehicle: Vehicle,
) -> DrivenMoves:
    """Find a curve the vehicle drives inside the field for each move between cells.

    A move is the vehicle's own turn between its pulled-back ends: the first pair of
    :func:`pull_pairs_m`, within the room its lines leave, whose curve stays inside the
    field. A move the first :data:`_PAIR_BATCHES` batch does not serve may instead be a
    chain of turns through poses off the corners of the shortest path between its ends,
    whichever costs the lines less. The pulls found are then refined (:func:`_refine`).

    Parameters
    ----------
    ends : TurnEnds
        Each move's unpulled ends: the end of the line it leaves, the start of the line it
        joins, and their headings, local [m] and [rad].
    back_room_m, on_room_m : ndarray, shape (k,)
        The most each move may pull back the line it leaves and push on the line it joins [m].
    router : FieldRouter
        The machine area the curves stay in, and the shortest paths in it.
    vehicle : Vehicle
        A vehicle with a turning radius.

    Returns
    -------
    DrivenMoves
    """
    count = len(ends)
    pairs_m, pair_steps = _pull_pairs(turning_radius_m(vehicle))
    within_room = (pairs_m[None, :, 0] <= back_room_m[:, None] + 1e-9) & (
        pairs_m[None, :, 1] <= on_room_m[:, None] + 1e-9
    )
    curves: list[FloatArray | None] = [None] * count
    pair_at = np.full(count, len(pairs_m), dtype=np.int64)  # the pair each found curve costs
    routes: list[FloatArray | None] = [None] * count
    through: list[Chain | None] = [None] * count  # the chain a curve runs through, if any
    for first, stop in zip(_PAIR_BATCHES[:-1], _PAIR_BATCHES[1:], strict=True):
        if first == _PAIR_BATCHES[1]:
            # The moves the cheapest pulls do not serve: their shortest paths, and chains
            # through them, which then bound the pulls the turn is tried at.
            todo = np.flatnonzero(pair_at == len(pairs_m))
            paths = router.paths(
                np.stack([ends.x0[todo], ends.y0[todo]], axis=1),
                np.stack([ends.x1[todo], ends.y1[todo]], axis=1),
            )
            for k, path in zip(todo.tolist(), paths, strict=True):
                routes[k] = path
            chained, cost, chains = _chained(
                ends.take(todo), within_room[todo], pair_steps, paths, router, vehicle
            )
            for j, k in enumerate(todo.tolist()):
                curves[k], pair_at[k], through[k] = chained[j], cost[j], chains[j]
        todo = np.flatnonzero(pair_at > first)
        if len(todo) == 0:
            break
        cheaper = within_room[todo, first:stop] & (
            np.arange(first, stop)[None, :] < pair_at[todo, None]
        )
        move, pair = np.nonzero(cheaper)
        move, pair = todo[move], pair + first  # move-major, each move's pairs in order
        if len(move) == 0:
            continue
        turns = _distinct_turns(_pulled_ends(ends, move, pairs_m[pair]), vehicle)
        for t in _first_inside(move, turns, router):
            k = int(move[t])
            curves[k], pair_at[k] = turns.curve(t).copy(), pair[t]
            through[k] = None  # the turn costs less than the chain found
    found = pair_at < len(pairs_m)
    pulls_m = np.where(found[:, None], pairs_m[np.minimum(pair_at, len(pairs_m) - 1)], 0.0)
    curves, pulls_m = _refine(ends, curves, pulls_m, through, router, vehicle)
    return DrivenMoves(curves, pulls_m[:, 0], pulls_m[:, 1], routes)


def _refine(
    ends: TurnEnds,
    curves: list[FloatArray | None],
    pulls_m: FloatArray,
    through: list[Chain | None],
    router: FieldRouter,
    vehicle: Vehicle,
) -> tuple[list[FloatArray | None], FloatArray]:
    """Pull each found move's lines back less, where a curve still fits.

    The pulls (``pulls_m``, shape (k, 2): back, on [m]) were found on the coarse steps of
    :data:`PULL_STEPS_R`; each of the two is tried again at :data:`REFINE_STEPS` - 1 points
    between the step below and itself, least first, the pull-back first and then the
    push-on with the pull-back kept. Returns the curves and pulls, refined.
    """
    curves, pulls_m = list(curves), pulls_m.copy()
    steps_m = np.asarray(PULL_STEPS_R) * turning_radius_m(vehicle)
    share = np.arange(1, REFINE_STEPS) / REFINE_STEPS
    for side in (0, 1):
        found = [k for k, curve in enumerate(curves) if curve is not None and pulls_m[k, side] > 0]
        if not found:
            continue
        now_m = pulls_m[found, side]
        below_m = steps_m[np.maximum(np.searchsorted(steps_m, now_m - 1e-9) - 1, 0)]
        move = np.repeat(np.array(found, dtype=np.int64), len(share))
        tried_m = pulls_m[move].copy()
        tried_m[:, side] = (below_m[:, None] + (now_m - below_m)[:, None] * share).ravel()
        for t, curve in _try_pairs(ends, move, tried_m, through, router, vehicle).items():
            k = int(move[t])
            curves[k] = curve
            pulls_m[k] = tried_m[t]
    return curves, pulls_m


def _try_pairs(
    ends: TurnEnds,
    move: IntArray,
    pulls_m: FloatArray,
    through: list[Chain | None],
    router: FieldRouter,
    vehicle: Vehicle,
) -> dict[int, FloatArray]:
    """Return each move's first candidate whose curve stays inside, by candidate, with it.

    Candidate ``t`` pulls move ``move[t]``'s lines by ``pulls_m[t]`` (back, on); a move's
    candidates are consecutive, cheapest first. Its curve is the vehicle's turn between the
    pulled ends, or, for a move with a chain in ``through``, the legs to and from the chain.
    """
    out: dict[int, FloatArray] = {}
    chained = np.array([through[k] is not None for k in move.tolist()], dtype=bool)
    direct = np.flatnonzero(~chained)
    if len(direct):
        turns = _distinct_turns(_pulled_ends(ends, move[direct], pulls_m[direct]), vehicle)
        for t in _first_inside(move[direct], turns, router):
            out[int(direct[t])] = turns.curve(t).copy()
    legs = np.flatnonzero(chained)
    if len(legs):
        chains = [chain for k in move[legs].tolist() if (chain := through[k]) is not None]
        pulled = _pulled_ends(ends, move[legs], pulls_m[legs])
        a = np.array([chain[0][0] for chain in chains])  # each chain's first pose
        b = np.array([chain[0][-1] for chain in chains])  # and its last
        into = _distinct_turns(
            TurnEnds(pulled.x0, pulled.y0, pulled.yaw0, a[:, 0], a[:, 1], a[:, 2]), vehicle
        )
        out_of = _distinct_turns(
            TurnEnds(b[:, 0], b[:, 1], b[:, 2], pulled.x1, pulled.y1, pulled.yaw1), vehicle
        )
        passing = _screened_inside(into, router) & _screened_inside(out_of, router)
        done: set[int] = set()
        for j in np.flatnonzero(passing).tolist():
            k = int(move[legs[j]])
            if k in done:
                continue
            curve = np.vstack([into.curve(j), chains[j][1][1:], out_of.curve(j)[1:]])
            if router.inside_path(curve):
                out[int(legs[j])] = curve
                done.add(k)
    return out


def _chained(
    ends: TurnEnds,
    within_room: npt.NDArray[np.bool_],
    pair_steps: IntArray,
    routes: list[FloatArray],
    router: FieldRouter,
    vehicle: Vehicle,
) -> tuple[list[FloatArray | None], IntArray, list[Chain | None]]:
    """Find each move's cheapest chain through poses beside its shortest path's corners.

    ``within_room[k, p]``: whether move ``k``'s lines have room for pair ``p`` of the pulls
    (:func:`_pull_pairs`), whose steps in :data:`PULL_STEPS_R` are ``pair_steps[p]`` (back,
    on). Returns the curves (None where none is found), the index of the pair of pulls each
    costs (``len(pair_steps)`` where none is found) and the chains they run through. Each
    offset of :data:`CORNER_OFFSETS_R` is tried in turn on the moves still without a curve.
    A chain's first leg depends only on the pull-back and its last only on the push-on:
    each is planned once per step of :data:`PULL_STEPS_R`.
    """
    count = len(ends)
    radius = turning_radius_m(vehicle)
    curves: list[FloatArray | None] = [None] * count
    through: list[Chain | None] = [None] * count
    used = np.full(count, len(pair_steps), dtype=np.int64)
    steps_m = np.asarray(PULL_STEPS_R) * radius
    for offset_r in CORNER_OFFSETS_R:
        todo = np.array(
            [k for k in range(count) if curves[k] is None and len(routes[k]) > 2], dtype=np.int64
        )
        chains = _corner_chains([routes[k] for k in todo], offset_r * radius, router, vehicle)
        kept = [(int(todo[j]), chain) for j, chain in enumerate(chains) if chain is not None]
        if not kept:
            continue
        move = np.array([k for k, _ in kept], dtype=np.int64)
        first_pose = np.array([chain[0][0] for _, chain in kept])  # each chain's first pose
        last_pose = np.array([chain[0][-1] for _, chain in kept])  # and its last
        n, m = len(kept), len(steps_m)
        who = np.repeat(np.arange(n), m)
        zero = np.zeros(n * m)
        start = _pulled_ends(ends, move[who], np.stack([np.tile(steps_m, n), zero], axis=1))
        end = _pulled_ends(ends, move[who], np.stack([zero, np.tile(steps_m, n)], axis=1))
        a, b = first_pose[who], last_pose[who]
        into = _distinct_turns(
            TurnEnds(start.x0, start.y0, start.yaw0, a[:, 0], a[:, 1], a[:, 2]), vehicle
        )
        out_of = _distinct_turns(
            TurnEnds(b[:, 0], b[:, 1], b[:, 2], end.x1, end.y1, end.yaw1), vehicle
        )
        into_ok = _screened_inside(into, router).reshape(n, m)
        out_ok = _screened_inside(out_of, router).reshape(n, m)
        # Each move's pairs that its room allows and both legs pass, cheapest first.
        passing = within_room[move] & into_ok[:, pair_steps[:, 0]] & out_ok[:, pair_steps[:, 1]]
        for j, p in zip(*np.nonzero(passing), strict=True):
            k = int(move[j])
            if curves[k] is not None:
                continue
            s_i, t_i = (int(i) for i in pair_steps[p])
            curve = np.vstack(
                [into.curve(j * m + s_i), kept[j][1][1][1:], out_of.curve(j * m + t_i)[1:]]
            )
            if router.inside_path(curve):
                curves[k], used[k], through[k] = curve, p, kept[j][1]
    return curves, used, through


def _first_inside(move: IntArray, turns: TurnCurves, router: FieldRouter) -> list[int]:
    """Return, for each move, its first candidate curve that stays inside (if any).

    Curve ``t`` of ``turns`` belongs to ``move[t]``; a move's curves are consecutive,
    cheapest first. All are screened (:func:`_screened_inside`); each move's curves that
    pass are then tested exactly, chords and all, cheapest first, until one stays inside.
    """
    chosen: list[int] = []
    done: set[int] = set()
    for t in np.flatnonzero(_screened_inside(turns, router)).tolist():
        k = int(move[t])
        if k not in done and router.inside_path(turns.curve(t)):
            chosen.append(t)
            done.add(k)
    return chosen


def _screened_inside(curves: TurnCurves, router: FieldRouter) -> npt.NDArray[np.bool_]:
    """Whether each curve passes a screen of its points: likely inside, if not surely.

    Its points at either end first (:func:`_ends_inside`), then one in
    :data:`_SCREEN_STRIDE` of the curves that passed: most curves that leave the field are
    turned away for few point tests, and an exact test follows on the few that pass.
    """
    inside = _ends_inside(curves, router)
    owner, index = _strided_points(curves.offsets, np.flatnonzero(inside), _SCREEN_STRIDE)
    inside[owner[~router.holds_points(curves.xy[index])]] = False
    return inside


def _strided_points(offsets: IntArray, which: IntArray, stride: int) -> tuple[IntArray, IntArray]:
    """Every ``stride``-th point of curves ``which``, from each one's first: curve and index.

    Curve ``k``'s points are ``offsets[k]:offsets[k + 1]``. Only the points returned are
    indexed: most curves were turned away before, and a curve has hundreds of points.
    """
    first = offsets[which]
    per_curve = (offsets[which + 1] - first + stride - 1) // stride
    owner = np.repeat(which, per_curve)
    rank = np.arange(len(owner)) - np.repeat(np.cumsum(per_curve) - per_curve, per_curve)
    return owner, np.repeat(first, per_curve) + rank * stride


def _ends_inside(curves: TurnCurves, router: FieldRouter) -> npt.NDArray[np.bool_]:
    """Whether the first and last :data:`_END_POINTS` points of each curve lie inside.

    Where a move leaves a line at the field's edge, or joins one, is where its curves
    leave the field, if they do: a screen of few points that turns most of them away.
    """
    counts = curves.point_counts()
    step = np.minimum(np.arange(_END_POINTS)[None, :], counts[:, None] - 1)
    index = np.concatenate(
        [curves.offsets[:-1, None] + step, curves.offsets[1:, None] - 1 - step], axis=1
    )
    held = router.holds_points(curves.xy[index.ravel()])
    return np.asarray(held.reshape(index.shape).all(axis=1))


def _distinct_turns(ends: TurnEnds, vehicle: Vehicle) -> TurnCurves:
    """Plan candidate moves' turns (:func:`planner.turns.vehicle_turns`), no shapes shared.

    Candidates differ (each has its own pulls or poses): looking for shared shapes among
    them costs time and finds few, if any (planned alone, a shape's points are the same).
    """
    return vehicle_turns(ends, vehicle, shared_shapes=False)


def _pulled_ends(ends: TurnEnds, move: IntArray, pairs_m: FloatArray) -> TurnEnds:
    """Return ``ends`` of ``move``, starts pulled back and ends pushed on by ``pairs_m``."""
    taken = ends.take(move)
    back, on = pairs_m[:, 0], pairs_m[:, 1]
    return TurnEnds(
        taken.x0 - back * np.cos(taken.yaw0),
        taken.y0 - back * np.sin(taken.yaw0),
        taken.yaw0,
        taken.x1 + on * np.cos(taken.yaw1),
        taken.y1 + on * np.sin(taken.yaw1),
        taken.yaw1,
    )


def _corner_chains(
    routes: list[FloatArray], offset_m: float, router: FieldRouter, vehicle: Vehicle
) -> list[Chain | None]:
    """Poses beside each route's corners and the curve through them, if it stays inside.

    Each pose sits ``offset_m`` off its corner on the outside of the bend, heading along
    the bisector of the two legs. Returns per route the poses (shape (c, 3): x, y, yaw) and
    the curve from the first to the last (just the first pose's point if there is one
    corner); None if the route has no bend or a corner is degenerate, or if the curve
    leaves the field. Every route's curves are planned in one call and tested in another.
    """
    poses: list[FloatArray | None] = []
    for route in routes:
        into = route[1:-1] - route[:-2]
        out_of = route[2:] - route[1:-1]
        into_m = np.hypot(*into.T)
        out_of_m = np.hypot(*out_of.T)
        if len(into) == 0 or (into_m < 1e-9).any() or (out_of_m < 1e-9).any():
            poses.append(None)
            continue
        into, out_of = into / into_m[:, None], out_of / out_of_m[:, None]
        outward = into - out_of  # away from the corner the path bends round
        outward_m = np.hypot(*outward.T)
        bends = outward_m > 1e-9
        if not bends.any():
            poses.append(None)
            continue
        tangent = into + out_of
        xy = route[1:-1][bends] + offset_m * outward[bends] / outward_m[bends, None]
        yaw = np.arctan2(tangent[bends, 1], tangent[bends, 0])
        poses.append(np.column_stack([xy, yaw]))
    between = [p for p in poses if p is not None and len(p) > 1]
    chains: list[Chain | None] = [None] * len(routes)
    pieces: list[FloatArray] = []
    ok: list[bool] = []
    if between:
        a = np.concatenate([p[:-1] for p in between])
        b = np.concatenate([p[1:] for p in between])
        turns = _distinct_turns(
            TurnEnds(a[:, 0], a[:, 1], a[:, 2], b[:, 0], b[:, 1], b[:, 2]), vehicle
        )
        pieces = [turns.curve(t) for t in range(len(turns))]
        ok = router.inside_paths(pieces).tolist()
    used = 0
    for j, p in enumerate(poses):
        if p is None:
            continue
        if len(p) == 1:
            chains[j] = (p, p[:1, :2].copy())
            continue
        mine = slice(used, used + len(p) - 1)
        used += len(p) - 1
        if all(ok[mine]):
            chain = pieces[mine]
            chains[j] = (p, np.vstack([chain[0], *(piece[1:] for piece in chain[1:])]))
    return chains
