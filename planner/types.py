"""Value types shared by the planner stages, the exporters and their callers.

Coordinates here are WGS84 ``(lon, lat)`` in degrees: these types are what leaves the planner.
Local metric geometry stays inside the stage modules.
"""

from __future__ import annotations

import itertools
import operator
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, fields
from typing import Any, Literal, TypeVar, overload

from shapely import Polygon

Objective = Literal["shortest_path", "fewest_lines"]
WaypointRole = Literal["start", "line_start", "line_end", "turn", "headland", "finish"]
SegmentKind = Literal["transit", "line", "turn", "headland", "round"]
Pattern = Literal["boustrophedon", "snake", "spiral"]
VehiclePreset = Literal["hand_tractor", "paper_g1000", "small_tractor", "rover"]

OBJECTIVES: tuple[Objective, ...] = ("shortest_path", "fewest_lines")
PATTERNS: tuple[Pattern, ...] = ("boustrophedon", "snake", "spiral")

_Item = TypeVar("_Item")

#: The paper's tractor (Quick G1000) works at 0.56 m/s.
DEFAULT_SPEED_MPS = 0.56
#: Track width of a walk-behind tractor [m]: it pivots about one braked wheel.
DEFAULT_TRACK_WIDTH_M = 1.8


@dataclass(frozen=True, slots=True)
class Machine:
    """The tractor and implement as the planner sees them.

    Attributes
    ----------
    working_width_m : float
        Effective width of the puddler [m]: the interval between tillage lines.
    speed_mps : float
        Working speed [m/s], for time estimates.
    track_width_m : float
        Distance between the wheels [m]. A walk-behind tractor turns by pulling one clutch, so
        it pivots about that wheel at ``speed_mps / track_width_m`` rad/s.
    """

    working_width_m: float
    speed_mps: float = DEFAULT_SPEED_MPS
    track_width_m: float = DEFAULT_TRACK_WIDTH_M


@dataclass(frozen=True, slots=True)
class Vehicle:
    """The machine that drives the path (product.md §3a; Fields2Cover's ``Robot``).

    Presets and their sources live in :mod:`planner.vehicles`; this is only the value type.

    Attributes
    ----------
    preset : str
        Name of the preset the figures started from (overrides may have changed them).
    width_m : float
        Width of the body, implement included [m]: the path buffered by half of it stays inside
        the field (R1).
    length_m : float
        Length of the body, implement included [m].
    track_m : float
        Distance between the wheels [m]. A vehicle with ``min_turn_radius_m`` 0 pivots about one
        stopped wheel, its axle centre on a circle of radius ``track_m / 2``.
    min_turn_radius_m : float
        Smallest radius the axle centre can drive [m]; 0 for a vehicle that pivots.
    can_reverse : bool
        Whether turns may drive backwards (Reeds–Shepp instead of Dubins).
    turn_rate_dps : float
        Yaw rate while turning [°/s], for time estimates and the simulator.
    """

    preset: str
    width_m: float
    length_m: float
    track_m: float
    min_turn_radius_m: float
    can_reverse: bool
    turn_rate_dps: float


@dataclass(frozen=True, slots=True)
class Waypoint:
    """One point of the route, in driving order (the paper's p_s, p_0 … p_n, p_f).

    Attributes
    ----------
    seq : int
        Position in the route, from 0.
    lon, lat : float
        WGS84 degrees.
    role : str
        ``start``, ``line_start``, ``line_end``, ``turn``, ``headland`` or ``finish``.
    line : int or None
        Index of the tillage line the point begins or ends, else None.
    """

    seq: int
    lon: float
    lat: float
    role: WaypointRole
    line: int | None


