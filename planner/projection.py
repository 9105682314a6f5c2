"""Local metric frames: the only place the planner talks to pyproj.

A field is planned in a frame tied to its centroid: the UTM zone of the centroid (the zone
computed from the longitude, not queried from the PROJ database, which costs ~60 ms), shifted
to the centroid, rotated so that +y is *true* north, and scaled so that one unit is one true
metre there. So line angles are true-north headings and interval, lengths and areas are true
metres, even at a zone edge where UTM's own scale is 0.1 % off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TypeVar

import numpy as np
import numpy.typing as npt
import shapely
from pyproj import Geod, Transformer
from shapely import Polygon
from shapely.geometry.base import BaseGeometry

from planner.errors import InvalidFieldError

GeometryT = TypeVar("GeometryT", bound=BaseGeometry)
FloatArray = npt.NDArray[np.float64]

WGS84 = Geod(ellps="WGS84")
#: UTM is defined from 80°S to 84°N; fields beyond need a polar projection.
UTM_LAT_RANGE_DEG = (-80.0, 84.0)
#: Step north used to measure the grid's convergence and scale at the origin [deg].
_PROBE_DEG = 1e-4


def utm_epsg(lon: float, lat: float) -> int:
    """Return the EPSG code of the UTM zone that contains ``(lon, lat)``.

    Follows the standard zone layout, including the wider zone 32V over western Norway and
    the Svalbard zones 31X, 33X, 35X and 37X.

    Examples
    --------
    >>> utm_epsg(115.298, -8.6265)   # Bali: zone 50 south
    32750
    >>> utm_epsg(5.5, 60.0)          # Bergen: zone 32V, not 31
    32632
    """
    if not (UTM_LAT_RANGE_DEG[0] <= lat <= UTM_LAT_RANGE_DEG[1]):
        raise InvalidFieldError(
            "field",
            f"latitude {lat:.5f} is outside the UTM range (80°S to 84°N) that tillpath plans in",
        )
    lon = ((lon + 180.0) % 360.0) - 180.0
    zone = min(int((lon + 180.0) // 6.0) + 1, 60)
    if 56.0 <= lat < 64.0 and 3.0 <= lon < 12.0:
        zone = 32
    elif 72.0 <= lat <= 84.0 and 0.0 <= lon < 42.0:
        zone = 31 if lon < 9.0 else 33 if lon < 21.0 else 35 if lon < 33.0 else 37
    return (32600 if lat >= 0.0 else 32700) + zone


@lru_cache(maxsize=64)
def _utm_transformers(epsg: int) -> tuple[Transformer, Transformer]:
    # Creating a Transformer costs 0.1–3 ms; one pair per zone is reused (pyproj's advice).
    forward = Transformer.from_crs("EPSG:4326", f"EPSG:{epsg}", always_xy=True)
    inverse = Transformer.from_crs(f"EPSG:{epsg}", "EPSG:4326", always_xy=True)
    return forward, inverse


@dataclass(frozen=True, slots=True)
class LocalFrame:
    """A true-north, true-scale metric frame around an origin.

    Local ``x`` points east and ``y`` true north, in metres, with ``(0, 0)`` at the origin.

    Attributes
    ----------
    epsg : int
        The UTM zone the frame is built on.
    origin_lon, origin_lat : float
        WGS84 origin [deg].
    origin_e, origin_n : float
        UTM easting and northing of the origin [m].
    cos_g, sin_g : float
        Rotation from grid to true north (cosine and sine of the grid convergence).
    scale : float
        UTM point scale factor at the origin: grid metres per true metre.
    """

    epsg: int
    origin_lon: float
    origin_lat: float
    origin_e: float
    origin_n: float
    cos_g: float
    sin_g: float
    scale: float

    def to_local_xy(self, lon: npt.ArrayLike, lat: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Project WGS84 ``lon, lat`` arrays [deg] to local ``x, y`` [m]."""
        forward, _ = _utm_transformers(self.epsg)
        e, n = forward.transform(np.asarray(lon, dtype=float), np.asarray(lat, dtype=float))
        de = (np.asarray(e) - self.origin_e) / self.scale
        dn = (np.asarray(n) - self.origin_n) / self.scale
        return de * self.cos_g - dn * self.sin_g, de * self.sin_g + dn * self.cos_g

    def to_lonlat_xy(self, x: npt.ArrayLike, y: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Unproject local ``x, y`` arrays [m] to WGS84 ``lon, lat`` [deg]."""
        _, inverse = _utm_transformers(self.epsg)
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        de = x * self.cos_g + y * self.sin_g
        dn = -x * self.sin_g + y * self.cos_g
        lon, lat = inverse.transform(
            de * self.scale + self.origin_e, dn * self.scale + self.origin_n
        )
        return np.asarray(lon, dtype=float), np.asarray(lat, dtype=float)

    # shapely's stubs know only the interleaved form of transform's callback.

    def to_local(self, geometry_lonlat: GeometryT) -> GeometryT:
        """Return ``geometry_lonlat`` (WGS84) in this local frame [m]."""
        return shapely.transform(
            geometry_lonlat,
            self.to_local_xy,  # type: ignore[arg-type]
            interleaved=False,
        )

    def to_lonlat(self, geometry_local: GeometryT) -> GeometryT:
        """Return ``geometry_local`` [m] in WGS84 ``(lon, lat)``."""
        return shapely.transform(
            geometry_local,
            self.to_lonlat_xy,  # type: ignore[arg-type]
            interleaved=False,
        )


def local_frame(lon: float, lat: float) -> LocalFrame:
    """Build the local frame whose origin is ``(lon, lat)``.

    Parameters
    ----------
    lon, lat : float
        Origin, WGS84 degrees.

    Returns
    -------
    LocalFrame

    Examples
    --------
    >>> frame = local_frame(115.298, -8.6265)
    >>> lon, lat, _ = WGS84.fwd(115.298, -8.6265, 90.0, 100.0)   # 100 m due east
    >>> [round(float(v), 4) for v in frame.to_local_xy(lon, lat)]
    [100.0, 0.0]
    """
    epsg = utm_epsg(lon, lat)
    forward, _ = _utm_transformers(epsg)
    # Measure where true north points on the grid, and the grid scale, at the origin.
    e, n = forward.transform([lon, lon], [lat, lat + _PROBE_DEG])
    de, dn = e[1] - e[0], n[1] - n[0]
    grid_m = math.hypot(de, dn)
    _, _, true_m = WGS84.inv(lon, lat, lon, lat + _PROBE_DEG)
    return LocalFrame(
        epsg=epsg,
        origin_lon=float(lon),
        origin_lat=float(lat),
        origin_e=float(e[0]),
        origin_n=float(n[0]),
        # Rotating the grid vector (de, dn) by this onto (0, +1) makes +y true north.
        cos_g=dn / grid_m,
        sin_g=de / grid_m,
        scale=grid_m / true_m,
    )


def field_frame(field_lonlat: BaseGeometry) -> LocalFrame:
    """Return the local frame centred on the centroid of ``field_lonlat``'s bounding box.

    The box centre (not the area centroid) is used: it is cheaper, and any point inside the
    field keeps projection distortion far below the 1 cm tolerance.
    """
    min_lon, min_lat, max_lon, max_lat = field_lonlat.bounds
    return local_frame((min_lon + max_lon) / 2.0, (min_lat + max_lat) / 2.0)


def geodesic_area_m2(polygon_lonlat: BaseGeometry) -> float:
    """Return the area of a WGS84 polygon on the ellipsoid [m²] (holes subtracted).

    pyproj signs each ring's area by its orientation, so the polygon is oriented first
    (exterior counter-clockwise, holes clockwise) for the holes to be subtracted.
    """
    oriented = shapely.orient_polygons(polygon_lonlat)
    if not isinstance(oriented, Polygon):
        area, _ = WGS84.geometry_area_perimeter(oriented)
        return abs(float(area))
    # geometry_area_perimeter's own sum (exterior, then each hole), on the rings' coordinate
    # arrays: it reaches a polygon through an exception and copies each ring's .xy.
    area = 0.0
    for ring in (oriented.exterior, *oriented.interiors):
        lonlat = shapely.get_coordinates(ring)
        ring_area, _ = WGS84.polygon_area_perimeter(lonlat[:, 0], lonlat[:, 1])
        area += ring_area
    return abs(float(area))


@lru_cache(maxsize=16)
def _to_lonlat_transformer(crs: str) -> Transformer:
    return Transformer.from_crs(crs, "EPSG:4326", always_xy=True)


def reproject_to_lonlat(geometry: GeometryT, crs: str) -> GeometryT:
    """Return ``geometry`` from the CRS ``crs`` (WKT, ``EPSG:n`` …) in WGS84 ``(lon, lat)``.

    The import readers call this for files that declare another CRS (a Shapefile's ``.prj``,
    a GeoPackage layer's SRS). One cached ``Transformer`` per CRS.

    Raises
    ------
    InvalidFieldError
        If ``crs`` is not a CRS pyproj knows, or a coordinate does not transform.
    """
    from pyproj.exceptions import CRSError

    try:
        transformer = _to_lonlat_transformer(crs)
    except CRSError as exc:
        raise InvalidFieldError("crs", f"is not a coordinate system pyproj knows ({exc})") from None
    result = shapely.transform(
        geometry,
        transformer.transform,  # type: ignore[arg-type]
        interleaved=False,
    )
    if not np.isfinite(shapely.get_coordinates(result)).all():
        raise InvalidFieldError("crs", "some coordinates do not transform to longitude/latitude")
    return result


def is_lonlat_crs(crs: str | None) -> bool:
    """Tell whether ``crs`` is WGS84 longitude/latitude (None counts as WGS84, as in GeoJSON).

    Examples
    --------
    >>> is_lonlat_crs("EPSG:4326"), is_lonlat_crs("OGC:CRS84"), is_lonlat_crs("EPSG:32750")
    (True, True, False)
    """
    if crs is None:
        return True
    text = crs.strip().upper()
    return text in ("EPSG:4326", "OGC:CRS84", "CRS84", "URN:OGC:DEF:CRS:OGC:1.3:CRS84") or (
        text.startswith("URN:OGC:DEF:CRS:EPSG:") and text.endswith(":4326")
    )
