"""Read the features of a vector file with GDAL, through pyogrio, from bytes in memory.

GDAL does the parsing (KML through libkml, Shapefile, GeoPackage); this module only turns
pyogrio's raw arrays (WKB geometries, attribute columns) into shapely geometries in WGS84
with their properties, reprojected from the CRS the layer declares.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyogrio
import pyogrio.errors
import pyogrio.raw
import shapely
from shapely.geometry.base import BaseGeometry

from planner.errors import InvalidFieldError, UnreadableFileError
from planner.projection import is_lonlat_crs, reproject_to_lonlat


@dataclass(frozen=True, slots=True)
class OgrFeature:
    """One feature of a layer.

    Attributes
    ----------
    layer : str
    fid : int
        GDAL's feature id.
    geometry_lonlat : BaseGeometry
        WGS84 ``(lon, lat)``, 2-D.
    properties : dict
        Attribute columns by name (NaN and empty strings as None).
    """

    layer: str
    fid: int
    geometry_lonlat: BaseGeometry
    properties: dict[str, Any]


def read_ogr_features(data: bytes, *, filename: str, what: str) -> Iterator[OgrFeature]:
    """Yield every feature with a geometry of every layer of the vector file ``data``.

    Parameters
    ----------
    data : bytes
        A file GDAL can open from memory (KML, GeoPackage, a zip of one Shapefile).
    filename : str
        Named in errors.
    what : str
        The format, named in errors (``KML``, ``GeoPackage``, ``Shapefile``).

    Raises
    ------
    UnreadableFileError
        If GDAL cannot open or read the file, or a layer has no CRS (a Shapefile without its
        ``.prj``).
    """
    try:
        with _quiet_gdal():
            layers = pyogrio.list_layers(data)
    except (pyogrio.errors.DataSourceError, pyogrio.errors.DataLayerError, OSError) as exc:
        raise UnreadableFileError(filename, f"GDAL cannot read it as {what} ({exc})") from None
    for index, (layer_name, _geometry_type) in enumerate(layers):
        # By index: an in-memory KML's layer is named after a temporary file name that
        # changes from one call to the next.
        layer = str(layer_name) if not str(layer_name).startswith("pyogrio_") else f"{index + 1}"
        try:
            with _quiet_gdal():
                meta, fids, geometries, columns = pyogrio.raw.read(
                    data, layer=index, force_2d=True, return_fids=True, datetime_as_string=True
                )
        except (pyogrio.errors.DataSourceError, pyogrio.errors.DataLayerError) as exc:
            raise UnreadableFileError(
                filename, f"layer {layer!r} cannot be read as {what} ({exc})"
            ) from None
        if geometries is None or len(geometries) == 0:
            continue
        crs = meta.get("crs")
        if crs is None and what == "Shapefile":
            raise UnreadableFileError(
                filename,
                f"layer {layer!r} has no .prj file, so its coordinate system is unknown; "
                "zip the .prj with the .shp, .shx and .dbf",
            )
        names = [str(n) for n in meta["fields"]]
        for row, wkb in enumerate(geometries):
            if wkb is None:
                continue
            try:
                geometry = shapely.from_wkb(wkb)
            except shapely.errors.GEOSException as exc:
                raise UnreadableFileError(
                    filename,
                    f"layer {layer!r} feature {row} has a geometry GEOS cannot read ({exc})",
                ) from None
            if geometry.is_empty:
                continue
            if not is_lonlat_crs(crs):
                try:
                    geometry = reproject_to_lonlat(geometry, str(crs))
                except InvalidFieldError as exc:
                    raise UnreadableFileError(filename, f"layer {layer!r}: {exc}") from None
            properties = {
                name: _plain(column[row]) for name, column in zip(names, columns, strict=True)
            }
            yield OgrFeature(
                layer=layer,
                fid=int(fids[row]) if fids is not None else row,
                geometry_lonlat=geometry,
                properties=properties,
            )


@contextmanager
def _quiet_gdal() -> Iterator[None]:
    """Silence GDAL's RuntimeWarning about in-memory names (a GeoPackage has no ``.gpkg``)."""
    with warnings.catch_warnings():
        warnings.filterwarnings(
            "ignore", message=".*non conformant file extension", category=RuntimeWarning
        )
        yield


def _plain(value: Any) -> Any:
    if value is None:
        return None
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    if isinstance(value, bytes):
        return None
    if isinstance(value, str) and not value.strip():
        return None
    return value
