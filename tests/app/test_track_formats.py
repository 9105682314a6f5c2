"""app.tracks: reading GPX, CSV and NMEA track files (pure; no database, no HTTP)."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from app.tracks import (
    TrackFix,
    TrackFormatError,
    detect_format,
    parse_time,
    parse_track,
    sort_fixes,
)
from tests.app.track_files import (
    RUN_START,
    csv_file,
    gpx_file,
    nmea_file,
    nmea_lines,
    sentence,
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


def times_s(fixes: list[TrackFix]) -> np.ndarray:
    return (np.array([f.t for f in fixes]) - fixes[0].t) / 1e6


@pytest.mark.parametrize("writer", [gpx_file, csv_file, nmea_file], ids=["gpx", "csv", "nmea"])
def test_simulated_run_reads_back_with_its_times_and_positions(writer):
    run = simulated_run()
    track = parse_track(writer(run))
    assert track.format == writer.__name__.removesuffix("_file")
    assert len(track.fixes) == len(run.time_s)
    assert track.fixes[0].t == RUN_START.timestamp() * 1_000_000
    np.testing.assert_allclose(times_s(track.fixes), run.time_s, atol=0.006)
    # NMEA keeps 1e-5 minutes (1.9 cm); the others keep 1e-9 degrees.
    atol = 2e-7 if track.format == "nmea" else 1e-8
    np.testing.assert_allclose([f.lat for f in track.fixes], run.lat, rtol=0, atol=atol)
    np.testing.assert_allclose([f.lon for f in track.fixes], run.lon, rtol=0, atol=atol)
    assert track.report["fixes"] == len(run.time_s)


def test_gpx_reads_the_first_timed_track_only():
    track = parse_track(gpx_file(simulated_run()))
    assert track.report["track"] == "true"
    assert track.report["tracks_ignored"] == 2


def test_csv_epoch_seconds_and_iso_times_give_the_same_fixes():
    run = simulated_run()
    iso = parse_track(csv_file(run))
    epoch = parse_track(csv_file(run, epoch=True))
    assert [f.t for f in iso.fixes] == [f.t for f in epoch.fixes]


def test_csv_columns_in_any_order_with_aliases_and_optional_fields():
    text = b"lon,speed,latitude,timestamp\n115.298,0.5,-8.6265,2026-11-22T00:00:01Z\n"
    (fix,) = parse_track(text).fixes
    assert (fix.lat, fix.lon, fix.speed_mps, fix.heading_deg) == (-8.6265, 115.298, 0.5, None)


def test_nmea_log_across_midnight_gets_the_next_date():
    track = parse_track(nmea_file(simulated_run()))
    days = {dt.datetime.fromtimestamp(f.t / 1e6, dt.UTC).date() for f in track.fixes}
    assert days == {dt.date(2026, 11, 21), dt.date(2026, 11, 22)}
    assert all(np.diff([f.t for f in track.fixes]) > 0)


def test_nmea_gga_before_the_first_rmc_is_dated_back_from_it_across_midnight():
    gga = sentence("GNGGA,235959.80,0837.59116,S,11517.87860,E,1,09,0.86,35.2,M,18.1,M,,")
    gga2 = sentence("GNGGA,000000.00,0837.59117,S,11517.87861,E,1,09,0.86,35.2,M,18.1,M,,")
    rmc = sentence("GNRMC,000000.20,A,0837.59118,S,11517.87862,E,0.1,,221126,,,A")
    track = parse_track("\n".join([gga, gga2, rmc]).encode())
    stamps = [dt.datetime.fromtimestamp(f.t / 1e6, dt.UTC) for f in track.fixes]
    assert stamps == [
        dt.datetime(2026, 11, 21, 23, 59, 59, 800000, tzinfo=dt.UTC),
        dt.datetime(2026, 11, 22, 0, 0, 0, tzinfo=dt.UTC),
        dt.datetime(2026, 11, 22, 0, 0, 0, 200000, tzinfo=dt.UTC),
    ]
    assert track.fixes[0].lat == pytest.approx(-(8 + 37.59116 / 60))
    assert track.fixes[0].lon == pytest.approx(115 + 17.87860 / 60)


def test_nmea_bad_checksums_and_garbage_are_skipped_and_counted():
    times = [RUN_START + dt.timedelta(seconds=i) for i in range(10)]
    lines = nmea_lines(times, [115.298 + i * 1e-6 for i in range(10)], [-8.6265] * 10)
    rmc_gga = [i for i, line in enumerate(lines) if line[3:6] in ("RMC", "GGA")]
    broken = rmc_gga[4]  # one sentence of the third epoch
    lines[broken] = lines[broken][:-2] + ("00" if lines[broken][-2:] != "00" else "11")
    lines.insert(3, "\x00\xb5b\x01\x07 binary UBX noise")
    lines.append(lines[-1][: len(lines[-1]) // 2])  # truncated at the end
    track = parse_track("\n".join(lines).encode())
    assert track.report["bad_sentences"] == 3
    assert len(track.fixes) == 10  # the epoch keeps its other sentence


def test_nmea_fix_quality_zero_is_dropped_and_counted():
    times = [RUN_START + dt.timedelta(seconds=i) for i in range(6)]
    quality = [1, 0, 0, 4, 5, 1]
    lines = nmea_lines(times, [115.298] * 6, [-8.6265] * 6, quality=quality)
    track = parse_track("\n".join(lines).encode())
    assert len(track.fixes) == 4
    assert track.report["no_fix"] == 2


def test_nmea_with_only_bad_checksums_has_no_usable_fix():
    times = [RUN_START + dt.timedelta(seconds=i) for i in range(5)]
    lines = [line[:-2] + "ZZ" for line in nmea_lines(times, [115.298] * 5, [-8.6265] * 5)]
    with pytest.raises(TrackFormatError, match=r"^file: has no usable fix \(NMEA; bad sentences"):
        parse_track("\n".join(lines).encode())


def test_nmea_without_rmc_cannot_date_its_fixes():
    gga = sentence("GNGGA,120000.00,0837.59116,S,11517.87860,E,1,09,0.86,35.2,M,18.1,M,,")
    with pytest.raises(TrackFormatError, match="no RMC sentence with a date"):
        parse_track(gga.encode())


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


def test_csv_without_lat_column_names_what_is_missing():
    with pytest.raises(TrackFormatError, match="missing: lat"):
        parse_track(b"time,lon,x\n2026-11-22T00:00:00Z,115.298,1\n")


def test_csv_without_header_is_an_unknown_format():
    with pytest.raises(TrackFormatError, match="^file: is not a track file"):
        parse_track(b"2026-11-22T00:00:00Z,-8.6265,115.298\n")


def test_csv_truncated_row_names_its_line():
    data = csv_file(simulated_run())
    cut = data[: data.index(b"\n", 500) + 20]  # ends inside a row
    with pytest.raises(TrackFormatError, match=r"^file: line \d+: has [12] fields"):
        parse_track(cut)


@pytest.mark.parametrize(
    ("row", "message"),
    [
        ("yesterday,-8.6,115.2", r"line 2: time: 'yesterday' is neither"),
        ("2026-11-22T00:00:00Z,north,115.2", r"line 2: lat: 'north' is not a number"),
        ("2026-11-22T00:00:00Z,-98.6,115.2", r"line 2: lat must be between -90 and 90"),
        ("1900-01-01T00:00:00Z,-8.6,115.2", r"line 2: time: must lie between 1980 and 2100"),
    ],
)
def test_csv_bad_value_names_line_and_column(row: str, message: str):
    with pytest.raises(TrackFormatError, match=message):
        parse_track(f"time,lat,lon\n{row}\n".encode())


@pytest.mark.parametrize("data", [b"", b"hello world\n", b"\x89PNG\r\n\x1a\n\x00\x00"])
def test_unknown_format_is_refused(data: bytes):
    with pytest.raises(TrackFormatError, match="^file: is not a track file tillpath can read"):
        parse_track(data)


def test_parse_time_accepts_iso_and_epoch_alike():
    expected = 1_795_318_455_200_000
    for value in [
        "2026-11-22T03:34:15.2Z",
        "2026-11-22T03:34:15.200+00:00",
        "2026-11-22T11:34:15.2+08:00",
        "2026-11-22 03:34:15.2",
        "1795318455.2",
        1795318455.2,
    ]:
        assert parse_time(value, input_name="t") == expected, value


@pytest.mark.parametrize("value", [None, True, "", "soon", float("nan"), "inf", 1e30])
def test_parse_time_refuses_what_is_not_a_time(value):
    with pytest.raises(TrackFormatError, match="^t: "):
        parse_time(value, input_name="t")


def test_sort_fixes_orders_by_time_and_keeps_the_first_of_a_timestamp():
    fixes = [TrackFix(3, 3, 0), TrackFix(1, 1, 0), TrackFix(3, 9, 9), TrackFix(2, 2, 0)]
    kept, dropped = sort_fixes(fixes)
    assert [(f.t, f.lat) for f in kept] == [(1, 1), (2, 2), (3, 3)]
    assert dropped == 1


def test_detect_format_looks_at_content_not_names():
    assert detect_format("\ufeff  <?xml version='1.0'?>") == "gpx"
    assert detect_format("junk\n$GPRMC,1,2*00\n") == "nmea"
    assert detect_format("Time,Latitude,Longitude\n") == "csv"
    assert detect_format("a,b,c\n1,2,3\n") is None
