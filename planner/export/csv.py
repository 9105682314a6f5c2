"""CSV waypoints: header ``seq,lat,lon,role,line`` (``line`` empty off the tillage lines)."""

from __future__ import annotations

import csv
import io

from planner.types import CoveragePlan

HEADER = ("seq", "lat", "lon", "role", "line")


def plan_to_csv(plan: CoveragePlan) -> str:
    """Return the plan's waypoints as CSV text, one row per waypoint in driving order."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(HEADER)
    for w in plan.waypoints:
        writer.writerow((w.seq, repr(w.lat), repr(w.lon), w.role, "" if w.line is None else w.line))
    return out.getvalue()
