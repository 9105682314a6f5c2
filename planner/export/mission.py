"""Missions an autopilot loads: QGC WPL 110 (``.waypoints``) and QGroundControl ``.plan``.

Both carry the same items (product.md §4), for ArduPilot Rover and PX4 ground vehicles:

0. the home position: the plan's start, else its first waypoint;
1. ``MAV_CMD_DO_CHANGE_SPEED`` (178): ground speed ``speed_mps``;
2. … one ``MAV_CMD_NAV_WAYPOINT`` (16) per waypoint in driving order, frame 3
   (``MAV_FRAME_GLOBAL_RELATIVE_ALT``), altitude 0.

The ``.waypoints`` file is the plain-text format of mavlink.io's *File Formats* page: a
``QGC WPL 110`` line, then one tab-separated line per item (index, current, frame, command,
param1–4, latitude, longitude, altitude, autocontinue); the home line is frame 0
(``MAV_FRAME_GLOBAL``, absolute), as Mission Planner writes it. The ``.plan`` is
QGroundControl's JSON plan file: the items as SimpleItems (``firmwareType`` 3 ArduPilot,
``vehicleType`` 10 ground rover), ``plannedHomePosition`` at the start, the field's boundary as
an inclusion polygon geofence and each hole as an exclusion polygon. QGroundControl lists
polygon vertices as ``[lat, lon]`` without repeating the first.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

from shapely import LinearRing

from planner.types import DEFAULT_SPEED_MPS, CoveragePlan

MAV_CMD_NAV_WAYPOINT: Final = 16
MAV_CMD_DO_CHANGE_SPEED: Final = 178
MAV_FRAME_GLOBAL: Final = 0
MAV_FRAME_GLOBAL_RELATIVE_ALT: Final = 3
#: MAV_AUTOPILOT_ARDUPILOTMEGA and MAV_TYPE_GROUND_ROVER.
MAV_AUTOPILOT_ARDUPILOTMEGA: Final = 3
MAV_TYPE_GROUND_ROVER: Final = 10
#: DO_CHANGE_SPEED param1: 1 = ground speed.
SPEED_TYPE_GROUND: Final = 1


@dataclass(frozen=True, slots=True)
class MissionItem:
    """One MAVLink mission item (``MISSION_ITEM`` fields, lat/lon in degrees)."""

    frame: int
    command: int
    params: tuple[float, float, float, float]
    lat: float
    lon: float
    alt: float = 0.0


def mission_items(plan: CoveragePlan, *, speed_mps: float = DEFAULT_SPEED_MPS) -> list[MissionItem]:
    """Return the mission: home, the speed command, then a waypoint item per waypoint.

    Parameters
    ----------
    plan : CoveragePlan
        With at least one waypoint.
    speed_mps : float
        Ground speed for ``MAV_CMD_DO_CHANGE_SPEED`` [m/s].
    """
    home = next((w for w in plan.waypoints if w.role == "start"), plan.waypoints[0])
    items = [
        MissionItem(MAV_FRAME_GLOBAL, MAV_CMD_NAV_WAYPOINT, (0, 0, 0, 0), home.lat, home.lon),
        MissionItem(
            MAV_FRAME_GLOBAL_RELATIVE_ALT,
            MAV_CMD_DO_CHANGE_SPEED,
            (SPEED_TYPE_GROUND, float(speed_mps), -1, 0),
            0.0,
            0.0,
        ),
    ]
    items.extend(
        MissionItem(MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_CMD_NAV_WAYPOINT, (0, 0, 0, 0), w.lat, w.lon)
        for w in plan.waypoints
    )
    return items


def plan_to_qgc_wpl(plan: CoveragePlan, *, speed_mps: float = DEFAULT_SPEED_MPS) -> str:
    """Return the mission as QGC WPL 110 text (``.waypoints``), tab-separated.

    Examples
    --------
    >>> from planner.types import PlanStats, Waypoint
    >>> from shapely import box
    >>> stats = PlanStats(0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0)
    >>> start = Waypoint(0, 115.5, -8.5, "start", None)
    >>> plan = CoveragePlan(box(0, 0, 1, 1), (start,), (), stats, 4.0)
    >>> print(plan_to_qgc_wpl(plan, speed_mps=0.5).expandtabs(1))
    QGC WPL 110
    0 1 0 16 0 0 0 0 -8.5 115.5 0 1
    1 0 3 178 1 0.5 -1 0 0 0 0 1
    2 0 3 16 0 0 0 0 -8.5 115.5 0 1
    <BLANKLINE>
    """
    lines = ["QGC WPL 110"]
    for index, item in enumerate(mission_items(plan, speed_mps=speed_mps)):
        values = [
            index,
            1 if index == 0 else 0,
            item.frame,
            item.command,
            *(_number(p) for p in item.params),
            _number(item.lat),
            _number(item.lon),
            _number(item.alt),
            1,
        ]
        lines.append("\t".join(str(v) for v in values))
    return "\n".join(lines) + "\n"


def plan_to_qgc_plan(plan: CoveragePlan, *, speed_mps: float = DEFAULT_SPEED_MPS) -> dict[str, Any]:
    """Return the mission as a QGroundControl ``.plan`` object (``json.dumps`` it).

    The geofence holds the field's boundary (inclusion) and each hole (exclusion).
    """
    items = mission_items(plan, speed_mps=speed_mps)
    home = items[0]
    simple_items = [
        {
            "AMSLAltAboveTerrain": None,
            "Altitude": item.alt,
            "AltitudeMode": 1,
            "autoContinue": True,
            "command": item.command,
            "doJumpId": number,
            "frame": item.frame,
            "params": [*item.params, item.lat, item.lon, item.alt],
            "type": "SimpleItem",
        }
        for number, item in enumerate(items[1:], start=1)
    ]
    polygons = [{"inclusion": True, "polygon": _latlon(plan.field_lonlat.exterior), "version": 1}]
    polygons.extend(
        {"inclusion": False, "polygon": _latlon(hole), "version": 1}
        for hole in plan.field_lonlat.interiors
    )
    return {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": polygons, "version": 2},
        "groundStation": "tillpath",
        "mission": {
            "cruiseSpeed": float(speed_mps),
            "firmwareType": MAV_AUTOPILOT_ARDUPILOTMEGA,
            "globalPlanAltitudeMode": 1,
            "hoverSpeed": float(speed_mps),
            "items": simple_items,
            "plannedHomePosition": [home.lat, home.lon, 0],
            "vehicleType": MAV_TYPE_GROUND_ROVER,
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }


def _latlon(ring: LinearRing) -> list[list[float]]:
    coords = list(ring.coords)
    if len(coords) > 1 and coords[0] == coords[-1]:
        coords = coords[:-1]
    return [[float(lat), float(lon)] for lon, lat, *_ in coords]


def _number(value: float) -> str:
    """Full precision, integers without a decimal point (``0``, ``-8.62649238``)."""
    number = float(value)
    return str(int(number)) if number.is_integer() else repr(number)
