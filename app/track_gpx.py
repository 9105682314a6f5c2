"""Read a GPX 1.0/1.1 track incrementally (defusedxml ``iterparse``): see :mod:`app.tracks`."""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterator
from typing import Any, BinaryIO, Final

import defusedxml.ElementTree
from defusedxml import DefusedXmlException

from app.track_fixes import (
    MAX_TIME_TEXT,
    TrackFix,
    TrackFormatError,
    check_motion,
    check_position,
    checked_time,
    datetime_to_us,
    finite_or_none,
    optional_float,
)

#: GPX 1.1 ``<fix>`` values (none, 2d, 3d, dgps, pps) mapped where they say something.
GPX_FIXES: Final[dict[str, str]] = {"2d": "single", "3d": "single", "dgps": "dgps"}


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def read_gpx(stream: BinaryIO, report: dict[str, Any]) -> Iterator[TrackFix]:
    """Yield the timed points of the first ``<trk>`` that has any, reading incrementally.

    Each ``<trkpt>``, ``<rtept>`` and ``<wpt>`` is removed from the tree once read, so memory
    holds one point at a time. The rest of the file is still parsed (to count the tracks and
    to refuse a file that is not well-formed).
    """
    try:
        events = defusedxml.ElementTree.iterparse(
            stream,
            events=("start", "end"),
            forbid_dtd=True,
            forbid_entities=True,
            forbid_external=True,
        )
        stack: list[Any] = []
        tracks = 0
        chosen = False  # a track with timed points has been read
        untimed = 0
        track_name: str | None = None
        yielded = 0
        for event, elem in events:
            name = _local(elem.tag)
            if event == "start":
                if not stack and name != "gpx":
                    raise TrackFormatError(
                        "file", f"is not a valid GPX file (its root element is <{name}>)"
                    )
                stack.append(elem)
                if name == "trk":
                    tracks += 1
                    if not chosen:
                        untimed, track_name, yielded = 0, None, 0
                continue
            stack.pop()
            parent = _local(stack[-1].tag) if stack else ""
            if name == "name" and parent == "trk" and not chosen and tracks:
                track_name = (elem.text or "").strip() or None
            elif name == "trkpt" and not chosen:
                fix = _gpx_point(elem, tracks)
                if fix is None:
                    untimed += 1
                else:
                    yielded += 1
                    yield fix
            elif name == "trk" and yielded and not chosen:
                chosen = True
                report.update(
                    track=track_name or f"track {tracks}", tracks_ignored=0, untimed_points=untimed
                )
            if name in ("trkpt", "rtept", "wpt") and stack:
                stack[-1].remove(elem)
    except DefusedXmlException:
        raise TrackFormatError(
            "file", "GPX with a DTD, entity declarations or external references is refused"
        ) from None
    except TrackFormatError:
        raise
    except Exception as exc:  # ParseError: not well-formed (truncated, …)
        raise TrackFormatError("file", f"is not well-formed XML ({exc})") from None
    if chosen:
        report["tracks_ignored"] = tracks - 1
    else:
        report.update(tracks=tracks, untimed_points=untimed)


def _gpx_point(elem: Any, track: int) -> TrackFix | None:
    where = f"file: track {track}"
    lat = optional_float(elem.get("lat"), input_name=f"{where}: lat")
    lon = optional_float(elem.get("lon"), input_name=f"{where}: lon")
    if lat is None or lon is None:
        raise TrackFormatError(where, "a <trkpt> needs lat and lon")
    check_position(lat, lon, input_name=where)
    values: dict[str, str] = {}
    for child in elem:
        values.setdefault(_local(child.tag), (child.text or "").strip())
    if not values.get("time"):
        return None
    try:
        when = dt.datetime.fromisoformat(values["time"][:MAX_TIME_TEXT])
    except ValueError:
        raise TrackFormatError(
            f"{where}: time", f"{values['time'][:40]!r} is not an ISO 8601 time"
        ) from None
    heading = finite_or_none(optional_float(values.get("course"), input_name=f"{where}: course"))
    speed = finite_or_none(optional_float(values.get("speed"), input_name=f"{where}: speed"))
    check_motion(heading, speed, input_name=where)
    hdop = optional_float(values.get("hdop"), input_name=f"{where}: hdop")
    sat = optional_float(values.get("sat"), input_name=f"{where}: sat")
    return TrackFix(
        t=checked_time(datetime_to_us(when), "file: GPX point time"),
        lat=lat,
        lon=lon,
        heading_deg=heading,
        speed_mps=speed,
        quality=GPX_FIXES.get(values.get("fix", "").lower()),
        hdop=hdop if hdop is not None and 0 <= hdop <= 1000 else None,
        satellites=int(sat) if sat is not None and 0 <= sat <= 1000 else None,
    )
