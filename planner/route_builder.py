"""A route under construction, local [m]: waypoints with roles, lines and segments.

A fitted cell's lines and turns are appended to it by :func:`add_fitted_lines`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from planner.line_ends import FittedLines
from planner.lines import from_sweep
from planner.types import SegmentKind, WaypointRole

FloatArray = npt.NDArray[np.float64]


@dataclass
class RouteBuilder:
    """A route under construction, local [m], with the role and line of every point.

    ``segments`` holds ``(kind, index, first waypoint, last waypoint)``; a segment shares its
    end points with its neighbours.
    """

    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    roles: list[WaypointRole] = field(default_factory=list)
    lines: list[int | None] = field(default_factory=list)
    segments: list[tuple[SegmentKind, int | None, int, int]] = field(default_factory=list)

    def here(self) -> tuple[float, float] | None:
        """Return the last point, or None if the route is empty."""
        return (self.x[-1], self.y[-1]) if self.x else None

    def append(
        self,
        kind: SegmentKind,
        index: int | None,
        points: FloatArray,
        role: WaypointRole,
        line: int | None = None,
        *,
        last_role: WaypointRole | None = None,
    ) -> None:
        """Add a segment through ``points``, joined to the route's last point if any.

        If the route is not empty, ``points[0]`` must be its last point (it is not repeated).
        """
        first = len(self.x) - 1 if self.x else 0
        new = points[1:] if self.x else points
        roles = [role] * len(new)
        if last_role is not None and roles:
            roles[-1] = last_role
        self.x.extend(new[:, 0].tolist())
        self.y.extend(new[:, 1].tolist())
        self.roles.extend(roles)
        self.lines.extend([line] * len(new))
        if len(self.x) - 1 > first:
            self.segments.append((kind, index, first, len(self.x) - 1))


def densify(points: FloatArray, step_m: float) -> FloatArray:
    """Insert points along a polyline so that none are more than ``step_m`` apart."""
    if len(points) < 2:
        return points
    gaps = np.hypot(*np.diff(points, axis=0).T)
    pieces = np.maximum(np.ceil(gaps / step_m), 1).astype(np.int64)
    start = np.repeat(points[:-1], pieces, axis=0)
    delta = np.repeat(np.diff(points, axis=0) / pieces[:, None], pieces, axis=0)
    within = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces)
    dense = start + delta * within[:, None]
    return np.vstack([dense, points[-1:]])


def add_fitted_lines(
    route: RouteBuilder, heading: float, fit: FittedLines, *, joined: bool = False
) -> None:
    """Append a cell's fitted lines and the driven turns between them to ``route``.

    If the route's last point is the start point, a transit leg joins it to the first line.
    With ``joined``, the route already ends at the first line's start (a routed move).
    """
    n = len(fit.u)
    if n == 0:
        return
    offsets = fit.turns.offsets
    # A turn's curve holds its two ends and the points between; a degenerate curve of one
    # point (the next line starts where this one ends) has none between.
    inner = np.maximum(np.diff(offsets) - 2, 0) if n > 1 else np.zeros(0, dtype=np.int64)
    # Driving order: s0 e0 (turn 0) s1 e1 (turn 1) … as blocks of 2 + inner points.
    sizes = np.full(n, 2, dtype=np.int64)
    sizes[:-1] += inner
    block = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    total = int(sizes.sum())
    u = np.empty(total)
    v = np.empty(total)
    u[block], v[block] = fit.u, fit.v_start
    u[block + 1], v[block + 1] = fit.u, fit.v_end
    if n > 1:
        keep = np.ones(len(fit.turns.xy), dtype=bool)
        keep[offsets[:-1]] = False
        keep[offsets[1:] - 1] = False
        slots = np.ones(total, dtype=bool)
        slots[block] = False
        slots[block + 1] = False
        u[slots], v[slots] = fit.turns.xy[keep, 0], fit.turns.xy[keep, 1]
    x, y = from_sweep(u, v, heading)
    roles: list[WaypointRole] = ["turn"] * total
    lines: list[int | None] = [None] * total
    line_of = fit.index.tolist()
    starts = block.tolist()
    for k in range(n):
        roles[starts[k]] = "line_start"
        roles[starts[k] + 1] = "line_end"
        lines[starts[k]] = lines[starts[k] + 1] = line_of[k]
    skip = 1 if joined else 0
    if joined:
        route.roles[-1] = "line_start"
        route.lines[-1] = line_of[0]
    base = len(route.x) - skip
    if not joined and base and route.roles[-1] == "start":
        route.segments.append(("transit", None, base - 1, base))
    for k in range(n):
        first = base + starts[k]
        route.segments.append(("line", line_of[k], first, first + 1))
        if k + 1 < n:
            route.segments.append(("turn", None, first + 1, base + starts[k + 1]))
    route.x.extend(x[skip:].tolist())
    route.y.extend(y[skip:].tolist())
    route.roles.extend(roles[skip:])
    route.lines.extend(lines[skip:])
