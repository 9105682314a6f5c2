"""plan_coverage(): chains the planner stages (being written)."""

from __future__ import annotations

from typing import Any

from planner.types import CoveragePlan


def plan_coverage(*args: Any, **kwargs: Any) -> CoveragePlan:
    """Plan a coverage path (the implementation lands with the planner core)."""
    raise NotImplementedError
