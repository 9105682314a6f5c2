"""Magnetic declination from the World Magnetic Model, and the paper's compass heading.

The paper's algorithm 2 turns the magnetometer's horizontal components into a heading and adds
the magnetic declination. The declination comes from the World Magnetic Model 2025 (pygeomag,
with the WMM-2025 coefficient file it ships): the paper's equation 20 is the *sun's*
declination, which has nothing to do with a compass, and is not used.
"""

from __future__ import annotations

import datetime as dt
import math
from functools import lru_cache

from pygeomag import GeoMag

from navigation.types import NavigationError

#: The coefficient file pygeomag ships for WMM-2025 (valid 2025.0 to 2030.0), relative to the
#: pygeomag package. Named explicitly rather than relying on pygeomag's default file.
WMM_2025_FILE = "wmm/WMM_2025.COF"


@lru_cache(maxsize=1)
def _wmm_2025() -> GeoMag:
    return GeoMag(coefficients_file=WMM_2025_FILE)


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
    """Magnetic declination (east positive) from WMM-2025 [deg].

    Parameters
    ----------
    lon, lat : float
        WGS84 degrees.
    date : datetime.date or float
        The date, or a decimal year, within the model's life span 2025.0–2030.0.
    altitude_km : float
        Height above the WGS84 ellipsoid [km].

    Raises
    ------
    NavigationError
        If the date is outside WMM-2025's life span or the position is invalid.

    Examples
    --------
    >>> round(magnetic_declination_deg(115.298, -8.6265, date=dt.date(2026, 1, 1)), 1)
    0.8
    """
    year = decimal_year(date) if isinstance(date, dt.date) else float(date)
    if not (2025.0 <= year <= 2030.0):
        raise NavigationError(
            "date", f"{year:.2f} is outside the World Magnetic Model 2025's life span (2025–2030)"
        )
    if not (math.isfinite(lon) and math.isfinite(lat) and -90.0 <= lat <= 90.0):
        raise NavigationError("position", f"({lon}, {lat}) is not a longitude/latitude")
    lon = (lon + 180.0) % 360.0 - 180.0
    result = _wmm_2025().calculate(glat=lat, glon=lon, alt=altitude_km, time=year)
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
