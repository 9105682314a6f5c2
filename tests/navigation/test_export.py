"""GeoJSON and GPX output of a simulated run; the plot renders."""

from __future__ import annotations

from pathlib import Path

import gpxpy
import numpy as np
from lxml import etree

from navigation import SimulationConfig, simulate
from navigation.export import simulation_to_geojson, simulation_to_gpx
from navigation.plot import plot_simulation


def test_geojson_has_the_three_tracks_and_the_metrics(paper_plan) -> None:  # type: ignore[no-untyped-def]
    log = simulate(paper_plan, SimulationConfig(), np.random.default_rng(0))
    doc = simulation_to_geojson(log)
    assert doc["type"] == "FeatureCollection"
    assert [f["properties"]["source"] for f in doc["features"]] == ["true", "estimated", "gps"]
    true = doc["features"][0]
    assert true["geometry"]["type"] == "LineString"
    # Thinned to one point a second, last point kept.
    assert len(true["geometry"]["coordinates"]) == len(true["properties"]["time_s"])
    assert abs(len(true["properties"]["time_s"]) - (log.time_s[-1] + 1)) <= 1
    assert true["properties"]["time_s"][-1] == round(float(log.time_s[-1]), 3)
    assert doc["properties"]["metrics"]["completed"] is True
    lon, lat = true["geometry"]["coordinates"][0]
    assert (
        abs(lon - paper_plan.waypoints[0].lon) < 1e-4
        and abs(lat - paper_plan.waypoints[0].lat) < 1e-4
    )


def test_gpx_has_route_and_timed_tracks(paper_plan) -> None:  # type: ignore[no-untyped-def]
    log = simulate(paper_plan, SimulationConfig(gps="rtk"), np.random.default_rng(0))
    doc = gpxpy.parse(simulation_to_gpx(log, name="paper"))
    assert len(doc.routes[0].points) == len(paper_plan.waypoints)
    true = doc.tracks[0].segments[0].points
    assert (true[-1].time - true[0].time).total_seconds() == round(float(log.time_s[-1]), 6)


GPX_XSD = Path(__file__).resolve().parents[3] / "shared" / "schemas" / "gpx-1.1.xsd"


def test_gpx_validates_against_the_gpx_1_1_schema(paper_plan) -> None:  # type: ignore[no-untyped-def]
    log = simulate(paper_plan, SimulationConfig(), np.random.default_rng(2))
    schema = etree.XMLSchema(etree.parse(str(GPX_XSD)))
    document = etree.fromstring(simulation_to_gpx(log, name="paper").encode())
    assert schema.validate(document), schema.error_log


def test_plot_is_a_png(paper_plan) -> None:  # type: ignore[no-untyped-def]
    log = simulate(paper_plan, SimulationConfig(), np.random.default_rng(0))
    png = plot_simulation(log)
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
