"""app.track_csv: reading CSV tracks; a bad row names its line and column (pure)."""

from __future__ import annotations

import pytest

from app.track_fixes import TrackFormatError
from app.tracks import parse_track
from tests.app.track_files import (
    csv_file,
    simulated_run,
)


def test_csv_epoch_seconds_and_iso_times_give_the_same_fixes():
    run = simulated_run()
    iso = parse_track(csv_file(run))
    epoch = parse_track(csv_file(run, epoch=True))
    assert [f.t for f in iso.fixes] == [f.t for f in epoch.fixes]


def test_csv_columns_in_any_order_with_aliases_and_optional_fields():
    text = b"lon,speed,latitude,timestamp\n115.298,0.5,-8.6265,2026-11-22T00:00:01Z\n"
    (fix,) = parse_track(text).fixes
    assert (fix.lat, fix.lon, fix.speed_mps, fix.heading_deg) == (-8.6265, 115.298, 0.5, None)


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
