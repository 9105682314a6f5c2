"""The headings R5 fits on fields planned in cells (``planner.fitted_cells``)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from planner.fitted_cells import (
    PROBE_OFFSETS_DEG,
    FittedCells,
    _probed,
)

#: R5's slack in these made-up figures [m²].
SLACK_M2 = 10.0


def _fitted(covered_m2: float, length_m: float) -> FittedCells:
    return FittedCells(None, {}, covered_m2, length_m, 10, covered_m2)  # type: ignore[arg-type]


def _probe_case(
    neighbours: dict[float, FittedCells],
    fitted: dict[int, FittedCells],
    estimated_m2: list[float],
    objective: str = "shortest_path",
) -> tuple[list[FittedCells], list[tuple[float, float]]]:
    """Run :func:`_probed` on headings 10°, 20°, 30°; return its answer and the probes asked."""
    covers = [SimpleNamespace(heading_deg=h) for h in (10.0, 20.0, 30.0)]
    asked: list[tuple[float, float]] = []

    def probe(heading_deg: float, neighbours_deg: list[float]) -> list[float]:
        asked.extend((heading_deg, round(h, 6)) for h in neighbours_deg)
        return [round(h, 6) for h in neighbours_deg]

    found = _probed(
        fitted, covers, estimated_m2, max(estimated_m2), SLACK_M2, probe,  # type: ignore[arg-type]
        lambda plan: neighbours[plan], objective,  # type: ignore[arg-type,index]
    )  # fmt: skip
    return found, asked


def test_a_heading_that_fitting_cost_its_cover_has_its_neighbours_fitted() -> None:
    # 20° was estimated as good as the best, fitted 3 slacks below it, and is 5 % shorter
    # than the shortest heading that keeps the rule (10°).
    fitted = {0: _fitted(1000.0, 100.0), 1: _fitted(970.0, 95.0), 2: _fitted(995.0, 101.0)}
    keeps_and_saves = _fitted(995.0, 97.0)  # within the slack, 3 % shorter
    saves_too_little = _fitted(999.0, 99.5)  # within the slack, 0.5 % shorter
    neighbours = {20.0 + PROBE_OFFSETS_DEG[0]: keeps_and_saves}
    neighbours[20.0 + PROBE_OFFSETS_DEG[1]] = saves_too_little
    found, asked = _probe_case(neighbours, fitted, [1000.0, 999.0, 990.0])
    assert asked == [(20.0, 20.0 + offset) for offset in PROBE_OFFSETS_DEG]
    assert found == [keeps_and_saves]


def test_a_neighbour_that_covers_clearly_more_is_a_candidate_however_long() -> None:
    fitted = {0: _fitted(1000.0, 100.0), 1: _fitted(970.0, 95.0)}
    covers_more = _fitted(1000.0 + 2 * SLACK_M2, 150.0)
    neighbours = {20.0 + offset: covers_more for offset in PROBE_OFFSETS_DEG}
    found, _ = _probe_case(neighbours, fitted, [1000.0, 1000.0, 0.0])
    assert found == [covers_more, covers_more]


@pytest.mark.parametrize(
    ("fitted", "estimated_m2", "objective"),
    [
        # Fitting cost 20° its cover, but it was not estimated within the slack either.
        ({0: _fitted(1000.0, 100.0), 1: _fitted(970.0, 95.0)}, [1000.0, 980.0, 0.0], None),
        # ... it would not save 1 % over the shortest heading that keeps the rule.
        ({0: _fitted(1000.0, 100.0), 1: _fitted(970.0, 99.5)}, [1000.0, 1000.0, 0.0], None),
        # ... fitting cost it no more than the slack.
        ({0: _fitted(1000.0, 100.0), 1: _fitted(991.0, 95.0)}, [1000.0, 1000.0, 0.0], None),
        # ... fewer lines are the objective: a neighbour drives as many.
        (
            {0: _fitted(1000.0, 100.0), 1: _fitted(970.0, 95.0)},
            [1000.0, 1000.0, 0.0],
            "fewest_lines",
        ),
    ],
)
def test_no_neighbour_is_probed_unless_fitting_cost_a_shorter_heading_its_cover(
    fitted: dict[int, FittedCells], estimated_m2: list[float], objective: str | None
) -> None:
    found, asked = _probe_case({}, fitted, estimated_m2, objective or "shortest_path")
    assert (found, asked) == ([], [])
