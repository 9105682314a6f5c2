"""app.track_fixes: times read alike, fixes sorted with one per timestamp (pure)."""

from __future__ import annotations

import pytest

from app.track_fixes import TrackFix, TrackFormatError, parse_time, sort_fixes


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
