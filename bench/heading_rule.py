"""The heading rule's measure: a searched plan against every 1° fixed heading (R5, issue 9 item 5).

One measure for the test that holds the rule (``tests/planner/test_heading_rule_non_convex.py``)
and the benches that count how often it holds (:mod:`bench.heading_brute_force_non_convex`,
:mod:`bench.heading_brute_force_real`), so that a figure in a note and a test's verdict are
the same sum.

The field is planned once with the heading searched and at every heading of
:data:`GRID_DEG` (``angle_deg``, as a user would). Of it:

- the *coverage shortfall*: the best fixed heading's ``coverage_ratio`` minus the searched
  plan's, minus R5's 0.2 pp slack, floored at 0 [pp] (the rule: 0);
- the *length excess*: the searched plan's ``path_length_m`` over the shortest fixed heading
  within 0.2 pp of the best coverage [%] (the rule: at most :data:`LOSS_PCT`). Where the
  search found a heading between the 1° ones that covers more (the plan's own, or the one it
  reports giving coverage up against), a 1° heading 0.2 pp below that is no candidate; where
  no 1° heading is one, the searched plan is the only candidate (excess 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from shapely import Polygon

from bench.shapes import fixed_heading_figures
from planner import plan_coverage
from planner.angles import COVERAGE_SLACK

#: The 1° grid of fixed headings [deg].
GRID_DEG = np.arange(0.0, 180.0, 1.0)
#: The searched plan may be this much longer than the best fixed heading that keeps the rule [%].
LOSS_PCT = 1.0


@dataclass(frozen=True, slots=True)
class Outcome:
    """One field's searched plan against its brute force.

    Attributes
    ----------
    searched_deg, searched_cover : float
        The searched plan's heading [deg] and coverage ratio.
    best_deg, best_cover : float
        The best-covering fixed heading (the first of equals) and its coverage ratio.
    shortest_deg : float
        The shortest fixed heading that keeps the rule (the searched one if none does).
    shortfall_pp : float
        Coverage shortfall beyond R5's slack [pp], 0 when the rule is kept.
    excess_pct : float
        Length over the shortest heading that keeps the rule [%].
    """

    searched_deg: float
    searched_cover: float
    best_deg: float
    best_cover: float
    shortest_deg: float
    shortfall_pp: float
    excess_pct: float

    @property
    def keeps_rule(self) -> bool:
        """No shortfall and an excess within :data:`LOSS_PCT`."""
        return self.shortfall_pp <= 0.0 and self.excess_pct <= LOSS_PCT

    def describe(self) -> str:
        """One line: the searched heading against the best and the shortest fixed ones."""
        return (
            f"searched {self.searched_deg:6.2f}° {self.searched_cover * 100:.3f} %, "
            f"best {self.best_deg:5.1f}° {self.best_cover * 100:.3f} %, "
            f"shortfall {self.shortfall_pp:.3f} pp, excess {self.excess_pct:+.2f} % "
            f"(vs {self.shortest_deg:.1f}°)"
        )


def fixed_figures(
    field: Polygon, interval_m: float, vehicle: str | None = None, cache: Path | None = None
) -> np.ndarray:
    """Plan ``field`` at every heading of :data:`GRID_DEG`: rows (heading, coverage, length).

    :func:`bench.shapes.fixed_heading_figures` (a heading the planner refuses is left out).
    With ``cache`` (a ``.npy`` file), the rows are read from it if it exists and written to it
    if not: only right while every fixed-heading plan is unchanged.
    """
    if cache is not None and cache.exists():
        return np.asarray(np.load(cache), dtype=float)
    headings, lengths, covers = fixed_heading_figures(
        field, GRID_DEG.tolist(), interval_m=interval_m, vehicle=vehicle
    )
    figures = np.stack([headings, covers, lengths], axis=1)
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        np.save(cache, figures)
    return figures


def compare(
    field: Polygon, interval_m: float, vehicle: str | None = None, cache: Path | None = None
) -> Outcome:
    """Plan ``field`` (WGS84) searched and at every fixed heading of :data:`GRID_DEG`.

    ``cache``: as :func:`fixed_figures`.

    Raises
    ------
    PlannerError
        If the searched plan is refused.
    """
    searched = plan_coverage(field, interval_m=interval_m, vehicle=vehicle).stats
    fixed = fixed_figures(field, interval_m, vehicle, cache)
    heading, cover, length = fixed.T
    best = int(np.argmax(cover))  # the first of equals
    found = searched.coverage_ratio + searched.coverage_given_up_pp / 100.0
    top_cover = max(float(cover[best]), found)
    keeping = np.flatnonzero(cover >= top_cover - COVERAGE_SLACK)
    if len(keeping):
        shortest = int(keeping[np.argmin(length[keeping])])
        shortest_deg, shortest_m = float(heading[shortest]), float(length[shortest])
    else:
        shortest_deg, shortest_m = searched.angle_deg, searched.path_length_m
    shortfall = float(cover[best]) - searched.coverage_ratio - COVERAGE_SLACK
    return Outcome(
        searched_deg=searched.angle_deg,
        searched_cover=searched.coverage_ratio,
        best_deg=float(heading[best]),
        best_cover=float(cover[best]),
        shortest_deg=shortest_deg,
        shortfall_pp=max(shortfall, 0.0) * 100.0,
        excess_pct=(searched.path_length_m / shortest_m - 1.0) * 100.0,
    )
