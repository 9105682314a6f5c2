"""Read a field file of any import format into fields: ``bytes, filename -> list[FieldSpec]``.

The page (through the API), the API and the CLI all call :func:`read_fields`, so a file one of
them accepts, the others accept too (style.md §7). Formats (product.md §4):

- **GeoJSON** (RFC 7946, or older GeoJSON declaring a ``crs``): read by
  :func:`planner.fields.parse_fields_geojson`; a legacy ``crs`` other than WGS84 goes through
  GDAL, which knows it.
- **KML** and **KMZ** (Google Earth): GDAL's libkml driver. A KMZ is unzipped (size-checked)
  and its ``doc.kml`` (else its first ``.kml``) read. Point placemarks named ``start`` or
  ``finish`` are the start and finish.
- **Zipped Shapefile**: every ``.shp`` in the zip with its ``.shx``, ``.dbf`` and ``.prj``,
  reprojected from the ``.prj``'s CRS.
- **GeoPackage**: every layer, reprojected from each layer's SRS.

A field is a Polygon; a MultiPolygon of several parts is several fields (``id.1``, ``id.2`` …).
Points whose ``role`` (or KML name) is ``start``/``finish`` apply to every field of the file.
Every archive is size-checked before it is unpacked and every XML document parsed without
entities first (:mod:`planner.io.safety`); every refusal names the file and the problem.
"""

from __future__ import annotations

import io
import json
import zipfile
from collections.abc import Iterable, Mapping
from pathlib import PurePosixPath
from typing import Any, Final

from shapely import MultiPolygon, Point, Polygon

from planner.errors import FieldChoiceError, InvalidFieldError, PlannerError, UnreadableFileError
from planner.fields import FieldSpec, parse_fields_geojson
from planner.io.ogr import OgrFeature, read_ogr_features
from planner.io.safety import DEFAULT_LIMITS, ZIP_MAGIC, ArchiveLimits, check_xml, unzip_checked
from planner.projection import geodesic_area_m2, is_lonlat_crs

#: Formats :func:`read_fields` reads, as :func:`detect_field_format` names them.
FIELD_FORMATS: Final = ("geojson", "kml", "kmz", "shapefile", "gpkg")
#: File name endings the page's file picker offers.
FIELD_FILE_SUFFIXES: Final = (".geojson", ".json", ".kml", ".kmz", ".zip", ".gpkg")

_SQLITE_MAGIC: Final = b"SQLite format 3\x00"
_EXPECTED: Final = "GeoJSON, KML, KMZ, a zipped Shapefile or a GeoPackage"
_SHAPEFILE_PARTS: Final = (".shp", ".shx", ".dbf", ".prj", ".cpg")
_NAME_KEYS: Final = ("name", "Name", "NAME")
_ID_KEYS: Final = ("id", "ID", "Id", "fid", "FID")


def detect_field_format(data: bytes, *, filename: str) -> str:
    """Tell a field file's format from its first bytes (and a zip's members).

    Parameters
    ----------
    data : bytes
    filename : str
        Named in errors; its ending is not trusted.

    Returns
    -------
    str
        One of :data:`FIELD_FORMATS`; a zip is ``kmz`` or ``shapefile`` only after
        :func:`read_fields` has looked inside, so here it is ``zip``.

    Raises
    ------
    UnreadableFileError
        If the file is empty, binary of another kind, or text that is neither JSON nor XML.

    Examples
    --------
    >>> detect_field_format(b'{"type": "Polygon"}', filename="f.geojson")
    'geojson'
    >>> png = bytes([0x89, 0x50, 0x4E, 0x47, 0, 0])
    >>> detect_field_format(png, filename="photo.png")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    planner.errors.UnreadableFileError: photo.png: is binary data tillpath cannot read; ...
    """
    if not data.strip():
        raise UnreadableFileError(filename, f"is empty; expected {_EXPECTED}")
    if data.startswith(ZIP_MAGIC):
        return "zip"
    if data.startswith(_SQLITE_MAGIC):
        return "gpkg"
    head = data[:4096]
    if head.startswith(b"\xef\xbb\xbf"):
        head = head[3:]
    head = head.lstrip(b" \t\r\n")
    if head[:1] in (b"{", b"["):
        return "geojson"
    if head[:1] == b"<":
        return "kml"
    if b"\x00" in head or not _is_text(head):
        raise UnreadableFileError(
            filename, f"is binary data tillpath cannot read; expected {_EXPECTED}"
        )
    raise UnreadableFileError(filename, f"is text but neither JSON nor XML; expected {_EXPECTED}")


