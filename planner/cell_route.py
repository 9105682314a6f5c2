"""The winning heading driven: each cell's lines fitted for the vehicle, turns and moves.

Line ends are pulled back until the vehicle's turns fit (:func:`planner.line_ends.fit_lines`)
and every move between cells is the vehicle's own turn if it stays in, else routed inside
the field (:mod:`planner.routing`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt
import shapely
from shapely import MultiPolygon, Polygon

from planner.cell_plans import Cell, CellPlan
from planner.coverage import Chains, cell_area, convex_chains
from planner.line_ends import FittedLines, fit_line_turns, fit_lines, snake_skip
from planner.lines import from_sweep
from planner.move_curves import drivable_moves
from planner.ordering import order_boustrophedon, order_snake
from planner.route_builder import RouteBuilder, add_fitted_lines, densify
from planner.routing import FieldRouter
from planner.turns import STEP_M, TurnCurves, TurnEnds, vehicle_turns
from planner.types import Pattern, Vehicle

FloatArray = npt.NDArray[np.float64]

#: A move between cells leaves at least this much of each line it shortens [m].
_KEPT_LINE_M = 1.0


#: Fitted lines of a plan's cells by ``(cell, variant)``, before numbering.
CellFits = dict[tuple[int, int], FittedLines]


def fit_cell(
    plan: CellPlan,
    cell_index: int,
    variant: int,
    *,
    vehicle: Vehicle,
    skip: int,
    room: Polygon | MultiPolygon | None,
    planned: TurnCurves | None = None,
) -> FittedLines:
    """Order one cell's lines by ``variant`` and pull their ends back until the turns fit.

    ``room`` is the turning room already in the heading's sweep frame (or None: the cell);
    ``planned``, the turns between the ordered lines if they are planned already.
    """
    u, a, b, index = ordered_cell_lines(plan, cell_index, variant, skip=skip)
    return fit_lines(
        u,
        a,
        b,
        index,
        machine=room_chains(plan.cells[cell_index], room),
        vehicle=vehicle,
        planned=planned,
    )


def ordered_cell_lines(
    plan: CellPlan, cell_index: int, variant: int, *, skip: int
) -> tuple[FloatArray, FloatArray, FloatArray, npt.NDArray[np.int64]]:
    """Return one cell's lines in driving order: ``u, v_start, v_end`` and left-to-right index."""
    k = plan.cells[cell_index].lines
    scan = plan.scan
    u, lo, hi = scan.u[k], scan.v_lo[k], scan.v_hi[k]
    n = len(u)
    if skip > 1:
        index, up = order_snake(n, variant, skip=skip)
    else:
        index, up = order_boustrophedon(n, variant)
    return u[index], np.where(up, lo[index], hi[index]), np.where(up, hi[index], lo[index]), index


def fit_cells(
    plan: CellPlan,
    *,
    vehicle: Vehicle,
    pattern: Pattern,
    interval_m: float,
    turning_room: Polygon | MultiPolygon | None = None,
    fits: CellFits | None = None,
) -> list[FittedLines]:
    """Fit every cell of ``plan`` in its driving order (see :func:`add_cells`).

    ``fits`` holds cells fitted before, by ``(cell, variant)``; new fits are added to it. The
    first fitting round of all new cells plans its turns, level and lopsided, in one call
    each (:func:`planner.line_ends.fit_line_turns`): a cell has a few lines, and planning
    them cell by cell was mostly call overhead.
    """
    fits = {} if fits is None else fits
    skip = snake_skip(vehicle, interval_m) if pattern == "snake" else 1
    room = None if turning_room is None else to_sweep_frame(turning_room, plan.heading_deg)
    todo = [key for key in dict.fromkeys(plan.order) if key not in fits]
    ordered = [ordered_cell_lines(plan, c, v, skip=skip) for c, v in todo]
    machines = [room_chains(plan.cells[c], room) for c, _ in todo]
    first_turns = fit_line_turns(ordered, machines, vehicle)
    for key, (u, a, b, index), machine, turns in zip(
        todo, ordered, machines, first_turns, strict=True
    ):
        fits[key] = fit_lines(u, a, b, index, machine=machine, vehicle=vehicle, first_turns=turns)
    return [fits[key] for key in plan.order]


