"""Read a CSV track with a ``time,lat,lon`` header, line by line: see :mod:`app.tracks`."""

from __future__ import annotations

import csv
from collections.abc import Iterable, Iterator
from typing import Any, Final

from app.track_fixes import (
    TrackFix,
    TrackFormatError,
    check_motion,
    check_position,
    optional_float,
    parse_time,
)

#: Header names read (lower case) -> the column they give.
CSV_COLUMNS: Final[dict[str, str]] = {
    "time": "time",
    "timestamp": "time",
    "t": "time",
    "lat": "lat",
    "latitude": "lat",
    "lon": "lon",
    "lng": "lon",
    "longitude": "lon",
    "heading_deg": "heading_deg",
    "heading": "heading_deg",
    "course": "heading_deg",
    "speed_mps": "speed_mps",
    "speed": "speed_mps",
}


def read_csv(lines: Iterable[str], report: dict[str, Any]) -> Iterator[TrackFix]:
    """Yield the rows of a CSV track as fixes; a row that cannot be read refuses the file."""
    reader = csv.reader(lines)
    try:
        header = next(reader)
    except StopIteration:
        raise TrackFormatError("file", "the CSV file is empty") from None
    except csv.Error as exc:
        raise TrackFormatError("file", f"line 1: {exc}") from None
    columns: dict[str, int] = {}
    for i, name in enumerate(header):
        key = CSV_COLUMNS.get(name.strip().lstrip("\ufeff").lower())
        if key is not None and key not in columns:
            columns[key] = i
    missing = [name for name in ("time", "lat", "lon") if name not in columns]
    if missing:
        raise TrackFormatError(
            "file",
            f"the CSV header must name time, lat and lon (optional: heading_deg, speed_mps); "
            f"missing: {', '.join(missing)}",
        )
    width = max(columns.values()) + 1
    try:
        for row in reader:
            line = reader.line_num
            if not row or all(not cell.strip() for cell in row):
                continue
            where = f"file: line {line}"
            if len(row) < width:
                raise TrackFormatError(
                    where, f"has {len(row)} fields, the header needs at least {width}"
                )
            lat = optional_float(row[columns["lat"]], input_name=f"{where}: lat")
            lon = optional_float(row[columns["lon"]], input_name=f"{where}: lon")
            if lat is None or lon is None:
                raise TrackFormatError(where, "lat and lon are required")
            check_position(lat, lon, input_name=where)
            heading = speed = None
            if "heading_deg" in columns and columns["heading_deg"] < len(row):
                heading = optional_float(
                    row[columns["heading_deg"]], input_name=f"{where}: heading_deg"
                )
            if "speed_mps" in columns and columns["speed_mps"] < len(row):
                speed = optional_float(row[columns["speed_mps"]], input_name=f"{where}: speed_mps")
            check_motion(heading, speed, input_name=where)
            yield TrackFix(
                t=parse_time(row[columns["time"]], input_name=f"{where}: time"),
                lat=lat,
                lon=lon,
                heading_deg=heading,
                speed_mps=speed,
            )
    except csv.Error as exc:
        raise TrackFormatError(f"file: line {reader.line_num}", str(exc)) from None
