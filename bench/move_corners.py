"""How many turns between lines a vehicle with a turning radius cannot drive as exported (R1).

``python -m bench.move_corners [VEHICLE] [--limit K] [--pattern P] [--every N]`` plans every
real field of :mod:`bench.bench_fields` at its 4 m interval (VEHICLE defaults to
``small_tractor``; ``--every 9``: the 25 fields of ``bench.spiral_times``) and looks at each
turn between two lines (with ``--pattern spiral``, rounds too) as the vehicle would drive
it (a vehicle with a turning radius: one that pivots drives a corner on the spot): the
turn's points with a point half a metre back along what it leaves and half a metre on
along what it joins (along a shorter line, its length; :func:`turn_seams`), so that a
heading that jumps where the turn meets a line counts too. A turn is
*sharp* where the circle through three consecutive points is tighter than the turning
radius even at the least the exported points allow: they are rounded to 1e-9°, which on
steps of a few centimetres can tighten a circle by a tenth (:func:`curvatures`). Turns
within a cell are held to the radius by the tests; the sharp ones are moves between cells
for which no curve was found, even with the lines shortened (:mod:`planner.move_curves`),
up to three of them dropped (``planner.cell_moves._LineDrops``) or the vehicle's arcs
searched (:mod:`planner.move_search`): the shortest path inside the machine area, with
corners (:func:`planner.cell_moves.moves_between_cells`).
Not part of ``make bench``.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterator

import numpy as np

from bench.bench_fields import DATASETS, INTERVAL_M, load
from planner import PlannerError, plan_coverage
from planner.pipeline import LONLAT_DECIMALS
from planner.projection import field_frame
from planner.turns import turning_radius_m
from planner.types import CoveragePlan

#: Points this far along the lines on either side are added to each turn [m].
SEAM_M = 0.5
#: The most an exported point may lie from where the planner put it [m]: half the last of
#: :data:`planner.pipeline.LONLAT_DECIMALS` decimal degrees in both coordinates, at
#: 111.32 km a degree (about 0.08 mm).
ROUNDING_M = 0.5 * 10.0**-LONLAT_DECIMALS * 111_320.0 * math.sqrt(2.0)


def curvatures(points: np.ndarray, *, rounding_m: float = ROUNDING_M) -> np.ndarray:
    """A lower bound of the curvature of the circle through every three consecutive points.

    Each exported point may lie up to ``rounding_m`` from where the planner put it. That
    turns each step's direction by up to about ``2 rounding_m / step`` and changes the
    chord by up to ``2 rounding_m``, so on steps of a few centimetres a circle through three
    rounded points can be a tenth tighter than the curve. Each curvature is
    ``2 sin(turn) / chord`` with the turn less that error and the chord more: the least the
    points allow. The bound is loose on short steps (on 6 cm steps an arc of 2.4 m would
    pass for 3 m): a count of sharp turns says which are provably sharp.

    Parameters
    ----------
    points : ndarray, shape (k, 2)
        A polyline, local [m]; triples with a step under 5 cm are left out.
    rounding_m : float, optional
        How far each point may lie from the curve [m] (0: the points are exact).

    Returns
    -------
    ndarray
        Curvature [1/m] of each triple kept.
    """
    a, b, c = points[:-2], points[1:-1], points[2:]
    ab, bc, ca = (np.hypot(*(q - p).T) for p, q in ((a, b), (b, c), (c, a)))
    ok = (ab > 0.05) & (bc > 0.05) & (ca > 0.05)
    first, second = (b - a)[ok], (c - b)[ok]
    cross = first[:, 0] * second[:, 1] - first[:, 1] * second[:, 0]
    turn = np.arctan2(np.abs(cross), np.einsum("ij,ij->i", first, second))
    turn_error = 2.0 * rounding_m * (1.0 / ab[ok] + 1.0 / bc[ok])
    least_sin = np.minimum(
        np.sin(np.clip(turn - turn_error, 0.0, np.pi)),
        np.sin(np.clip(turn + turn_error, 0.0, np.pi)),
    )
    return np.asarray(2.0 * least_sin / (ca[ok] + 2.0 * rounding_m))


#: The segments a counted turn may leave or join: with the spiral, its rounds too.
_DRIVEN = {"boustrophedon": ("line",), "snake": ("line",), "spiral": ("line", "round")}


def _way(points: np.ndarray, at_end: bool, kind: str) -> np.ndarray | None:
    """Unit direction a segment is driven in where a turn leaves it (``at_end``) or joins it.

    A line's whole length (straight), a round's last or first step; None if it has none.
    """
    if kind == "line":
        step = points[-1] - points[0]
    else:
        step = points[-1] - points[-2] if at_end else points[1] - points[0]
    length_m = float(np.hypot(*step))
    return step / length_m if length_m > 0.0 else None


def turn_seams(
    plan: CoveragePlan, driven: tuple[str, ...] = ("line",)
) -> Iterator[tuple[int, np.ndarray]]:
    """Each turn between two driven segments as the vehicle drives it, local [m].

    The turn's points get a point :data:`SEAM_M` back along what it leaves and one on
    along what it joins (along a line, at most its length), so that a heading that jumps
    where the turn meets a segment bends the seam. A round's direction is its last (or
    first) step's: a round driven once round ends where it starts.

    Parameters
    ----------
    plan : CoveragePlan
        A plan, its segments in driving order.
    driven : tuple of str
        The kinds of segment a turn joins: ``("line",)``, or ``("line", "round")`` for a
        spiral.

    Yields
    ------
    index : int
        The turn's index among ``plan.segments``.
    seam : ndarray, shape (k + 2, 2)
        Its ``k`` points with the two added, local [m].
    """
    frame = field_frame(plan.field_lonlat)
    local = [np.stack(frame.to_local_xy(*np.asarray(s.lonlat).T), axis=1) for s in plan.segments]
    kinds = [s.kind for s in plan.segments]

    def reach_m(points: np.ndarray, kind: str) -> float:
        if kind != "line":
            return SEAM_M
        return min(SEAM_M, float(np.hypot(*(points[-1] - points[0]))))

    for k in range(1, len(kinds) - 1):
        if kinds[k] != "turn" or kinds[k - 1] not in driven or kinds[k + 1] not in driven:
            continue
        before, turn, after = local[k - 1], local[k], local[k + 1]
        back = _way(before, True, kinds[k - 1])
        on = _way(after, False, kinds[k + 1])
        if back is None or on is None:
            continue
        back_m, on_m = reach_m(before, kinds[k - 1]), reach_m(after, kinds[k + 1])
        yield k, np.vstack([turn[:1] - back * back_m, turn, turn[-1:] + on * on_m])


def sharp_turns(field: object, vehicle: str, pattern: str = "boustrophedon") -> tuple[int, int]:
    """Plan ``field``; return its turns between driven segments and how many are sharp.

    A turn is counted where it leaves and joins a line (and, for the spiral, a round).
    """
    plan = plan_coverage(
        field,  # type: ignore[arg-type]
        interval_m=INTERVAL_M,
        vehicle=vehicle,
        pattern=pattern,  # type: ignore[arg-type]
    )
    assert plan.vehicle is not None
    radius = turning_radius_m(plan.vehicle)
    turns = sharp = 0
    for _, seam in turn_seams(plan, _DRIVEN[pattern]):
        turns += 1
        sharp += bool((curvatures(seam) > 1.0 / radius * (1.0 + 1e-6)).any())
    return turns, sharp


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.move_corners")
    parser.add_argument("vehicle", nargs="?", default="small_tractor")
    parser.add_argument("--limit", type=int, default=None, help="only the first LIMIT fields")
    parser.add_argument("--pattern", choices=sorted(_DRIVEN), default="boustrophedon")
    parser.add_argument(
        "--every",
        type=int,
        default=1,
        help="only fields 1, 1 + EVERY, … (bench.spiral_times: 9); default: all",
    )
    args = parser.parse_args()
    fields = [(fid, f) for name in DATASETS for fid, f in load(name)][: args.limit]
    if args.every > 1:
        fields = fields[1 :: args.every]
    turns = sharp = with_sharp = 0
    for _, field in fields:
        try:
            t, s = sharp_turns(field, args.vehicle, args.pattern)
        except PlannerError:
            continue
        turns, sharp, with_sharp = turns + t, sharp + s, with_sharp + (s > 0)
    print(
        f"{args.vehicle}, {args.pattern}, {len(fields)} fields at {INTERVAL_M:g} m: {sharp} of "
        f"{turns} turns tighter than the turning radius, on {with_sharp} fields"
    )


if __name__ == "__main__":
    main()