def to_sweep_frame(geometry: Polygon | MultiPolygon, heading: float) -> Polygon | MultiPolygon:
    """Rotate ``geometry`` from local ``x, y`` into the sweep frame ``u, v`` of ``heading``."""
    theta = math.radians(heading)
    cos_t, sin_t = math.cos(theta), math.sin(theta)

    def to_uv(xy: FloatArray) -> FloatArray:
        return np.stack(
            [xy[:, 0] * cos_t - xy[:, 1] * sin_t, xy[:, 0] * sin_t + xy[:, 1] * cos_t], 1
        )

    rotated: Polygon | MultiPolygon = shapely.transform(geometry, to_uv)
    return rotated


@dataclass(frozen=True, slots=True)
class DrivenCells:
    """A plan's cells as the vehicle drives them: fitted lines and the moves between cells.

    Attributes
    ----------
    fitted : list of FittedLines
        Every cell of the plan's order, in driving order (sweep frame): fitted, and the
        first and last lines shortened where a move between cells needs the room.
    moves : list of ndarray
        The moves between consecutive cells that have lines, local [m].
    """

    fitted: list[FittedLines]
    moves: list[FloatArray]


def drive_cells(
    plan: CellPlan, fitted: list[FittedLines], router: FieldRouter, *, vehicle: Vehicle
) -> DrivenCells:
    """Plan the moves between ``plan``'s fitted cells (in driving order), all at once.

    Each leaves the last line's end of one cell (driven from the line's start) for the first
    line's start of the next (:func:`moves_between_cells`), and may shorten each of the two
    lines by less than half, keeping :data:`_KEPT_LINE_M` of it (a cell of one line gives up
    length at both ends).
    """
    driven = [fit for fit in fitted if len(fit.u)]
    if len(driven) < 2:
        return DrivenCells(list(fitted), [])
    heading = plan.heading_deg
    first_u = np.array([fit.u[0] for fit in driven[1:]])
    first_v = np.array([fit.v_start[0] for fit in driven[1:]])
    last_u = np.array([fit.u[-1] for fit in driven[:-1]])
    x0, y0 = from_sweep(first_u, first_v, heading)
    x1, y1 = from_sweep(last_u, np.array([fit.v_end[-1] for fit in driven[:-1]]), heading)
    xb, yb = from_sweep(last_u, np.array([fit.v_start[-1] for fit in driven[:-1]]), heading)
    first_m = np.array([abs(fit.v_end[0] - fit.v_start[0]) for fit in driven[1:]])
    last_m = np.array([abs(fit.v_end[-1] - fit.v_start[-1]) for fit in driven[:-1]])
    moves, pulled_back, pushed_on = moves_between_cells(
        np.stack([x1, y1], axis=1),
        np.stack([xb, yb], axis=1),
        np.ones(len(driven) - 1, dtype=bool),
        np.stack([x0, y0], axis=1),
        np.array([fit.v_end[0] >= fit.v_start[0] for fit in driven[1:]], dtype=bool),
        heading=heading,
        router=router,
        vehicle=vehicle,
        back_room_m=np.maximum((last_m - _KEPT_LINE_M) / 2.0, 0.0),
        on_room_m=np.maximum((first_m - _KEPT_LINE_M) / 2.0, 0.0),
    )
    shortened = _shortened(driven, pulled_back, pushed_on)
    return DrivenCells([shortened.get(id(fit), fit) for fit in fitted], moves)


def _shortened(
    driven: list[FittedLines], pulled_back_m: FloatArray, pushed_on_m: FloatArray
) -> dict[int, FittedLines]:
    """Return the cells whose first or last line a move shortened, by ``id`` of their fit.

    Move ``k`` leaves cell ``k`` and joins cell ``k + 1`` (of the cells with lines). New
    arrays: a fit may be cached for other plans.
    """
    changed: dict[int, FittedLines] = {}
    for k, (back, on) in enumerate(zip(pulled_back_m.tolist(), pushed_on_m.tolist(), strict=True)):
        if back > 0.0:
            fit = changed.get(id(driven[k]), driven[k])
            v_end = fit.v_end.copy()
            v_end[-1] -= back if v_end[-1] >= fit.v_start[-1] else -back
            changed[id(driven[k])] = replace(fit, v_end=v_end)
        if on > 0.0:
            fit = changed.get(id(driven[k + 1]), driven[k + 1])
            v_start = fit.v_start.copy()
            v_start[0] += on if fit.v_end[0] >= v_start[0] else -on
            changed[id(driven[k + 1])] = replace(fit, v_start=v_start)
    return changed


