"""GeoPackage for QGIS and ogr2ogr: one layer per kind of feature, written by GDAL (pyogrio).

Layers (all WGS84, EPSG:4326): ``field`` (Polygon, holes included, with the plan's figures as
attributes), ``lines`` (``index``), ``headland`` (``index``), ``turns``, ``transit``,
``path`` (the whole route as one LineString) and ``waypoints`` (Point: ``seq``, ``role``,
``line``). A layer of a kind the plan lacks is written empty, so every file has the same
layers. One geometry type per layer: each converts to a Shapefile with ``ogr2ogr``.
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path
from typing import Any, Final

import numpy as np
import pyogrio
import pyogrio.raw
import shapely
from shapely import LineString, Point

from planner.types import CoveragePlan

#: Layer name per segment kind.
SEGMENT_LAYERS: Final = {
    "line": "lines",
    "headland": "headland",
    "turn": "turns",
    "transit": "transit",
}
#: Every layer of the file, in order.
GPKG_LAYERS: Final = ("field", "lines", "headland", "turns", "transit", "path", "waypoints")


def plan_to_gpkg(plan: CoveragePlan, *, name: str) -> bytes:
    """Return the plan as a GeoPackage file's bytes.

    Parameters
    ----------
    plan : CoveragePlan
    name : str
        Stored in the ``field`` layer's ``name`` attribute.

    Notes
    -----
    GDAL writes a GeoPackage (an SQLite database) to a file, and several layers cannot be
    written to memory through pyogrio; so the file is built in a private temporary directory
    that is removed before this returns. Nothing else is touched.
    """
    _no_fsync_for_scratch_files()
    stats = plan.stats.as_dict()
    del stats["planning_ms"]
    # A column holds one value: the vehicle (a dict of figures) goes as its preset and JSON.
    vehicle = stats.pop("vehicle", None)
    if isinstance(vehicle, dict):
        stats["vehicle"] = str(vehicle.get("preset"))
        stats["vehicle_json"] = json.dumps(vehicle, sort_keys=True)
    field_attrs: dict[str, Any] = {"name": name, "interval_m": plan.interval_m, **stats}
    with tempfile.TemporaryDirectory(prefix="tillpath-gpkg-") as scratch:
        path = str(Path(scratch) / "plan.gpkg")
        _write(
            path, "field", "Polygon", [plan.field_lonlat], {k: [v] for k, v in field_attrs.items()}
        )
        for kind, layer in SEGMENT_LAYERS.items():
            segments = [s for s in plan.segments if s.kind == kind]
            attrs: dict[str, list[Any]] = {}
            if kind in ("line", "headland"):
                attrs["index"] = [s.index for s in segments]
            _write(path, layer, "LineString", [LineString(s.lonlat) for s in segments], attrs)
        route = (
            [LineString([(w.lon, w.lat) for w in plan.waypoints])]
            if len(plan.waypoints) >= 2
            else []
        )
        _write(
            path, "path", "LineString", route, {"length_m": [plan.stats.path_length_m] * len(route)}
        )
        _write(
            path,
            "waypoints",
            "Point",
            [Point(w.lon, w.lat) for w in plan.waypoints],
            {
                "seq": [w.seq for w in plan.waypoints],
                "role": [w.role for w in plan.waypoints],
                "line": [w.line for w in plan.waypoints],
            },
        )
        return Path(path).read_bytes()


@lru_cache(maxsize=1)
def _no_fsync_for_scratch_files() -> None:
    """Let GDAL skip SQLite's fsync: the file is scratch, and fsync made it ~8x slower.

    A process-wide GDAL setting; tillpath writes no other SQLite file through GDAL (the app's
    database goes through SQLAlchemy, not GDAL).
    """
    pyogrio.set_gdal_config_options({"OGR_SQLITE_SYNCHRONOUS": "OFF"})


def _write(
    path: str,
    layer: str,
    geometry_type: str,
    geometries: Sequence[Any],
    attrs: dict[str, list[Any]],
) -> None:
    names = list(attrs)
    columns = []
    masks = []
    for column_name in names:
        values = attrs[column_name]
        array, mask = _column(values)
        columns.append(array)
        masks.append(mask)
    pyogrio.raw.write(
        path,
        np.array([shapely.to_wkb(g) for g in geometries], dtype=object),
        columns,
        names,
        field_mask=masks if names else None,
        layer=layer,
        driver="GPKG",
        geometry_type=geometry_type,
        crs="EPSG:4326",
        append=Path(path).exists(),
    )


def _column(values: list[Any]) -> tuple[Any, Any]:
    present = [v for v in values if v is not None]
    mask = np.array([v is None for v in values], dtype=bool)
    if present and all(isinstance(v, str) for v in present):
        return np.array([v if v is not None else "" for v in values], dtype=object), mask
    if all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in present):
        return np.array([0 if v is None else int(v) for v in values], dtype=np.int64), mask
    return np.array([np.nan if v is None else float(v) for v in values], dtype=np.float64), mask
