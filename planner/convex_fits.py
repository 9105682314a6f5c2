"""A convex field's lines fitted for the vehicle, at one heading or at many at once.

:func:`convex_lines` places, orders and fits the lines of one heading (the plan's own).
:func:`fit_headings` does the same at many headings of one field and measures what each
covers: R5's check on a small field fits every heading the search scored (some 50 to 500),
and one at a time that was mostly call overhead (1 ms a heading for a few lines). Here the
turns of every heading, and the lopsided variants of those that need them, are planned in one
call each (:func:`planner.line_ends.fit_line_turns`), and each heading keeps only the numpy
work of its own few lines.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import shapely
from shapely import MultiPolygon, Polygon

from planner.coverage import Chains, convex_chains, covered_each_cell
from planner.errors import InvalidParameterError
from planner.line_ends import (
    FirstTurns,
    FittedLines,
    fit_line_turns,
    fit_lines,
    machine_area,
    snake_skip,
)
from planner.lines import line_positions, to_sweep
from planner.ordering import order_boustrophedon, order_snake
from planner.turn_reach import side_reach_m
from planner.turns import turning_radius_m
from planner.types import Pattern, Vehicle

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True, slots=True)
class _Placed:
    """One heading's lines before fitting: driving order, sweep frame [m]."""

    u: FloatArray
    v_start: FloatArray
    v_end: FloatArray
    index: IntArray
    machine: Chains
    field_u: FloatArray  # the field's ring in the same frame
    field_v: FloatArray

    @property
    def width_m(self) -> float:
        """The field's width across the lines [m]."""
        return float(self.field_u.max() - self.field_u.min())


def convex_lines(
    field_local: Polygon,
    heading_deg: float,
    *,
    interval_m: float,
    vehicle: Vehicle,
    pattern: Pattern,
    variant: int,
    area: Polygon | None = None,
) -> FittedLines:
    """Place, order and fit the lines of a convex field for ``vehicle`` (sweep frame).

    The outermost lines lie ``interval / 2`` inside the boundary (R3) unless the body or its
    turns need more room: then half the vehicle's width plus the turns' sideways reach. The
    lines end on the machine area and are pulled back until the turns fit
    (:func:`planner.line_ends.fit_lines`).

    Raises
    ------
    InvalidParameterError
        If the vehicle does not fit the field.
    """
    if area is None:  # the same at every heading: a caller fitting many passes it in
        area = convex_machine_area(field_local, vehicle)
    placed = _place(_Rings(field_local, area), heading_deg, interval_m, vehicle, pattern, variant)
    return _fit(placed, interval_m, vehicle, None)


def fit_headings(
    field_local: Polygon,
    headings_deg: Sequence[float],
    variants: Sequence[int],
    *,
    interval_m: float,
    implement_width_m: float,
    vehicle: Vehicle,
    pattern: Pattern,
    area: Polygon | None = None,
) -> list[tuple[FittedLines, float] | InvalidParameterError]:
    """Fit a convex field's lines at many headings, and measure what each covers.

    Parameters
    ----------
    field_local : Polygon
        Convex field, local [m].
    headings_deg, variants : sequence
        Each heading [deg] and its variant (which corner the lines start from).
    interval_m, implement_width_m : float
        Line spacing and working width [m].
    vehicle : Vehicle
    pattern : {"boustrophedon", "snake"}
    area : Polygon, optional
        :func:`convex_machine_area` of the field, if known.

    Returns
    -------
    list
        Per heading, as :func:`convex_lines` fits it and the area its implement covers on
        those lines (R4) [m²], or the error :func:`convex_lines` would raise there.

    Examples
    --------
    Across a 40 m × 12 m field ten short lines lose more at their ends than three long ones:

    >>> from shapely import box
    >>> from planner.vehicles import resolve_vehicle
    >>> field = box(0, 0, 40, 12)
    >>> fits = fit_headings(field, [0.0, 90.0], [0, 0], interval_m=4.0, implement_width_m=4.0,
    ...                     vehicle=resolve_vehicle("hand_tractor"), pattern="boustrophedon")
    >>> [len(fit.u) for fit, _ in fits], [round(m2 / field.area, 3) for _, m2 in fits]
    ([10, 3], [0.877, 0.967])
    """
    if area is None:
        area = convex_machine_area(field_local, vehicle)
    rings = _Rings(field_local, area)
    placed = [
        _place(rings, float(h), interval_m, vehicle, pattern, int(k))
        for h, k in zip(headings_deg, variants, strict=True)
    ]
    ordered = [(p.u, p.v_start, p.v_end, p.index) for p in placed]
    planned = fit_line_turns(ordered, [p.machine for p in placed], vehicle)
    fits: list[FittedLines | InvalidParameterError] = []
    for lines, turns in zip(placed, planned, strict=True):
        try:
            fits.append(_fit(lines, interval_m, vehicle, turns))
        except InvalidParameterError as refused:
            fits.append(refused)
    # What each heading's fitted lines cover: the field's chains in every heading's frame,
    # measured together (covered_each_cell), lines left to right.
    chains, u, lo, hi, sizes = [], [], [], [], [0]
    for lines, fit in zip(placed, fits, strict=True):
        if isinstance(fit, InvalidParameterError):
            continue
        chains.append(convex_chains(lines.field_u, lines.field_v))
        order = np.argsort(fit.index, kind="stable")
        a, b = fit.v_start[order], fit.v_end[order]
        u.append(fit.u[order])
        lo.append(np.minimum(a, b))
        hi.append(np.maximum(a, b))
        sizes.append(len(order))
    covered: Iterator[float] = iter(())
    if chains:
        each = covered_each_cell(
            chains,
            np.cumsum(sizes),
            np.concatenate(u),
            np.concatenate(lo),
            np.concatenate(hi),
            implement_width_m,
        )
        covered = iter(each.tolist())
    return [fit if isinstance(fit, InvalidParameterError) else (fit, next(covered)) for fit in fits]


