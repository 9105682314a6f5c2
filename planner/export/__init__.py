"""Pure writers (and a reader) for plans: text or dicts out, never files.

``plan_to_geojson`` and ``plan_from_geojson`` round-trip; ``plan_to_gpx`` writes GPX 1.1 with
gpxpy; ``plan_to_csv`` and ``plan_to_waypoints_json`` write what a tractor controller loads.
"""

from planner.export.csv import plan_to_csv
from planner.export.geojson import plan_from_geojson, plan_to_geojson
from planner.export.gpx import GpxTrack, plan_to_gpx
from planner.export.waypoints_json import plan_to_waypoints_json

__all__ = [
    "GpxTrack",
    "plan_from_geojson",
    "plan_to_csv",
    "plan_to_geojson",
    "plan_to_gpx",
    "plan_to_waypoints_json",
]