def read_fields(
    data: bytes, *, filename: str, limits: ArchiveLimits = DEFAULT_LIMITS
) -> list[FieldSpec]:
    """Read every field of a field file, in file order.

    Parameters
    ----------
    data : bytes
        The file as uploaded or read from disk.
    filename : str
        Its name, used in errors and as the fallback name of a one-field file.
    limits : ArchiveLimits, optional
        How far a zip may inflate.

    Returns
    -------
    list of FieldSpec
        At least one; WGS84 boundaries, not yet validated for planning.

    Raises
    ------
    UnreadableFileError
        If the file is of no known format, is malformed, or is refused for safety.
    InvalidFieldError
        If it holds no polygon, or a polygon's coordinates are malformed.
    """
    fmt = detect_field_format(data, filename=filename)
    if fmt == "geojson":
        return _read_geojson(data, filename=filename)
    if fmt == "gpkg":
        return _fields_from_features(
            read_ogr_features(data, filename=filename, what="GeoPackage"), filename=filename
        )
    if fmt == "kml":
        return _read_kml(data, filename=filename)
    members = unzip_checked(data, filename=filename, limits=limits)
    shapefiles = sorted(n for n in members if n.lower().endswith(".shp"))
    if shapefiles:
        return _read_shapefiles(members, shapefiles, filename=filename)
    documents = sorted(n for n in members if n.lower().endswith(".kml"))
    if documents:
        # Google Earth writes one doc.kml; GDAL writes doc.kml linking to layers/*.kml.
        documents.sort(key=lambda n: PurePosixPath(n).name.lower() != "doc.kml")
        features: list[OgrFeature] = []
        for name in documents:
            check_xml(members[name], filename=f"{filename}/{name}", kind="KML")
            features.extend(
                read_ogr_features(members[name], filename=f"{filename}/{name}", what="KML")
            )
        return _fields_from_features(features, filename=filename)
    raise UnreadableFileError(
        filename,
        "the zip holds neither a Shapefile (.shp with .shx, .dbf, .prj) nor a KML document",
    )


def select_field(fields: list[FieldSpec], choice: str | None, *, filename: str) -> FieldSpec:
    """Pick one field of a file by id, name or index (``--feature ID|NAME|INDEX``).

    The id is matched first, then the name, then ``choice`` as a 0-based index in file order.

    Raises
    ------
    FieldChoiceError
        If the file holds several fields and ``choice`` is None, or ``choice`` matches none
        (or a name shared by several); ``choices`` lists them all.

    Examples
    --------
    >>> square = Polygon([(0, 0), (0.001, 0), (0.001, 0.001), (0, 0.001)])
    >>> fields = [FieldSpec(square, name="north", feature_id="7"), FieldSpec(square, name="south")]
    >>> select_field(fields, "south", filename="f.kml").name
    'south'
    >>> select_field(fields, "7", filename="f.kml").name
    'north'
    >>> select_field(fields, "1", filename="f.kml").name
    'south'
    """
    if choice is None:
        if len(fields) == 1:
            return fields[0]
        raise FieldChoiceError(
            filename,
            f"holds {len(fields)} fields; choose one by id, name or index",
            field_choices(fields),
        )
    text = choice.strip()
    by_id = [f for f in fields if f.feature_id is not None and f.feature_id == text]
    if len(by_id) == 1:
        return by_id[0]
    by_name = [f for f in fields if f.name is not None and f.name == text]
    if len(by_name) == 1:
        return by_name[0]
    if len(by_name) > 1:
        raise FieldChoiceError(
            filename,
            f"{len(by_name)} fields are named {text!r}; choose one by id or index",
            field_choices(fields),
        )
    if text.isdigit() and int(text) < len(fields):
        return fields[int(text)]
    raise FieldChoiceError(
        filename,
        f"has no field with id or name {text!r}, and it is not an index from 0 to "
        f"{len(fields) - 1}",
        field_choices(fields),
    )


def field_choices(fields: Iterable[FieldSpec]) -> list[tuple[int, str | None, str | None, float]]:
    """Return ``(index, feature_id, name, area_m2)`` per field: what a file of fields lists."""
    return [
        (index, f.feature_id, f.name, geodesic_area_m2(f.field_lonlat))
        for index, f in enumerate(fields)
    ]


def fields_to_geojson(fields: Iterable[FieldSpec]) -> dict[str, Any]:
    """Return fields as a GeoJSON FeatureCollection, one Feature per field.

    Each Feature's properties are ``index``, ``id``, ``name``, ``area_m2`` (geodesic) and
    ``interval_m``; the file's start and finish are Points with ``role`` after the fields, so
    the collection reads back with :func:`planner.fields.parse_fields_geojson`.
    """
    fields = list(fields)
    features: list[dict[str, Any]] = []
    for index, spec in enumerate(fields):
        rings = [spec.field_lonlat.exterior, *spec.field_lonlat.interiors]
        features.append(
            {
                "type": "Feature",
                "properties": {
                    "index": index,
                    "id": spec.feature_id,
                    "name": spec.name,
                    "area_m2": round(geodesic_area_m2(spec.field_lonlat), 2),
                    "interval_m": spec.interval_m,
                },
                "geometry": {
                    "type": "Polygon",
                    "coordinates": [[[x, y] for x, y, *_ in r.coords] for r in rings],
                },
            }
        )
    for role in ("start", "finish"):
        position = next(
            (getattr(f, f"{role}_lonlat") for f in fields if getattr(f, f"{role}_lonlat")), None
        )
        if position is not None:
            features.append(
                {
                    "type": "Feature",
                    "properties": {"role": role},
                    "geometry": {"type": "Point", "coordinates": list(position)},
                }
            )
    return {"type": "FeatureCollection", "features": features}


