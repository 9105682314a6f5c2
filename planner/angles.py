"""The line-angle search (R5): which headings to try, and which (heading, variant) wins."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.errors import PlanTooLargeError
from planner.ordering import VariantLengths
from planner.types import Objective

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Step of the fine sweep of headings [deg], on top of every edge direction.
SWEEP_STEP_DEG = 1.0
#: At most this many edge directions are tried, the longest edges' first: a boundary traced
#: from GPS has many short edges whose directions are noise.
MAX_EDGE_HEADINGS = 180
#: A plan with more tillage lines than this is refused (product.md §3).
MAX_LINES = 20_000
#: Path lengths closer than this count as equal, so ties break the same way every time [m].
_TIE_M = 1e-6


def candidate_headings(ring_xy: FloatArray, fixed_deg: float | None = None) -> FloatArray:
    """Headings to try: every edge direction of the ring plus a 1° sweep, in [0, 180).

    A ring of more than :data:`MAX_EDGE_HEADINGS` edges contributes its longest edges'
    directions only.

    Parameters
    ----------
    ring_xy : ndarray, shape (m, 2)
        The field's exterior, local [m], not closed.
    fixed_deg : float or None
        If given, only this heading.

    Returns
    -------
    ndarray
        Sorted, unique headings [deg].

    Examples
    --------
    >>> ring = np.array([[0.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    >>> h = candidate_headings(ring)
    >>> len(h), 45.0 in h, 0.0 in h
    (180, True, True)
    """
    if fixed_deg is not None:
        return np.array([float(fixed_deg)])
    dx = np.roll(ring_xy[:, 0], -1) - ring_xy[:, 0]
    dy = np.roll(ring_xy[:, 1], -1) - ring_xy[:, 1]
    length = np.hypot(dx, dy)
    longest = np.argsort(-length, kind="stable")[:MAX_EDGE_HEADINGS]
    longest = longest[length[longest] > 0]
    edges = np.degrees(np.arctan2(dx[longest], dy[longest])) % 180.0
    sweep = np.arange(0.0, 180.0, SWEEP_STEP_DEG)
    headings = np.concatenate([sweep, np.round(edges, 9) % 180.0])
    return np.unique(headings)


def select_plan(
    lengths: VariantLengths,
    line_counts_per_heading: IntArray,
    objective: Objective,
    *,
    interval_m: float | None = None,
) -> tuple[int, int]:
    """Pick the (heading index, variant index) the objective prefers.

    ``shortest_path`` minimises the whole path; ``fewest_lines`` minimises the line count,
    then the path. Ties go to the first heading and variant, so the choice is deterministic.
    Headings that need more than :data:`MAX_LINES` lines are never chosen.

    Raises
    ------
    PlanTooLargeError
        If every heading needs more than :data:`MAX_LINES` lines.

    Examples
    --------
    >>> from planner.ordering import VariantLengths
    >>> lengths = VariantLengths(np.array([10.0, 9.0]), np.zeros((2, 4)), np.array(
    ...     [[1.0, 2.0, 3.0, 4.0], [5.0, 5.0, 5.0, 0.5]]))
    >>> select_plan(lengths, np.array([3, 4]), "shortest_path")
    (1, 3)
    >>> select_plan(lengths, np.array([3, 4]), "fewest_lines")
    (0, 0)
    """
    counts = line_counts_per_heading
    if counts.min() > MAX_LINES:
        at = f"at {interval_m:g} m " if interval_m else ""
        raise PlanTooLargeError(
            "interval_m",
            f"{at}the field needs at least {int(counts.min()):,} tillage lines; tillpath "
            f"plans at most {MAX_LINES:,}: choose a wider interval or a smaller field",
        )
    total = np.round(lengths.total / _TIE_M) * _TIE_M
    total = np.where((counts <= MAX_LINES)[:, None], total, np.inf)
    if objective == "fewest_lines":
        fewest = line_counts_per_heading == line_counts_per_heading.min()
        total = np.where(fewest[:, None], total, np.inf)
    flat = int(np.argmin(total))
    return flat // 4, flat % 4
