"""Guidance: which clutch to pull.

``waypoint`` mode is the paper's: the distance to the next waypoint by the haversine formula
(algorithm 3), the bearing to it (equations 17–19), the heading error wrapped to ±180°
(algorithm 4), and a clutch command: straight while the error is within a tolerance, else the
clutch on the side to turn to. ``line`` mode is pure pursuit: aim at a point a look-ahead
distance further along the planned segment, which pulls the tractor back onto the line rather
than straight at the waypoint from wherever it happens to be.
"""

from __future__ import annotations

import math

from navigation.types import LEFT, RIGHT, STRAIGHT, SteerCommand

#: Mean Earth radius (IUGG) [m], for the haversine formula.
EARTH_RADIUS_M = 6_371_008.8


def haversine_m(lon1: float, lat1: float, lon2: float, lat2: float) -> float:
    """Great-circle distance between two WGS84 points (the paper's algorithm 3) [m].

    Examples
    --------
    >>> round(haversine_m(0.0, 0.0, 0.0, 1.0))     # one degree of latitude on the sphere
    111195
    """
    phi1 = math.radians(lat1)
    phi2 = math.radians(lat2)
    dphi = phi2 - phi1
    dlmb = math.radians(lon2 - lon1)
    a = math.sin(0.5 * dphi) ** 2 + math.cos(phi1) * math.cos(phi2) * math.sin(0.5 * dlmb) ** 2
    return 2.0 * EARTH_RADIUS_M * math.atan2(math.sqrt(a), math.sqrt(1.0 - a))


def bearing_deg(lon1: float, lat1: float, lon2: float, lat2: float) -> float:
    """Return the initial bearing from point 1 to 2 (the paper's eq. 17–19) [deg, 0–360).

    ``X = cos φ2 sin Δλ``, ``Y = cos φ1 sin φ2 − sin φ1 cos φ2 cos Δλ``, ``β = atan2(X, Y)``.

    Examples
    --------
    >>> round(bearing_deg(0.0, 0.0, 1.0, 0.0), 6)      # due east
    90.0
    >>> round(bearing_deg(0.0, 0.0, 0.0, -1.0), 6)     # due south
    180.0
    """
    phi1 = math.radians(lat1)
    phi2 = math.radians(lat2)
    dlmb = math.radians(lon2 - lon1)
    x = math.cos(phi2) * math.sin(dlmb)
    y = math.cos(phi1) * math.sin(phi2) - math.sin(phi1) * math.cos(phi2) * math.cos(dlmb)
    return math.degrees(math.atan2(x, y)) % 360.0


def heading_error_deg(target_deg: float, heading_deg: float) -> float:
    """Target minus heading, wrapped to [-180, 180) (the paper's algorithm 4) [deg].

    Positive means the target lies to the right (clockwise).

    Examples
    --------
    >>> heading_error_deg(10.0, 350.0)
    20.0
    >>> heading_error_deg(350.0, 10.0)
    -20.0
    >>> heading_error_deg(180.0, 0.0)
    -180.0
    """
    return (target_deg - heading_deg + 180.0) % 360.0 - 180.0


def clutch_for(error_deg: float, *, tolerance_deg: float) -> int:
    """Straight within the tolerance, else pull the clutch on the side to turn to.

    Pulling the right clutch stops the right wheel and turns the tractor right.

    Examples
    --------
    >>> [clutch_for(e, tolerance_deg=5.0) for e in (-30.0, 0.0, 4.9, 30.0)]
    [-1, 0, 0, 1]
    """
    if error_deg > tolerance_deg:
        return RIGHT
    if error_deg < -tolerance_deg:
        return LEFT
    return STRAIGHT


def waypoint_command(
    lon: float,
    lat: float,
    heading_deg: float,
    target_lon: float,
    target_lat: float,
    *,
    tolerance_deg: float,
) -> SteerCommand:
    """Steer toward the target waypoint (the paper's waypoint law).

    Parameters
    ----------
    lon, lat : float
        Estimated position, WGS84 [deg].
    heading_deg : float
        Estimated heading, clockwise from true north [deg].
    target_lon, target_lat : float
        The waypoint, WGS84 [deg].
    tolerance_deg : float
        Heading error within which the tractor drives straight [deg].

    Returns
    -------
    SteerCommand
    """
    return SteerCommand(
        *waypoint_law(lon, lat, heading_deg, target_lon, target_lat, tolerance_deg=tolerance_deg)
    )


def waypoint_law(
    lon: float,
    lat: float,
    heading_deg: float,
    target_lon: float,
    target_lat: float,
    *,
    tolerance_deg: float,
) -> tuple[int, float, float]:
    """:func:`waypoint_command` as ``(clutch, heading_error_deg, distance_m)``, for the 10 Hz loop.

    Examples
    --------
    >>> clutch, error, distance = waypoint_law(0.0, 0.0, 0.0, 0.001, 0.0, tolerance_deg=8.0)
    >>> clutch, round(error, 6), round(distance, 1)     # due east: turn right
    (1, 90.0, 111.2)
    """
    distance = haversine_m(lon, lat, target_lon, target_lat)
    error = heading_error_deg(bearing_deg(lon, lat, target_lon, target_lat), heading_deg)
    return clutch_for(error, tolerance_deg=tolerance_deg), error, distance


