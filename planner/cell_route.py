"""The winning heading driven: each cell's lines fitted for the vehicle, with their turns.

Line ends are pulled back until the vehicle's turns fit (:func:`planner.line_ends.fit_lines`);
the moves between cells are :mod:`planner.cell_moves`'s.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import numpy.typing as npt
import shapely
from shapely import MultiPolygon, Polygon

from planner.cell_moves import DrivenCells, drive_cells
from planner.cell_plans import Cell, CellPlan
from planner.coverage import Chains, cell_area, convex_chains
from planner.line_ends import FittedLines, fit_line_turns, fit_lines, snake_skip
from planner.ordering import order_boustrophedon, order_snake
from planner.route_builder import RouteBuilder, add_fitted_lines
from planner.routing import FieldRouter
from planner.turns import TurnCurves
from planner.types import Pattern, Vehicle

FloatArray = npt.NDArray[np.float64]

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
