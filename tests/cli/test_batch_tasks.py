"""``plan-batch``'s task, in process: the path it writes is the plan's route, point for point."""

from __future__ import annotations

import json
from pathlib import Path

import shapely

from app.cli.batch_read import FieldRecord
from app.cli.batch_tasks import plan_record
from planner import parse_field_geojson, plan_coverage

PAPER = Path(__file__).resolve().parents[2].parent / "shared" / "fields" / "paper_ketewel.geojson"


def test_the_written_path_is_the_plans_waypoints_in_order() -> None:
    field = parse_field_geojson(json.loads(PAPER.read_text())).field_lonlat
    record = FieldRecord(
        index=0, ident="paper", name=None, wkb=shapely.to_wkb(field), interval_m=None
    )
    result = plan_record(record, {"interval_m": 1.5, "vehicle": "small_tractor"})
    assert result.error is None and result.path_wkb is not None
    plan = plan_coverage(field, interval_m=1.5, vehicle="small_tractor")
    expected = [(w.lon, w.lat) for w in plan.waypoints]
    assert shapely.from_wkb(result.path_wkb).coords[:] == expected
