"""A planning budget per request: no field can hold a worker (product.md §12, "Hardening").

Plain fields (the real ones have at most a few hundred vertices) are planned in the request's
thread, as fast as ever. A field past :data:`INLINE_MAX_VERTICES` vertices or
:data:`INLINE_MAX_HOLES` holes, or past :data:`INLINE_MAX_AREA_HA` in a pattern whose time
grows with the field's area (:data:`BUDGETED_PATTERNS`), is planned in a child process
(multiprocessing's ``forkserver``, which forks from a clean process that has the planner and
its kernels loaded) with a deadline: a plan that would take longer than
``Settings.planning_budget_s`` is stopped and answered 422, naming the limit. The command line
(``tillpath plan``) has no budget.
"""

from __future__ import annotations

import functools
import multiprocessing
import multiprocessing.connection
import threading
import time
from multiprocessing.context import ForkServerContext
from typing import Any, Final

import shapely
from pyproj import Geod
from shapely import Polygon

import planner
from app.forkserver import preloaded_context
from planner import CoveragePlan, PlannerError

#: Fields up to this many vertices (exterior and holes) are planned in the request's thread.
INLINE_MAX_VERTICES: Final = 400
#: Fields with up to this many holes are planned in the request's thread.
INLINE_MAX_HOLES: Final = 10
#: Patterns whose time grows with the field's area (a spiral's rounds), not its vertices:
#: 9 s for a real 130 ha field of 76 vertices, at most 0.24 s for the real fields up to
#: 10 ha (``python -m bench.spiral_times``: every ninth real field, two vehicles). Past this
#: area they are planned with the deadline.
BUDGETED_PATTERNS: Final = frozenset({"spiral"})
#: ... fields up to this area [ha] are planned in the request's thread in every pattern.
INLINE_MAX_AREA_HA: Final = 10.0

_WGS84: Final = Geod(ellps="WGS84")


@functools.cache
def _context() -> ForkServerContext:
    """Return the fork server's context, made on first use.

    Its server loads the planner's compiled kernels, so that no child pays for them out of its
    budget. Made here rather than when the web app is imported: it imports Dask for its
    settings (about 0.2 s).
    """
    return preloaded_context()


def _nothing() -> None:
    """Do nothing (in a child: starting one waits until the fork server is ready)."""


def _warm_up() -> None:
    from planner.warm_up import warm_up as warm_up_kernels

    # The fork server first, and this process's kernels once it is ready: with a cold numba
    # cache the fork server compiles them (about 9 s of CPU, once per install) and this
    # process then loads them from the cache instead of compiling them a second time.
    child = _context().Process(target=_nothing, daemon=True)
    child.start()
    child.join()
    child.close()
    warm_up_kernels()


def warm_up() -> threading.Thread:
    """Start the fork server and load the planner's kernels, in a background thread.

    Join the thread before serving, so that no request waits for them: the fork server
    imports the planner and its kernels in a fresh interpreter (about 1.5 s), which a large
    field's request would otherwise spend out of its budget, and the kernels take about
    0.35 s to load in this process (:mod:`planner.kernels`; seconds to compile where their
    cache is cold, as after a fresh install).

    Returns
    -------
    threading.Thread
        The started thread.
    """
    thread = threading.Thread(target=_warm_up, name="planner-warm-up", daemon=True)
    thread.start()
    return thread


class PlanningBudgetError(PlannerError):
    """Planning the field would take longer than the budget of one request.

    Parameters
    ----------
    budget_s : float
        The budget [s].
    vertices, holes : int
        The field's size, named in the message.
    """

    def __init__(
        self,
        budget_s: float,
        vertices: int,
        holes: int,
        *,
        pattern: str = "",
        area_ha: float | None = None,
    ) -> None:
        if area_ha is not None:  # budgeted for its area: the boundary is not the cause
            message = (
                f"planning this field of {area_ha:,.1f} ha as a {pattern} takes longer than "
                f"the limit of {budget_s:g} s per request; plan it with another pattern, "
                "or with `tillpath plan`"
            )
        else:
            message = (
                f"planning this field ({vertices:,} vertices, {holes} holes) takes longer "
                f"than the limit of {budget_s:g} s per request; simplify the boundary, or "
                "plan it with `tillpath plan`"
            )
        super().__init__("field", message)


def field_size(field: Polygon) -> tuple[int, int]:
    """Return ``(vertices, holes)`` of a polygon (closing vertices not counted)."""
    rings = [field.exterior, *field.interiors]
    return sum(max(len(r.coords) - 1, 0) for r in rings), len(field.interiors)


def _worker(conn: multiprocessing.connection.Connection, field: Polygon, options: Any) -> None:
    try:
        result: tuple[str, Any] = ("ok", planner.plan_coverage(field, **options))
    except PlannerError as exc:
        result = ("refused", (type(exc).__name__, str(exc)))
    except Exception as exc:  # noqa: BLE001 - reported to the parent, which re-raises
        result = ("failed", f"{type(exc).__name__}: {exc}")
    conn.send(result)
    conn.close()


def area_ha(field_lonlat: Polygon) -> float:
    """Return a WGS84 polygon's geodesic area [ha], holes taken off however they wind.

    pyproj sums the rings' signed areas: a hole wound as the exterior would be added.
    """
    oriented = shapely.orient_polygons(field_lonlat)
    return abs(float(_WGS84.geometry_area_perimeter(oriented)[0])) / 1e4


class ChildPlannerError(PlannerError):
    """A planner error from the child process, with the child's message."""

    def __init__(self, message: str) -> None:
        ValueError.__init__(self, message)


def plan_coverage(field_lonlat: Polygon, *, budget_s: float, **options: Any) -> CoveragePlan:
    """Plan like :func:`planner.plan_coverage`, within ``budget_s`` for large fields.

    Parameters
    ----------
    field_lonlat : Polygon
        The field, WGS84.
    budget_s : float
        Longest a large field may take [s].
    **options
        Passed to :func:`planner.plan_coverage`.

    Raises
    ------
    PlanningBudgetError
        If a large field is not planned within the budget.
    PlannerError
        What the planner refuses, with its message.
    """
    vertices, holes = field_size(field_lonlat)
    pattern = str(options.get("pattern") or "")
    large = vertices > INLINE_MAX_VERTICES or holes > INLINE_MAX_HOLES
    area = area_ha(field_lonlat) if pattern in BUDGETED_PATTERNS else 0.0
    if not large and area <= INLINE_MAX_AREA_HA:
        return planner.plan_coverage(field_lonlat, **options)
    deadline = time.monotonic() + budget_s  # the process's start counts against the budget
    receiver, sender = _context().Pipe(duplex=False)
    process = _context().Process(target=_worker, args=(sender, field_lonlat, options), daemon=True)
    process.start()
    sender.close()
    try:
        if not receiver.poll(max(0.0, deadline - time.monotonic())):
            raise PlanningBudgetError(
                budget_s, vertices, holes, pattern=pattern, area_ha=None if large else area
            )
        kind, value = receiver.recv()
    except EOFError:
        raise RuntimeError("the planning process ended without an answer") from None
    finally:
        receiver.close()
        if process.is_alive():
            process.kill()
        process.join()
        process.close()
    if kind == "ok":
        plan: CoveragePlan = value
        return plan
    if kind == "refused":
        raise ChildPlannerError(value[1])
    raise RuntimeError(f"planning failed: {value}")
