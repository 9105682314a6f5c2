"""Stream the fields of a GeoPackage, GeoJSON, zipped Shapefile or GeoParquet file in chunks.

``tillpath plan-batch`` plans files of any size in flat memory, so nothing here reads a whole
file: OGR formats are read with pyogrio ``skip_features``/``max_features`` windows (efficient on
GeoPackage and Shapefile; GDAL holds a GeoJSON file in memory, so use GeoPackage or GeoParquet
for millions of fields), GeoParquet with pyarrow's row-batch iterator. Geometries stay WKB and
are reprojected to WGS84 lon/lat when the file is in another CRS.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
import shapely
from pyproj import CRS, Transformer

#: File suffixes read through GDAL (pyogrio), and through pyarrow.
OGR_SUFFIXES: Final = (".gpkg", ".geojson", ".json", ".zip", ".shp", ".fgb")
PARQUET_SUFFIXES: Final = (".parquet", ".geoparquet")
#: Property names that give a field's id, name and line interval (case-insensitive).
ID_KEYS: Final = ("id", "field_id", "fid")
NAME_KEYS: Final = ("name", "field_name", "nama")
INTERVAL_KEY: Final = "interval_m"
WGS84: Final = CRS.from_epsg(4326)


class BatchInputError(ValueError):
    """The FIELDS file cannot be read at all (one bad field is a row, not this)."""


@dataclass(frozen=True, slots=True)
class FieldRecord:
    """One field of the file, as the planning task gets it.

    Attributes
    ----------
    index : int
        Position in the file, from 0.
    ident : str
        The ``id`` property, else the index.
    name : str or None
    wkb : bytes or None
        The geometry in WGS84 lon/lat, or None if the feature has none.
    interval_m : float or None
        The feature's own ``interval_m`` property.
    """

    index: int
    ident: str
    name: str | None
    wkb: bytes | None
    interval_m: float | None


@dataclass(frozen=True, slots=True)
class FieldSource:
    """An opened FIELDS file: what it is, and how many features it has."""

    path: Path
    kind: str
    count: int
    layer: str | None = None


def _vsi(path: Path) -> str:
    return f"/vsizip/{path}" if path.suffix.lower() == ".zip" else str(path)


def open_fields(path: Path, *, layer: str | None = None) -> FieldSource:
    """Check that ``path`` is a readable fields file and count its features.

    Raises
    ------
    BatchInputError
        ``FIELDS: …`` naming the file and the problem.
    """
    if not path.is_file():
        raise BatchInputError(f"FIELDS: {path} does not exist or is not a file")
    suffix = path.suffix.lower()
    if suffix in PARQUET_SUFFIXES:
        import pyarrow.parquet as pq

        try:
            count = pq.ParquetFile(path).metadata.num_rows
        except Exception as exc:
            raise BatchInputError(f"FIELDS: {path} is not a readable Parquet file ({exc})") from exc
        return FieldSource(path, "parquet", int(count))
    if suffix not in OGR_SUFFIXES:
        known = ", ".join((*OGR_SUFFIXES, *PARQUET_SUFFIXES))
        raise BatchInputError(f"FIELDS: {path.name} is not a known format (use {known})")
    import pyogrio

    try:
        info = pyogrio.read_info(_vsi(path), layer=layer, force_feature_count=True)
    except Exception as exc:
        raise BatchInputError(f"FIELDS: cannot read {path}: {exc}") from exc
    return FieldSource(path, "ogr", int(info["features"]), layer)


def _pick(columns: list[str], keys: tuple[str, ...]) -> int | None:
    lowered = [c.lower() for c in columns]
    for key in keys:
        if key in lowered:
            return lowered.index(key)
    return None


def _text(value: Any) -> str | None:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return None
    text = str(value).strip()
    return text or None


def _number(value: Any) -> float | None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if np.isfinite(number) else None


def _to_wgs84(crs: CRS | None) -> Transformer | None:
    if crs is None or crs.equals(WGS84, ignore_axis_order=True):
        return None
    return Transformer.from_crs(crs, WGS84, always_xy=True)


def _records(
    start: int,
    wkbs: list[bytes | None],
    columns: list[str],
    values: list[list[Any]],
    transformer: Transformer | None,
) -> list[FieldRecord]:
    id_at, name_at, interval_at = (
        _pick(columns, ID_KEYS),
        _pick(columns, NAME_KEYS),
        _pick(columns, (INTERVAL_KEY,)),
    )
    if transformer is not None:
        geometries = shapely.from_wkb(np.array(wkbs, dtype=object))
        moved = shapely.transform(
            geometries, lambda xy: np.column_stack(transformer.transform(xy[:, 0], xy[:, 1]))
        )
        wkbs = [None if g is None else shapely.to_wkb(g) for g in moved]
    records = []
    for i, wkb in enumerate(wkbs):
        ident = _text(values[id_at][i]) if id_at is not None else None
        records.append(
            FieldRecord(
                index=start + i,
                ident=ident or str(start + i),
                name=_text(values[name_at][i]) if name_at is not None else None,
                wkb=wkb,
                interval_m=_number(values[interval_at][i]) if interval_at is not None else None,
            )
        )
    return records


def iter_field_chunks(source: FieldSource, chunk_size: int) -> Iterator[list[FieldRecord]]:
    """Yield the file's fields, ``chunk_size`` at a time, in file order."""
    if source.kind == "parquet":
        yield from _parquet_chunks(source.path, chunk_size)
        return
    import pyogrio.raw

    start = 0
    while start < source.count:
        meta, _fids, geometry, field_data = pyogrio.raw.read(
            _vsi(source.path),
            layer=source.layer,
            skip_features=start,
            max_features=chunk_size,
        )
        if len(geometry) == 0:
            return
        crs = CRS.from_user_input(meta["crs"]) if meta.get("crs") else WGS84
        columns = [str(c) for c in meta["fields"]]
        values = [list(column) for column in field_data]
        yield _records(start, list(geometry), columns, values, _to_wgs84(crs))
        start += len(geometry)


def _parquet_chunks(path: Path, chunk_size: int) -> Iterator[list[FieldRecord]]:
    import pyarrow.parquet as pq

    parquet = pq.ParquetFile(path)
    geo = json.loads((parquet.schema_arrow.metadata or {}).get(b"geo", b"{}") or b"{}")
    column = geo.get("primary_column", "geometry")
    described = (geo.get("columns") or {}).get(column, {})
    if described.get("encoding", "WKB").upper() != "WKB":
        raise BatchInputError(
            f"FIELDS: {path.name}: geometry encoding {described['encoding']!r} is not supported "
            "(write the GeoParquet file with WKB geometries)"
        )
    crs_info = described.get("crs")
    crs = CRS.from_user_input(crs_info) if crs_info else WGS84  # GeoParquet's default: CRS84
    transformer = _to_wgs84(crs)
    start = 0
    for batch in parquet.iter_batches(batch_size=chunk_size):
        table = batch.to_pydict()
        if column not in table:
            raise BatchInputError(f"FIELDS: {path.name} has no geometry column {column!r}")
        wkbs = table.pop(column)
        columns = list(table)
        yield _records(start, wkbs, columns, [table[c] for c in columns], transformer)
        start += len(wkbs)
