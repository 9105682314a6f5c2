"""app.tracks: a track file's format told from its content, read back whole (pure)."""

from __future__ import annotations

import numpy as np
import pytest

from app.track_fixes import TrackFix, TrackFormatError
from app.tracks import detect_format, parse_track
from tests.app.track_files import (
    RUN_START,
    csv_file,
    gpx_file,
    nmea_file,
    simulated_run,
)


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


@pytest.mark.parametrize("data", [b"", b"hello world\n", b"\x89PNG\r\n\x1a\n\x00\x00"])
def test_unknown_format_is_refused(data: bytes):
    with pytest.raises(TrackFormatError, match="^file: is not a track file tillpath can read"):
        parse_track(data)


def test_detect_format_looks_at_content_not_names():
    assert detect_format("\ufeff  <?xml version='1.0'?>") == "gpx"
    assert detect_format("junk\n$GPRMC,1,2*00\n") == "nmea"
    assert detect_format("Time,Latitude,Longitude\n") == "csv"
    assert detect_format("a,b,c\n1,2,3\n") is None
