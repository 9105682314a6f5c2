"""Magnetic declination from the World Magnetic Model, and the paper's compass heading.

The paper's algorithm 2 turns the magnetometer's horizontal components into a heading and adds
the magnetic declination. The declination comes from the World Magnetic Model valid at the
date (pygeomag, with the coefficient files it ships): WMM2020 for 2020.0–2025.0 (the paper's
trial, 2021, falls here), WMM2025 for 2025.0–2030.0. A date outside both is an error, not an
extrapolation. The paper's equation 20 is the *sun's* declination, which has nothing to do
with a compass, and is not used.
"""

from __future__ import annotations

import datetime as dt
import math
from functools import lru_cache

from pygeomag import GeoMag

from navigation.types import NavigationError

#: The World Magnetic Models and the coefficient files pygeomag 1.1.0 ships for them, relative
#: to the pygeomag package, with the years each is valid for: (name, file, first, end).
WMM_MODELS: tuple[tuple[str, str, float, float], ...] = (
    ("WMM2020", "wmm/WMM_2020.COF", 2020.0, 2025.0),
    ("WMM2025", "wmm/WMM_2025.COF", 2025.0, 2030.0),
)
WMM_2025_FILE = "wmm/WMM_2025.COF"


@lru_cache(maxsize=4)
def _geomag(coefficients_file: str) -> GeoMag:
    return GeoMag(coefficients_file=coefficients_file)


def wmm_model_for(year: float) -> tuple[str, str]:
    """Name and coefficient file of the World Magnetic Model valid at decimal ``year``.

    A model's life span is ``[first, end)``, except that the last one includes its end.

    Raises
    ------
    NavigationError
        If no shipped model covers ``year``.

    Examples
    --------
    >>> wmm_model_for(2021.08)[0], wmm_model_for(2025.0)[0], wmm_model_for(2030.0)[0]
    ('WMM2020', 'WMM2025', 'WMM2025')
    """
    for name, path, first, end in WMM_MODELS:
        if first <= year < end or (year == end and path == WMM_MODELS[-1][1]):
            return name, path
    spans = ", ".join(f"{n} {a:.0f}–{b:.0f}" for n, _, a, b in WMM_MODELS)
    raise NavigationError(
        "date",
        f"{year:.2f} is outside every World Magnetic Model tillpath has ({spans}); "
        "the declination cannot be computed for it",
    )


def decimal_year(date: dt.date) -> float:
    """Return ``date`` as a decimal year (1 January = ``year.0``).

    Examples
    --------
    >>> decimal_year(dt.date(2025, 1, 1))
    2025.0
    >>> round(decimal_year(dt.date(2026, 7, 2)), 4)
    2026.4986
    """
    start = dt.date(date.year, 1, 1)
    days = (dt.date(date.year + 1, 1, 1) - start).days
    return date.year + (date - start).days / days


def magnetic_declination_deg(
    lon: float, lat: float, *, date: dt.date | float, altitude_km: float = 0.0
) -> float:
    """Magnetic declination (east positive) from the World Magnetic Model of the date [deg].

    Parameters
    ----------
    lon, lat : float
        WGS84 degrees.
    date : datetime.date or float
        The date, or a decimal year, within 2020.0–2030.0 (WMM2020, then WMM2025).
    altitude_km : float
        Height above the WGS84 ellipsoid [km].

    Raises
    ------
    NavigationError
        If no model covers the date, or the position is invalid.

    Examples
    --------
    >>> round(magnetic_declination_deg(115.298, -8.6265, date=dt.date(2026, 1, 1)), 1)
    0.8
    """
    year = decimal_year(date) if isinstance(date, dt.date) else float(date)
    if not math.isfinite(year):
        raise NavigationError("date", "must be a finite decimal year")
    _, coefficients = wmm_model_for(year)
    if not (math.isfinite(lon) and math.isfinite(lat) and -90.0 <= lat <= 90.0):
        raise NavigationError("position", f"({lon}, {lat}) is not a longitude/latitude")
    lon = (lon + 180.0) % 360.0 - 180.0
    result = _geomag(coefficients).calculate(glat=lat, glon=lon, alt=altitude_km, time=year)
    return float(result.d)


def compass_heading_deg(mag_x: float, mag_y: float, declination_deg: float) -> float:
    """Return the true heading from the magnetometer (the paper's algorithm 2) [deg, 0–360).

    ``atan2(mag_y, mag_x)`` is the magnetic heading; adding the declination (east positive)
    turns it into a heading from true north, then it is wrapped to [0, 360).

    Examples
    --------
    >>> compass_heading_deg(0.0, 1.0, 2.0)     # magnetic east, 2° east declination
    92.0
    >>> compass_heading_deg(1.0, -0.01, 0.5) > 359.0
    True
    """
    return (math.degrees(math.atan2(mag_y, mag_x)) + declination_deg) % 360.0
