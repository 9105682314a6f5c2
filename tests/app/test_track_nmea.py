"""app.track_nmea: reading NMEA 0183 logs: dates, checksums, fix quality (pure)."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from app.track_fixes import TrackFormatError
from app.tracks import parse_track
from tests.app.track_files import (
    RUN_START,
    nmea_file,
    nmea_lines,
    sentence,
    simulated_run,
)


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
