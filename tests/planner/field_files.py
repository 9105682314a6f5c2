"""Field files written by GDAL (pyogrio) from the shared GeoJSON: what other tools would give us.

None of these files is written by hand or by tillpath's own code: the geometry comes from
``../shared/fields`` and GDAL's drivers (KML, LIBKML, ESRI Shapefile, GPKG) write the files.
"""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pyogrio.raw
import shapely
from pyproj import Transformer
from shapely import Polygon

from tests.conftest import FIELDS_DIR, PAPER_FIELD

#: The paper field and three real fields, one with a hole: (file, feature id or None).
REAL_FIELDS = {
    "paper": (PAPER_FIELD, None),
    "rwanda-3": (FIELDS_DIR / "rwanda_2021.geojson", "rwanda_2021-3"),
    "netherlands-0": (FIELDS_DIR / "netherlands_f2c.geojson", "netherlands_f2c-0"),
    "germany-22-hole": (FIELDS_DIR / "germany_2018_2019.geojson", "germany_2018_2019-22"),
}


def shared_feature(path: Path, feature_id: str | None) -> dict[str, Any]:
    """The Feature of ``path`` with ``id`` ``feature_id`` (or its first Polygon)."""
    collection = json.loads(path.read_text())
    for feature in collection["features"]:
        if feature["geometry"]["type"] != "Polygon":
            continue
        if feature_id is None or feature["properties"].get("id") == feature_id:
            return dict(feature)
    raise KeyError(feature_id)


def shared_polygon(name: str) -> Polygon:
    path, feature_id = REAL_FIELDS[name]
    polygon = shapely.from_geojson(json.dumps(shared_feature(path, feature_id)["geometry"]))
    assert isinstance(polygon, Polygon)
    return polygon


def write_layer(
    path: Path,
    polygons: list[Polygon],
    *,
    driver: str,
    crs: str = "EPSG:4326",
    names: list[str] | None = None,
    layer: str | None = None,
    append: bool = False,
) -> None:
    """Write ``polygons`` (already in ``crs``) with GDAL's ``driver``, a ``name`` column."""
    names = names or [f"field {i}" for i in range(len(polygons))]
    pyogrio.raw.write(
        str(path),
        np.array([shapely.to_wkb(p) for p in polygons], dtype=object),
        [np.array(names, dtype=object)],
        ["name"],
        driver=driver,
        geometry_type="Polygon",
        crs=crs,
        layer=layer,
        append=append,
    )


def kml_bytes(tmp: Path, polygon: Polygon, name: str = "field") -> bytes:
    """A KML as GDAL's KML driver writes it (one Document, Placemark Polygons)."""
    path = tmp / f"{name}.kml"
    write_layer(path, [polygon], driver="KML", names=[name])
    return path.read_bytes()


def kmz_bytes(tmp: Path, polygon: Polygon, name: str = "field") -> bytes:
    """A KMZ as GDAL's LIBKML driver writes it (doc.kml linking layers/*.kml)."""
    path = tmp / f"{name}.kmz"
    write_layer(path, [polygon], driver="LIBKML", names=[name])
    return path.read_bytes()


def google_earth_kmz_bytes(tmp: Path, polygon: Polygon, name: str = "field") -> bytes:
    """A KMZ as Google Earth saves one: a zip holding ``doc.kml``."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("doc.kml", kml_bytes(tmp, polygon, name))
    return buffer.getvalue()


def utm_epsg(polygon: Polygon) -> int:
    lon, lat = polygon.centroid.x, polygon.centroid.y
    return (32600 if lat >= 0 else 32700) + int((lon + 180) // 6) + 1


def zipped_utm_shapefile_bytes(tmp: Path, polygon: Polygon, name: str = "field") -> bytes:
    """A zipped Shapefile in the field's UTM zone (with its .prj), inside a folder."""
    epsg = utm_epsg(polygon)
    to_utm = Transformer.from_crs("EPSG:4326", f"EPSG:{epsg}", always_xy=True)
    polygon_utm = shapely.transform(polygon, to_utm.transform, interleaved=False)  # type: ignore[arg-type]
    folder = tmp / f"{name}_shp"
    folder.mkdir(exist_ok=True)
    write_layer(folder / f"{name}.shp", [polygon_utm], driver="ESRI Shapefile", crs=f"EPSG:{epsg}")
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for part in sorted(folder.iterdir()):
            archive.write(part, f"export/{name}/{part.name}")
    return buffer.getvalue()


def gpkg_bytes(tmp: Path, polygons: list[Polygon], names: list[str], *, crs: str) -> bytes:
    """A GeoPackage of several fields in ``crs`` (reprojected from WGS84 here)."""
    to_crs = Transformer.from_crs("EPSG:4326", crs, always_xy=True)
    projected = [shapely.transform(p, to_crs.transform, interleaved=False) for p in polygons]  # type: ignore[arg-type]
    path = tmp / "fields.gpkg"
    write_layer(path, projected, driver="GPKG", crs=crs, names=names, layer="parcels")
    return path.read_bytes()