# --- formats ---------------------------------------------------------------------------------


def _read_geojson(data: bytes, *, filename: str) -> list[FieldSpec]:
    try:
        obj = json.loads(data.decode("utf-8-sig"))
    except UnicodeDecodeError:
        raise UnreadableFileError(filename, "is not UTF-8 text, so not GeoJSON") from None
    except (json.JSONDecodeError, RecursionError) as exc:
        where = (
            f" (line {exc.lineno}, column {exc.colno})"
            if isinstance(exc, json.JSONDecodeError)
            else ""
        )
        raise UnreadableFileError(filename, f"is not valid JSON{where}") from None
    crs = _geojson_crs(obj)
    if not is_lonlat_crs(crs):
        return _fields_from_features(
            read_ogr_features(data, filename=filename, what="GeoJSON"), filename=filename
        )
    try:
        return parse_fields_geojson(obj)
    except PlannerError as exc:
        raise InvalidFieldError(filename, exc.problem) from None


def _geojson_crs(obj: Any) -> str | None:
    if not isinstance(obj, Mapping):
        return None
    crs = obj.get("crs")
    if not isinstance(crs, Mapping):
        return None
    name = (
        (crs.get("properties") or {}).get("name")
        if isinstance(crs.get("properties"), Mapping)
        else None
    )
    return str(name) if name else None


def _read_kml(data: bytes, *, filename: str) -> list[FieldSpec]:
    check_xml(data, filename=filename, kind="KML")
    return _fields_from_features(
        read_ogr_features(data, filename=filename, what="KML"), filename=filename
    )


def _read_shapefiles(
    members: dict[str, bytes], shapefiles: list[str], *, filename: str
) -> list[FieldSpec]:
    by_lower = {name.lower(): name for name in members}
    features: list[OgrFeature] = []
    for shp in shapefiles:
        stem = shp[: -len(".shp")]
        flat = io.BytesIO()
        with zipfile.ZipFile(flat, "w", compression=zipfile.ZIP_STORED) as repacked:
            base = PurePosixPath(stem).name
            for ext in _SHAPEFILE_PARTS:
                member = by_lower.get(f"{stem}{ext}".lower())
                if member is not None:
                    repacked.writestr(f"{base}{ext}", members[member])
                elif ext in (".shx", ".dbf"):
                    raise UnreadableFileError(
                        filename, f"{shp} has no {ext} beside it; zip all the Shapefile's files"
                    )
        features.extend(read_ogr_features(flat.getvalue(), filename=filename, what="Shapefile"))
    return _fields_from_features(features, filename=filename)


# --- features to fields ----------------------------------------------------------------------


def _fields_from_features(features: Iterable[OgrFeature], *, filename: str) -> list[FieldSpec]:
    polygons: list[tuple[Polygon, str | None, str | None, float | None]] = []
    points: dict[str, tuple[float, float]] = {}
    for feature in features:
        props = feature.properties
        geometry = feature.geometry_lonlat
        name = _first(props, _NAME_KEYS)
        role = str(props.get("role") or name or "").strip().lower()
        if isinstance(geometry, Point):
            if role in ("start", "finish") and role not in points:
                points[role] = (float(geometry.x), float(geometry.y))
            continue
        parts = _polygon_parts(geometry)
        if not parts:
            continue
        feature_id = _first(props, _ID_KEYS)
        interval = props.get("interval_m")
        interval_m = float(interval) if isinstance(interval, (int, float)) else None
        for k, part in enumerate(parts, start=1):
            if len(parts) == 1:
                polygons.append((part, feature_id, name, interval_m))
            else:
                polygons.append(
                    (
                        part,
                        f"{feature_id}.{k}" if feature_id else None,
                        f"{name} ({k} of {len(parts)})" if name else None,
                        interval_m,
                    )
                )
    if not polygons:
        raise InvalidFieldError(filename, "holds no field boundary (no Polygon feature)")
    return [
        FieldSpec(
            field_lonlat=polygon,
            start_lonlat=points.get("start"),
            finish_lonlat=points.get("finish"),
            interval_m=interval_m,
            name=name or feature_id,
            feature_id=feature_id,
        )
        for polygon, feature_id, name, interval_m in polygons
    ]


def _polygon_parts(geometry: Any) -> list[Polygon]:
    if isinstance(geometry, Polygon):
        return [geometry]
    if isinstance(geometry, MultiPolygon):
        return list(geometry.geoms)
    if hasattr(geometry, "geoms"):  # a GeometryCollection (KML MultiGeometry)
        return [part for g in geometry.geoms for part in _polygon_parts(g)]
    return []


def _first(props: Mapping[str, Any], keys: Iterable[str]) -> str | None:
    for key in keys:
        value = props.get(key)
        if value not in (None, ""):
            return str(value)
    return None


def _is_text(head: bytes) -> bool:
    try:
        head.decode("utf-8")
    except UnicodeDecodeError as exc:
        return exc.start >= len(head) - 4  # a character cut by the 4 KiB window
    return True
