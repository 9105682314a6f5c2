"""Pure writers (and a reader) for plans: text or dicts out, never files.

``plan_to_geojson`` and ``plan_from_geojson`` round-trip; ``plan_to_gpx`` writes GPX 1.1 with
gpxpy; ``plan_to_csv`` and ``plan_to_waypoints_json`` write what a tractor controller loads;
``plan_to_kml`` writes KML 2.2 for Google Earth (simplekml), ``plan_to_qgc_wpl`` and
``plan_to_qgc_plan`` the missions an autopilot loads, and ``plan_to_gpkg`` a GeoPackage with a
layer per kind (GDAL).
"""

from planner.export.csv import plan_to_csv
from planner.export.geojson import plan_from_geojson, plan_to_geojson
from planner.export.gpkg import plan_to_gpkg
from planner.export.gpx import GpxTrack, plan_to_gpx
from planner.export.kml import plan_to_kml, tracks_to_kml
from planner.export.mission import plan_to_qgc_plan, plan_to_qgc_wpl
from planner.export.waypoints_json import plan_to_waypoints_json

__all__ = [
    "GpxTrack",
    "plan_from_geojson",
    "plan_to_csv",
    "plan_to_geojson",
    "plan_to_gpkg",
    "plan_to_gpx",
    "plan_to_kml",
    "plan_to_qgc_plan",
    "plan_to_qgc_wpl",
    "plan_to_waypoints_json",
    "tracks_to_kml",
]
