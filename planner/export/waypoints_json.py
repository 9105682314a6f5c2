"""Waypoints JSON: the array a tractor controller loads (the paper's waypoint block)."""

from __future__ import annotations

from typing import Any

from planner.types import CoveragePlan


def plan_to_waypoints_json(plan: CoveragePlan) -> dict[str, Any]:
    """Return ``{"waypoints": [{"seq", "lat", "lon", "role", "line"}, …]}`` in driving order."""
    return {
        "waypoints": [
            {"seq": w.seq, "lat": w.lat, "lon": w.lon, "role": w.role, "line": w.line}
            for w in plan.waypoints
        ]
    }
