"""app.track_gpx: reading GPX tracks, and refusing what defusedxml refuses (pure)."""

from __future__ import annotations

import pytest

from app.track_fixes import TrackFormatError
from app.tracks import parse_track
from tests.app.track_files import (
    gpx_file,
    simulated_run,
)

BILLION_LAUGHS = b"""<?xml version="1.0"?>
<!DOCTYPE lolz [
 <!ENTITY lol "lol">
 <!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol4 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
 <!ENTITY lol5 "&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;">
 <!ENTITY lol6 "&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;">
 <!ENTITY lol7 "&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;">
 <!ENTITY lol8 "&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;">
 <!ENTITY lol9 "&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;">
]>
<gpx version="1.1" creator="bomb" xmlns="http://www.topografix.com/GPX/1/1">
 <trk><name>&lol9;</name><trkseg>
  <trkpt lat="-8.6265" lon="115.298"><time>2026-11-22T00:00:00Z</time></trkpt>
 </trkseg></trk>
</gpx>
"""


EXTERNAL_ENTITY = b"""<?xml version="1.0"?>
<!DOCTYPE gpx [<!ENTITY xxe SYSTEM "file:///etc/passwd">]>
<gpx version="1.1" creator="x" xmlns="http://www.topografix.com/GPX/1/1">
 <trk><name>&xxe;</name><trkseg>
  <trkpt lat="-8.6265" lon="115.298"><time>2026-11-22T00:00:00Z</time></trkpt>
 </trkseg></trk>
</gpx>
"""


def test_gpx_reads_the_first_timed_track_only():
    track = parse_track(gpx_file(simulated_run()))
    assert track.report["track"] == "true"
    assert track.report["tracks_ignored"] == 2


def test_xml_bomb_is_refused_before_expansion():
    with pytest.raises(TrackFormatError, match="DTD, entity declarations"):
        parse_track(BILLION_LAUGHS)


def test_external_entity_is_refused():
    with pytest.raises(TrackFormatError, match="DTD, entity declarations"):
        parse_track(EXTERNAL_ENTITY)


def test_truncated_gpx_is_not_well_formed():
    data = gpx_file(simulated_run())
    with pytest.raises(TrackFormatError, match="^file: is not well-formed XML"):
        parse_track(data[: len(data) // 2])


def test_gpx_without_times_has_no_usable_fix():
    data = (
        b'<gpx version="1.1" creator="x" xmlns="http://www.topografix.com/GPX/1/1"><trk><trkseg>'
        b'<trkpt lat="-8.6265" lon="115.298"/><trkpt lat="-8.6266" lon="115.298"/>'
        b"</trkseg></trk></gpx>"
    )
    with pytest.raises(TrackFormatError, match="no usable fix.*untimed points: 2"):
        parse_track(data)
