"""Turns: how the tractor gets from the end of one line to the start of the next.

A walk-behind tractor turns by pulling one clutch and pivoting about that wheel, so a turn is
the straight move between the two line ends, with a pivot at each. Inside a convex cell that
move stays inside the cell (R1).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


def pivot_time_s(x: FloatArray, y: FloatArray, *, speed_mps: float, track_width_m: float) -> float:
    """Time spent pivoting along a polyline [s].

    Pulling one clutch stops that wheel; the other drives round it at ``speed_mps``, so the
    tractor turns at ``speed_mps / track_width_m`` rad/s. Zero-length steps are ignored.

    Examples
    --------
    >>> round(pivot_time_s(np.array([0.0, 0, 4, 4]), np.array([0.0, 10, 10, 0]),
    ...                    speed_mps=0.56, track_width_m=1.8), 2)   # two right angles
    10.1
    """
    dx, dy = np.diff(x), np.diff(y)
    moving = np.hypot(dx, dy) > 1e-9
    heading = np.arctan2(dx[moving], dy[moving])
    change = np.abs((np.diff(heading) + np.pi) % (2.0 * np.pi) - np.pi)
    return float(change.sum() * track_width_m / speed_mps)