def add_cells(
    route: RouteBuilder,
    plan: CellPlan,
    router: FieldRouter,
    *,
    vehicle: Vehicle,
    pattern: Pattern,
    interval_m: float,
    turning_room: Polygon | MultiPolygon | None = None,
    fits: CellFits | None = None,
    driven: DrivenCells | None = None,
) -> list[FittedLines]:
    """Append every cell's lines and turns, and the moves between cells, to ``route``.

    Each cell's lines are ordered (back and forth, or snake), then their ends are pulled
    back until the vehicle's turns fit the cell (:func:`planner.line_ends.fit_lines`), or,
    with headland passes, the machine area beyond the cell (``turning_room``): the turns
    swing out over the headland, as a tractor turns on the headland it then tills. Then the
    moves between cells are planned (:func:`drive_cells`), unless ``driven`` holds them
    already. ``route`` holds nothing yet, or only the start point.
    Returns the fitted lines of every cell, in driving order (sweep frame of the heading).
    """
    assert not route.x or route.roles == ["start"], "the cells come first in the route"
    if driven is None:
        cell_fits = fit_cells(
            plan,
            vehicle=vehicle,
            pattern=pattern,
            interval_m=interval_m,
            turning_room=turning_room,
            fits=fits,
        )
        driven = drive_cells(plan, cell_fits, router, vehicle=vehicle)
    first_index = 0
    fitted: list[FittedLines] = []
    for fit in driven.fitted:
        if len(fit.u) == 0:
            fitted.append(fit)  # one entry per cell, in driving order
            continue
        # Lines the turns could not reach are gone: number the rest left to right.
        rank = np.argsort(np.argsort(fit.index, kind="stable"), kind="stable")
        fitted.append(replace(fit, index=(first_index + rank).astype(np.int64)))
        first_index += len(fit.u)
    with_lines = [fit for fit in fitted if len(fit.u)]
    if not with_lines:
        return fitted
    add_fitted_lines(route, plan.heading_deg, with_lines[0])
    for fit, move in zip(with_lines[1:], driven.moves, strict=True):
        route.append("turn", None, move, "turn")
        add_fitted_lines(route, plan.heading_deg, fit, joined=True)
    return fitted


def room_chains(cell: Cell, room: Polygon | MultiPolygon | None) -> Chains:
    """Return the chains a cell's turns must stay within: the machine area over its span.

    The piece of ``room`` (the turning room in the heading's sweep frame) over the cell's
    ``u``-range that holds the cell, if it is one simple sweep-monotone polygon; else (or
    without ``room``) the cell itself.
    """
    if room is None:
        return cell.chains
    c = cell.chains
    big = 1e7
    strip = shapely.box(c.u_min, -big, c.u_max, big)
    middle = shapely.Point(
        (c.u_min + c.u_max) / 2.0,
        (
            float(np.interp((c.u_min + c.u_max) / 2.0, c.lo_u, c.lo_v))
            + float(np.interp((c.u_min + c.u_max) / 2.0, c.hi_u, c.hi_v))
        )
        / 2.0,
    )
    for piece in shapely.get_parts(shapely.intersection(room, strip)):
        if not isinstance(piece, Polygon) or piece.interiors or not piece.covers(middle):
            continue
        ring = np.asarray(shapely.orient_polygons(piece).exterior.coords)[:-1]
        chains = convex_chains(ring[:, 0], ring[:, 1])
        # Sweep-monotone exactly when the area between the two chains is the piece's area.
        if abs(cell_area(chains) - piece.area) <= 1e-6 * piece.area + 1e-6:
            return chains
    return cell.chains