class _MadeOnAccess(Sequence[_Item]):
    """A sequence whose items are made when they are read, from columns a subclass holds.

    Subclasses give :meth:`__len__`, :meth:`_item` (make item ``i``) and :meth:`columns`
    (what it holds, for equality and pickling); reading by index, slice or iteration,
    comparing with any sequence of the same items, hashing and printing come from here.
    """

    __slots__ = ()

    def _item(self, i: int) -> _Item:
        raise NotImplementedError

    def columns(self) -> tuple[Any, ...]:
        """Return what the sequence holds, its items made from it (do not modify it)."""
        raise NotImplementedError

    @overload
    def __getitem__(self, index: int) -> _Item: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[_Item, ...]: ...

    def __getitem__(self, index: int | slice) -> _Item | tuple[_Item, ...]:
        """Return one item, or a tuple of them for a slice."""
        if isinstance(index, slice):
            return tuple(map(self._item, range(*index.indices(len(self)))))
        i = operator.index(index)
        if i < 0:
            i += len(self)
        if not 0 <= i < len(self):
            raise IndexError(f"{type(self).__name__} index out of range")
        return self._item(i)

    def __iter__(self) -> Iterator[_Item]:
        """Make the items in order."""
        return map(self._item, range(len(self)))

    def __eq__(self, other: object) -> bool:
        """Equal to any sequence of the same items."""
        if type(other) is type(self):
            assert isinstance(other, _MadeOnAccess)
            if self.columns() == other.columns():
                return True  # the same columns make the same items, without making them
        if isinstance(other, Sequence) and not isinstance(other, str | bytes):
            return len(other) == len(self) and all(a == b for a, b in zip(self, other, strict=True))
        return NotImplemented

    def __hash__(self) -> int:
        """Hash as the tuple of the items would."""
        return hash(tuple(self))

    def __repr__(self) -> str:
        """Show the items as a tuple would."""
        return f"{type(self).__name__}({tuple(self)!r})"

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle the columns (plans cross process boundaries in batch planning)."""
        return (type(self), self.columns())


class Waypoints(_MadeOnAccess[Waypoint]):
    """The route's waypoints in driving order, made on access from plain lists.

    A plan of a large field with curved turns has some 50,000 waypoints; making every
    :class:`Waypoint` up front took longer than planning. This sequence holds the columns
    and makes each waypoint when it is read (by index, slice or iteration); it compares
    equal to any sequence of the same waypoints, a tuple included.

    Parameters
    ----------
    lon, lat : list of float
        WGS84 degrees of each point.
    roles : list of str
    lines : list of int or None

    Examples
    --------
    >>> route = Waypoints([115.3, 115.4], [-8.6, -8.7], ["line_start", "line_end"], [0, 0])
    >>> len(route), route[-1]
    (2, Waypoint(seq=1, lon=115.4, lat=-8.7, role='line_end', line=0))
    >>> route == (Waypoint(0, 115.3, -8.6, "line_start", 0), route[1])
    True
    """

    __slots__ = ("_lat", "_lines", "_lon", "_roles")

    def __init__(
        self,
        lon: list[float],
        lat: list[float],
        roles: list[WaypointRole],
        lines: list[int | None],
    ) -> None:
        if not len(lon) == len(lat) == len(roles) == len(lines):
            raise ValueError("waypoint columns differ in length")
        self._lon, self._lat, self._roles, self._lines = lon, lat, roles, lines

    def __len__(self) -> int:
        """Return the number of waypoints."""
        return len(self._lon)

    def _item(self, i: int) -> Waypoint:
        return Waypoint(i, self._lon[i], self._lat[i], self._roles[i], self._lines[i])

    def __iter__(self) -> Iterator[Waypoint]:
        """Make the waypoints in order (all at once: the export of a large plan reads all)."""
        columns = (range(len(self)), self._lon, self._lat, self._roles, self._lines)
        return itertools.starmap(Waypoint, zip(*columns, strict=True))

    def columns(self) -> tuple[list[float], list[float], list[WaypointRole], list[int | None]]:
        """Return the columns ``(lon, lat, roles, lines)`` as held (do not modify them).

        For writers that need every waypoint's fields (GeoJSON): no :class:`Waypoint` made.
        """
        return self._lon, self._lat, self._roles, self._lines


@dataclass(frozen=True, slots=True)
class PathSegment:
    """A piece of the route between waypoints, with what the tractor does on it.

    Attributes
    ----------
    kind : str
        ``transit`` (start or finish leg), ``line`` (tilling), ``turn`` (between lines or
        cells) or ``headland`` (a pass around the boundary).
    index : int or None
        Line index for ``line``, pass index for ``headland``, else None.
    lonlat : tuple of (float, float)
        The segment's vertices, WGS84 ``(lon, lat)``.
    """

    kind: SegmentKind
    index: int | None
    lonlat: tuple[tuple[float, float], ...]


class PathSegments(_MadeOnAccess[PathSegment]):
    """The route's segments in driving order, made on access from the waypoint columns.

    Like :class:`Waypoints`: a large field's plan has thousands of segments of some 50,000
    points, and making their point tuples up front took a third of the planning time. Each
    segment is ``(kind, index, first, last)`` over the columns (its points are the waypoints
    ``first … last``); it compares equal to any sequence of the same segments.

    Examples
    --------
    >>> segments = PathSegments([1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [("line", 0, 0, 1),
    ...                                                          ("turn", None, 1, 2)])
    >>> len(segments), segments[1]
    (2, PathSegment(kind='turn', index=None, lonlat=((2.0, 5.0), (3.0, 6.0))))
    >>> segments == (PathSegment("line", 0, ((1.0, 4.0), (2.0, 5.0))), segments[1])
    True
    """

    __slots__ = ("_bounds", "_lat", "_lon")

    def __init__(
        self,
        lon: list[float],
        lat: list[float],
        bounds: list[tuple[SegmentKind, int | None, int, int]],
    ) -> None:
        self._lon, self._lat, self._bounds = lon, lat, bounds

    def __len__(self) -> int:
        """Return the number of segments."""
        return len(self._bounds)

    def _item(self, i: int) -> PathSegment:
        kind, line, first, last = self._bounds[i]
        points = zip(self._lon[first : last + 1], self._lat[first : last + 1], strict=True)
        return PathSegment(kind, line, tuple(points))

    def columns(
        self,
    ) -> tuple[list[float], list[float], list[tuple[SegmentKind, int | None, int, int]]]:
        """Return ``(lon, lat, bounds)`` as held: each segment is ``(kind, index, first, last)``."""
        return self._lon, self._lat, self._bounds


@dataclass(frozen=True, slots=True)
class PlanStats:
    """The figures of a plan (product.md §3, "Output").

    ``coverage_given_up_pp`` is how far the chosen heading's coverage is below the best
    candidate heading's, in percentage points (R5 allows at most 0.2); 0 when none was given up.
    """

    area_m2: float
    line_count: int
    waypoint_count: int
    working_length_m: float
    turn_length_m: float
    transit_length_m: float
    path_length_m: float
    coverage_ratio: float
    angle_deg: float
    estimated_time_s: float
    planning_ms: float
    coverage_given_up_pp: float = 0.0
    #: Working width of the implement [m]: what the coverage is measured with (R4).
    implement_width_m: float | None = None
    #: Implement width minus interval [m]: > 0 the passes overlap, < 0 strips are left.
    overlap_m: float | None = None
    #: The vehicle the plan is for: its preset and figures (product.md §3a).
    vehicle: dict[str, Any] | None = None

    def as_dict(self) -> dict[str, Any]:
        """Return the figures as a plain dict, in declaration order (the vehicle's copied).

        The same as :func:`dataclasses.asdict`, without its recursive deep copy of every
        number (a plan preview calls this on every request).
        """
        figures = {name: getattr(self, name) for name in _PLAN_STATS_FIELDS}
        if self.vehicle is not None:
            figures["vehicle"] = dict(self.vehicle)
        return figures


_PLAN_STATS_FIELDS = tuple(f.name for f in fields(PlanStats))


def vehicle_dict(vehicle: Vehicle) -> dict[str, Any]:
    """Return the vehicle's figures as a plain dict, like :func:`dataclasses.asdict`.

    Examples
    --------
    >>> from dataclasses import asdict
    >>> vehicle = Vehicle("rover", 0.7, 1.0, 0.6, 0.0, True, 90.0)
    >>> vehicle_dict(vehicle) == asdict(vehicle)
    True
    """
    return {name: getattr(vehicle, name) for name in _VEHICLE_FIELDS}


_VEHICLE_FIELDS = tuple(f.name for f in fields(Vehicle))


@dataclass(frozen=True, slots=True)
class CoveragePlan:
    """A planned route over a field.

    Attributes
    ----------
    field_lonlat : Polygon
        The field as given (WGS84), holes included.
    waypoints : sequence of Waypoint
        The route τ = [p_s, p_0, …, p_n, p_f] in driving order (the planner gives
        :class:`Waypoints`, made on access; a tuple does as well).
    segments : sequence of PathSegment
        The same route cut into transit legs, tillage lines, turns and headland passes (the
        planner gives :class:`PathSegments`, made on access; a tuple does as well).
    stats : PlanStats
        The plan's figures.
    interval_m : float
        Distance between tillage lines [m].
    cells_lonlat : tuple of Polygon
        The cells the field was split into (one for a convex field), WGS84.
    vehicle : Vehicle or None
        The vehicle the plan is for (None for a plan read back from a file without one).
    implement_width_m : float or None
        Working width of the implement [m].
    """

    field_lonlat: Polygon
    waypoints: Sequence[Waypoint]
    segments: Sequence[PathSegment]
    stats: PlanStats
    interval_m: float
    cells_lonlat: tuple[Polygon, ...] = ()
    vehicle: Vehicle | None = None
    implement_width_m: float | None = None