def convex_machine_area(field_local: Polygon, vehicle: Vehicle) -> Polygon:
    """Return :func:`planner.line_ends.machine_area` of a convex field (one piece)."""
    area = machine_area(field_local, vehicle)
    if isinstance(area, MultiPolygon):  # only a non-convex field erodes into pieces
        return max(area.geoms, key=lambda p: p.area)
    return area


class _Rings:
    """The rings of a convex field and of its machine area, local [m]: the same at every heading."""

    __slots__ = ("field", "machine")

    def __init__(self, field_local: Polygon, area: Polygon) -> None:
        # get_coordinates: np.asarray(.coords), cheaper.
        self.machine = shapely.get_coordinates(area.exterior)[:-1]
        self.field = shapely.get_coordinates(field_local.exterior)[:-1]


def _place(
    rings: _Rings,
    heading_deg: float,
    interval_m: float,
    vehicle: Vehicle,
    pattern: Pattern,
    variant: int,
) -> _Placed:
    """Place one heading's lines in driving order, ending on the machine area's chains."""
    d = float(interval_m)
    ring = rings.machine
    mu, mv = to_sweep(ring[:, 0], ring[:, 1], heading_deg)
    machine = convex_chains(mu, mv)
    outer = rings.field
    fu, fv = to_sweep(outer[:, 0], outer[:, 1], heading_deg)
    u_min, u_max = float(fu.min()), float(fu.max())
    skip = snake_skip(vehicle, d) if pattern == "snake" else 1
    spacings = tuple(d * k for k in range(1, skip + 1))
    margin = max(d / 2.0, vehicle.width_m / 2.0 + side_reach_m(vehicle, spacings))
    if u_max - u_min >= 2.0 * margin:
        u = line_positions(u_min + margin - d / 2.0, u_max - margin + d / 2.0, d)
    else:
        u = np.array([(machine.u_min + machine.u_max) / 2.0])
    # Lines beyond the machine area's sides (a sliver narrower than the body across) have
    # nowhere to run: they are left out, and one line down the middle stays if none is left.
    u = u[(u >= machine.u_min) & (u <= machine.u_max)]
    if len(u) == 0:
        u = np.array([(machine.u_min + machine.u_max) / 2.0])
    v_lo = np.interp(u, machine.lo_u, machine.lo_v)
    v_hi = np.interp(u, machine.hi_u, machine.hi_v)
    n = len(u)
    if pattern == "snake":
        index, up = order_snake(n, variant, skip=skip)
    else:
        index, up = order_boustrophedon(n, variant)
    lo, hi = v_lo[index], v_hi[index]
    return _Placed(u[index], np.where(up, lo, hi), np.where(up, hi, lo), index, machine, fu, fv)


def _fit(
    placed: _Placed, interval_m: float, vehicle: Vehicle, first_turns: FirstTurns | None
) -> FittedLines:
    """Fit the placed lines; a field too narrow for any turn is refused by name."""
    fit = fit_lines(
        placed.u,
        placed.v_start,
        placed.v_end,
        placed.index,
        machine=placed.machine,
        vehicle=vehicle,
        first_turns=first_turns,
    )
    # Narrower than the turning circle and the body: no turn can fit, say so.
    width = placed.width_m
    too_narrow = width < 2.0 * turning_radius_m(vehicle) + vehicle.width_m
    if len(fit.u) == 1 and width > float(interval_m) and too_narrow:
        raise InvalidParameterError(
            "vehicle",
            f"a {turning_radius_m(vehicle):g} m turning radius does not fit this "
            f"{width:.1f} m-wide field",
        )
    return fit
