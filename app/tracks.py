"""Read a tractor's recorded track: GPX, CSV or an NMEA 0183 log (product.md §8).

Pure: the uploaded bytes in, a :class:`ParsedTrack` out (fixes sorted by time, one per
timestamp), or a :class:`TrackFormatError` naming the problem. No database, no HTTP. gpsbabel
unicsv, RTKLIB .pos, u-blox UBX and KML tracks are read by :mod:`app.track_formats`.

Formats
-------
- **GPX 1.0/1.1**: the first ``<trk>`` that has timed points (all its segments); points without
  a time are dropped and counted. The XML is read incrementally by defusedxml's ``iterparse``
  (expat), one point at a time: a DTD, entity declarations (the "billion laughs" bomb) or
  external references are refused as soon as they appear.
- **CSV**: a header naming ``time``, ``lat``, ``lon`` and optionally ``heading_deg`` and
  ``speed_mps`` (``heading`` and ``speed`` are accepted too), in any order. Times are ISO 8601
  (``2026-11-22T03:14:15.2Z``; without an offset, UTC) or Unix epoch seconds. A row that cannot
  be read refuses the whole file, naming its line.
- **NMEA 0183** as a u-blox receiver logs it (``$GNGGA``/``$GPGGA``, ``$GNRMC``/``$GPRMC`` among
  GSV, GSA, VTG, TXT …): every sentence must carry a correct checksum; a sentence that does not,
  or cannot be parsed, is skipped and counted. Fixes with GGA quality 0 or RMC status ``V``
  (no fix) are dropped and counted. GGA has no date: the date comes from the last RMC before it
  (for fixes before the first RMC, counted back from that one), and a time of day that falls
  back by more than 12 h means midnight passed.

Every reader streams (:func:`read_track`): memory holds a line or a point, never the file.
This module tells the format and hands the file to its reader, one module per format
(:mod:`app.track_gpx`, :mod:`app.track_csv`, :mod:`app.track_nmea`, :mod:`app.track_formats`);
what a fix is, its times and the checks they share are in :mod:`app.track_fixes`.

Timestamps are integers, microseconds since the Unix epoch (UTC): equal times written
differently (``…T00:00:01.500Z`` and ``1767225601.5``) become the same fix.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, BinaryIO, Final

from app.track_csv import CSV_COLUMNS, read_csv
from app.track_fixes import ParsedTrack, TrackFix, TrackFormatError, check_not_empty, sort_fixes
from app.track_formats import EXTRA_TRACK_FORMATS, detect_extra_format, read_extra_format
from app.track_gpx import read_gpx
from app.track_nmea import NMEA_LINE, read_nmea

#: The formats :func:`parse_track` reads.
TRACK_FORMATS: Final = ("gpx", "csv", "nmea")


# --- detection -------------------------------------------------------------------------------


def detect_format(text: str) -> str | None:
    """Tell ``gpx``, ``nmea`` or ``csv`` from the file's first lines; None if none fits.

    Examples
    --------
    >>> detect_format('<?xml version="1.0"?><gpx/>'), detect_format("time,lat,lon")
    ('gpx', 'csv')
    >>> detect_format("$GNGGA,1,2*00"), detect_format("hello")
    ('nmea', None)
    """
    head = text.lstrip("\ufeff \t\r\n")
    if head.startswith("<"):
        return "gpx"
    lines = [line.strip() for line in head.splitlines()[:50] if line.strip()]
    if any(NMEA_LINE.match(line) for line in lines):
        return "nmea"
    if lines:
        names = {name.strip().lower() for name in lines[0].split(",")}
        mapped = {CSV_COLUMNS.get(name) for name in names}
        if {"lat", "lon"} <= mapped or ("," in lines[0] and "time" in mapped):
            return "csv"
    return None


def parse_track(data: bytes) -> ParsedTrack:
    """Read a GPX, CSV or NMEA track file (the format is detected from its content).

    Parameters
    ----------
    data : bytes
        The file as uploaded.

    Returns
    -------
    ParsedTrack
        At least one fix.

    Raises
    ------
    TrackFormatError
        For an unknown format, a malformed file, XML with a DTD or entities, or a file with no
        usable fix.
    """
    stream = read_track(io.BytesIO(data))
    fixes, duplicates = sort_fixes(stream.fixes)
    return stream.parsed(fixes, duplicates)


@dataclass(slots=True)
class TrackStream:
    """A track file being read: its format, its fixes as they are read, and the report.

    Attributes
    ----------
    format : str
        ``gpx``, ``csv`` or ``nmea``.
    fixes : iterator of TrackFix
        In file order; consuming it may raise :class:`TrackFormatError`.
    report : dict
        Filled in while ``fixes`` is consumed (see :class:`ParsedTrack`).
    """

    format: str
    fixes: Iterator[TrackFix]
    report: dict[str, Any]

    def parsed(self, fixes: list[TrackFix], duplicates: int) -> ParsedTrack:
        """Wrap the sorted, de-duplicated ``fixes`` as a :class:`ParsedTrack`."""
        check_not_empty(self.format, len(fixes), self.report)
        return ParsedTrack(
            format=self.format, fixes=fixes, report=self.summary(len(fixes), duplicates)
        )

    def summary(self, count: int, duplicates: int) -> dict[str, Any]:
        """Return the import report: ``count`` fixes kept, ``duplicates`` dropped."""
        return {"format": self.format, "fixes": count, "duplicate_times": duplicates, **self.report}


#: Bytes read ahead to tell the format.
_HEAD_BYTES: Final = 64 * 1024


def read_track(stream: BinaryIO) -> TrackStream:
    """Start reading a track file from a seekable binary stream, one line or element at a time.

    Memory stays bounded whatever the file's size: CSV and NMEA are read line by line, GPX
    with an incremental XML parser (defusedxml, no DTD or entities) that drops each point once
    read. Nothing is sorted here (see :func:`sort_fixes`).

    Parameters
    ----------
    stream : binary file
        Positioned at the start; must be seekable (the head is read twice).

    Returns
    -------
    TrackStream

    Raises
    ------
    TrackFormatError
        If the format is none of GPX, CSV and NMEA (the fixes raise it for a malformed file).
    """
    head_bytes = stream.read(_HEAD_BYTES)
    stream.seek(0)
    fmt = detect_extra_format(head_bytes) or detect_format(
        head_bytes.decode("utf-8", errors="replace")
    )
    report: dict[str, Any] = {}
    if fmt in EXTRA_TRACK_FORMATS:  # read whole (within the upload limit), as before
        fixes, extra_report = read_extra_format(fmt, stream.read())
        return TrackStream(fmt, iter(fixes), extra_report)
    if fmt == "gpx":
        return TrackStream(fmt, read_gpx(stream, report), report)
    if fmt in ("nmea", "csv"):
        text = io.TextIOWrapper(stream, encoding="utf-8-sig", errors="replace", newline="")
        reader = read_nmea if fmt == "nmea" else read_csv
        return TrackStream(fmt, reader(text, report), report)
    raise TrackFormatError(
        "file",
        "is not a track file tillpath can read: expected GPX, KML, CSV with a "
        "time,lat,lon header, gpsbabel unicsv, RTKLIB .pos, u-blox UBX or an NMEA 0183 log",
    )