def moves_between_cells(
    here_xy: FloatArray,
    before_xy: FloatArray,
    leaves_line: npt.NDArray[np.bool_],
    target_xy: FloatArray,
    up: npt.NDArray[np.bool_],
    *,
    heading: float,
    router: FieldRouter,
    vehicle: Vehicle,
    back_room_m: FloatArray | None = None,
    on_room_m: FloatArray | None = None,
) -> tuple[list[FloatArray], FloatArray, FloatArray]:
    """Plan the moves from line ends to other cells' first line starts.

    Move ``k`` leaves ``here_xy[k]``, the end of the line from ``before_xy[k]`` (if
    ``leaves_line[k]``), for ``target_xy[k]``, where a line runs along the heading (``up[k]``)
    or against it. Each is the vehicle's own turn (a Dubins or pivot curve from pose to pose)
    if it stays inside the machine area. Else a vehicle that pivots takes the shortest path
    inside it, with points at most 0.5 m apart, and turns its corners on the spot; one with
    a turning radius takes a curve that gives up some of the lines' length
    (:func:`planner.move_curves.drivable_moves`, at most ``back_room_m[k]`` off the line it
    leaves and ``on_room_m[k]`` off the one it joins), or, if none is found, that shortest
    path, whose corners it cannot turn (a known weakness, counted by ``bench.move_corners``).
    All turns are planned in one call and tested in another, the straight moves found in a
    third (:meth:`planner.routing.FieldRouter.paths`): a turn depends on its own ends alone,
    so the moves are those planned one by one.

    Parameters
    ----------
    here_xy, before_xy, target_xy : ndarray, shape (k, 2)
        Local [m].
    leaves_line, up : ndarray of bool, shape (k,)
    heading : float
        Line heading [deg].
    router : FieldRouter
    vehicle : Vehicle
    back_room_m, on_room_m : ndarray, shape (k,), optional
        The most each move may shorten the line it leaves and the line it joins [m]
        (default: nothing).

    Returns
    -------
    moves : list of ndarray
        Each move's points, from ``here_xy[k]`` (less its pull-back) to ``target_xy[k]``
        (plus its push-on), local [m].
    pulled_back_m, pushed_on_m : ndarray, shape (k,)
        How much earlier the line move ``k`` leaves now ends, and how much later the line it
        joins starts [m].
    """
    count = len(here_xy)
    # Lines run along the heading: +v is (sin h, cos h) in local x, y.
    theta = math.radians(heading)
    along = math.atan2(math.cos(theta), math.sin(theta))
    turning = [
        k for k in range(count) if leaves_line[k] and np.hypot(*(here_xy[k] - before_xy[k])) > 1e-9
    ]
    moves: list[FloatArray | None] = [None] * count
    if turning:
        ends = TurnEnds(
            here_xy[turning, 0],
            here_xy[turning, 1],
            np.array(
                [
                    math.atan2(here_xy[k, 1] - before_xy[k, 1], here_xy[k, 0] - before_xy[k, 0])
                    for k in turning
                ]
            ),
            target_xy[turning, 0],
            target_xy[turning, 1],
            np.array([along if up[k] else along + math.pi for k in turning]),
        )
        curves = vehicle_turns(ends, vehicle)
        tried = [(k, curves.curve(t)) for t, k in enumerate(turning)]
        tried = [(k, curve) for k, curve in tried if len(curve) >= 2]
        inside = router.inside_paths([curve for _, curve in tried]).tolist()
        for (k, curve), ok in zip(tried, inside, strict=True):
            if ok:
                moves[k] = curve
    pulled_back, pushed_on = np.zeros(count), np.zeros(count)
    routes: dict[int, FloatArray] = {}
    curving = [k for k in turning if moves[k] is None]
    if vehicle.min_turn_radius_m > 0.0 and curving:
        which = np.array(curving, dtype=np.int64)
        ends = TurnEnds(
            here_xy[which, 0],
            here_xy[which, 1],
            np.arctan2(
                here_xy[which, 1] - before_xy[which, 1], here_xy[which, 0] - before_xy[which, 0]
            ),
            target_xy[which, 0],
            target_xy[which, 1],
            np.where(up[which], along, along + math.pi),
        )
        no_room = np.zeros(count)
        driven = drivable_moves(
            ends,
            back_room_m=(no_room if back_room_m is None else back_room_m)[which],
            on_room_m=(no_room if on_room_m is None else on_room_m)[which],
            router=router,
            vehicle=vehicle,
        )
        for j, k in enumerate(curving):
            moves[k] = driven.curves[j]
            route = driven.routes[j]
            if route is not None:
                routes[k] = route
        pulled_back[which] = driven.pulled_back_m
        pushed_on[which] = driven.pushed_on_m
    routed = [k for k in range(count) if moves[k] is None and k not in routes]
    for k, path in zip(routed, router.paths(here_xy[routed], target_xy[routed]), strict=True):
        routes[k] = path
    for k in range(count):
        if moves[k] is None:
            moves[k] = densify(routes[k], STEP_M)
    return [move for move in moves if move is not None], pulled_back, pushed_on