def segment_progress(
    x_m: float, y_m: float, ax_m: float, ay_m: float, bx_m: float, by_m: float
) -> tuple[float, float, float]:
    """Along-track distance, signed cross-track error and length of segment A→B [m].

    The cross-track error is positive when the point lies right of the segment's direction.

    Examples
    --------
    >>> segment_progress(1.0, 2.0, 0.0, 0.0, 0.0, 10.0)
    (2.0, 1.0, 10.0)
    """
    ux, uy, length = segment_axes(ax_m, ay_m, bx_m, by_m)
    if length == 0.0:
        return 0.0, 0.0, 0.0
    px = x_m - ax_m
    py = y_m - ay_m
    return px * ux + py * uy, px * uy - py * ux, length


def segment_axes(ax_m: float, ay_m: float, bx_m: float, by_m: float) -> tuple[float, float, float]:
    """Return the unit direction ``(ux, uy)`` and length [m] of A→B; ``(0, 0, 0)`` if none.

    A leg's constants, computed once per leg by the 10 Hz loop: the along-track distance of
    ``(x, y)`` is then ``(x - ax) * ux + (y - ay) * uy``, as :func:`segment_progress` has it.

    Examples
    --------
    >>> segment_axes(0.0, 0.0, 3.0, 4.0)
    (0.6, 0.8, 5.0)
    """
    dx = bx_m - ax_m
    dy = by_m - ay_m
    length = math.hypot(dx, dy)
    if length == 0.0:
        return 0.0, 0.0, 0.0
    return dx / length, dy / length, length


def pursuit_law(
    x_m: float,
    y_m: float,
    heading_rad: float,
    ax_m: float,
    ay_m: float,
    bx_m: float,
    by_m: float,
    along_m: float,
    length_m: float,
    *,
    lookahead_m: float,
    tolerance_deg: float,
) -> tuple[int, float, float]:
    """:func:`pure_pursuit_command` as ``(clutch, heading_error_deg, distance_m)``.

    Given the along-track distance and the segment's length (:func:`segment_progress`), which
    the 10 Hz loop has already computed for the waypoint test.

    Examples
    --------
    >>> clutch, error, distance = pursuit_law(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 10.0, 0.0, 10.0,
    ...                                       lookahead_m=2.0, tolerance_deg=3.0)
    >>> clutch, round(error, 1), round(distance, 3)
    (-1, -26.6, 10.05)
    """
    if length_m == 0.0:
        aim_x, aim_y = bx_m, by_m
    else:
        s = min(max(along_m, 0.0) + lookahead_m, length_m) / length_m
        aim_x = ax_m + s * (bx_m - ax_m)
        aim_y = ay_m + s * (by_m - ay_m)
    clutch, error = aim_law(x_m, y_m, heading_rad, aim_x, aim_y, tolerance_deg=tolerance_deg)
    return clutch, error, math.hypot(bx_m - x_m, by_m - y_m)


def aim_law(
    x_m: float,
    y_m: float,
    heading_rad: float,
    aim_x_m: float,
    aim_y_m: float,
    *,
    tolerance_deg: float,
) -> tuple[int, float]:
    """Steer toward an aim point: ``(clutch, heading_error_deg)``, for the 10 Hz loop.

    The step pursuit shares, along a segment (:func:`pursuit_law`) or along a curve of the
    plan (:func:`navigation.curves.aim_point`): for a tractor that can only drive straight or
    pivot, pursuing a point is steering toward it within a heading tolerance.

    Parameters
    ----------
    x_m, y_m, heading_rad : float
        Pose, local frame ([m], clockwise from true north [rad]).
    aim_x_m, aim_y_m : float
        The point pursued [m].
    tolerance_deg : float
        Heading error within which the tractor drives straight [deg].

    Examples
    --------
    >>> clutch, error = aim_law(0.0, 0.0, 0.0, 1.0, 1.0, tolerance_deg=3.0)
    >>> clutch, round(error, 6)                       # aim north-east: turn right
    (1, 45.0)
    """
    target_deg = math.degrees(math.atan2(aim_x_m - x_m, aim_y_m - y_m))
    error = heading_error_deg(target_deg, math.degrees(heading_rad))
    return clutch_for(error, tolerance_deg=tolerance_deg), error


def pure_pursuit_command(
    x_m: float,
    y_m: float,
    heading_rad: float,
    ax_m: float,
    ay_m: float,
    bx_m: float,
    by_m: float,
    *,
    lookahead_m: float,
    tolerance_deg: float,
) -> SteerCommand:
    """Line mode: aim at the point ``lookahead_m`` ahead along segment A→B (local frame).

    The aim point is the projection of the tractor on the segment moved ``lookahead_m``
    forward, clamped to B, so the tractor converges onto the line and then holds it. For a
    tractor that can only drive straight or pivot, pure pursuit reduces to steering toward
    this point with a heading tolerance.

    Parameters
    ----------
    x_m, y_m, heading_rad : float
        Estimated pose, local frame ([m], clockwise from true north [rad]).
    ax_m, ay_m, bx_m, by_m : float
        The planned segment, from the previous waypoint A to the target B [m].
    lookahead_m : float
        Look-ahead distance [m].
    tolerance_deg : float
        Heading error within which the tractor drives straight [deg].

    Returns
    -------
    SteerCommand

    Examples
    --------
    >>> cmd = pure_pursuit_command(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 10.0,
    ...                            lookahead_m=2.0, tolerance_deg=3.0)
    >>> cmd.clutch, round(cmd.heading_error_deg, 1)    # right of the line: turn left
    (-1, -26.6)
    """
    along, _, length = segment_progress(x_m, y_m, ax_m, ay_m, bx_m, by_m)
    return SteerCommand(
        *pursuit_law(
            x_m,
            y_m,
            heading_rad,
            ax_m,
            ay_m,
            bx_m,
            by_m,
            along,
            length,
            lookahead_m=lookahead_m,
            tolerance_deg=tolerance_deg,
        )
    )
