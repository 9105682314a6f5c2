"""Vehicle presets (product.md §3a) and the one function that turns a request's vehicle into one.

The figures of each preset, with their sources, are listed in ``docs/vehicles.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from planner.errors import InvalidParameterError
from planner.types import Vehicle

#: The presets by name. Sources: docs/vehicles.md.
PRESETS: dict[str, Vehicle] = {
    # A walk-behind hand tractor with a puddler, steered by its clutches: it pivots about the
    # braked wheel, its axle centre on a circle of radius track / 2.
    "hand_tractor": Vehicle(
        preset="hand_tractor",
        width_m=0.85,
        length_m=2.1,
        track_m=0.7,
        min_turn_radius_m=0.0,
        can_reverse=False,
        turn_rate_dps=45.0,
    ),
    # The paper's Table 3 as printed: 1.8 m between the wheels, pi/4 rad/s.
    "paper_g1000": Vehicle(
        preset="paper_g1000",
        width_m=1.8,
        length_m=2.1,
        track_m=1.8,
        min_turn_radius_m=0.0,
        can_reverse=False,
        turn_rate_dps=45.0,
    ),
    # A compact four-wheel tractor: forward turns only, a turning radius of a few metres.
    "small_tractor": Vehicle(
        preset="small_tractor",
        width_m=1.3,
        length_m=2.8,
        track_m=1.0,
        min_turn_radius_m=3.0,
        can_reverse=False,
        turn_rate_dps=20.0,
    ),
    # A skid-steer field robot that may reverse.
    "rover": Vehicle(
        preset="rover",
        width_m=0.7,
        length_m=1.0,
        track_m=0.55,
        min_turn_radius_m=0.0,
        can_reverse=True,
        turn_rate_dps=60.0,
    ),
}

DEFAULT_VEHICLE = "hand_tractor"

#: (low, high) bounds of each numeric override, in the field's own unit.
_BOUNDS: dict[str, tuple[float, float]] = {
    "width_m": (0.1, 20.0),
    "length_m": (0.1, 30.0),
    "track_m": (0.1, 10.0),
    "min_turn_radius_m": (0.0, 50.0),
    "turn_rate_dps": (1.0, 360.0),
}


def resolve_vehicle(spec: str | Mapping[str, Any] | Vehicle | None) -> Vehicle:
    """Return the vehicle a request names: a preset, a preset with overrides, or the default.

    Parameters
    ----------
    spec : str, mapping, Vehicle or None
        A preset name, ``{"preset": name, <field>: value, ...}`` (fields override the preset),
        a ready :class:`Vehicle`, or None for ``hand_tractor``.

    Returns
    -------
    Vehicle

    Raises
    ------
    InvalidParameterError
        If the preset is unknown, a field is unknown, or a value is out of range.

    Examples
    --------
    >>> resolve_vehicle("small_tractor").min_turn_radius_m
    3.0
    >>> resolve_vehicle({"preset": "hand_tractor", "width_m": 0.9}).width_m
    0.9
    """
    if isinstance(spec, Vehicle):
        return spec
    if spec is None:
        return PRESETS[DEFAULT_VEHICLE]
    if isinstance(spec, str):
        return _preset(spec)
    overrides = dict(spec)
    base = _preset(str(overrides.pop("preset", DEFAULT_VEHICLE)))
    changes: dict[str, Any] = {}
    for name, value in overrides.items():
        if name == "can_reverse":
            if not isinstance(value, bool):
                raise InvalidParameterError("vehicle.can_reverse", "must be true or false")
            changes[name] = value
            continue
        if name not in _BOUNDS:
            known = ", ".join(["preset", "can_reverse", *_BOUNDS])
            raise InvalidParameterError(f"vehicle.{name}", f"is not a vehicle field ({known})")
        low, high = _BOUNDS[name]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InvalidParameterError(f"vehicle.{name}", "must be a number")
        number = float(value)
        if not (math.isfinite(number) and low <= number <= high):
            raise InvalidParameterError(
                f"vehicle.{name}", f"must be between {low:g} and {high:g}, got {value}"
            )
        changes[name] = number
    return replace(base, **changes)


def _preset(name: str) -> Vehicle:
    try:
        return PRESETS[name]
    except KeyError:
        known = ", ".join(PRESETS)
        raise InvalidParameterError(
            "vehicle", f"unknown preset {name!r} (known: {known})"
        ) from None
