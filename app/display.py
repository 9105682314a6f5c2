"""Lighter answers for drawing: a simulation's tracks thinned to what a map can show.

A 4 ha simulation stores one vertex per second for three tracks (true, estimated, GPS): about
2 MB of JSON. The page draws the true track only, and a straight stretch driven for a minute
draws the same with two vertices as with sixty. ``?tracks=display`` answers that track
simplified (Douglas–Peucker, shapely) to within :data:`DISPLAY_TOLERANCE_M`; the stored
simulation and its GPX export keep every vertex.
"""

from __future__ import annotations

import math
from typing import Any, Final, Literal

import shapely

#: Largest distance between the thinned track and the stored one [m]: under a pixel at zoom 21.
DISPLAY_TOLERANCE_M: Final = 0.05
#: Metres per degree of latitude (mean), to turn the tolerance into degrees.
METRES_PER_DEGREE: Final = 111_320.0

TrackDetail = Literal["full", "display"]


def thin_line(coordinates: list[list[float]], *, tolerance_m: float) -> list[int]:
    """Return the indices of the vertices kept when ``coordinates`` is simplified.

    Parameters
    ----------
    coordinates : list of [lon, lat]
        A track in WGS84 degrees.
    tolerance_m : float
        Largest distance from the original line [m] (turned into degrees of latitude, which
        errs small in longitude, never large).

    Returns
    -------
    list of int
        Increasing indices into ``coordinates``, first and last included.

    Examples
    --------
    >>> thin_line([[0, 0], [1e-6, 0], [2e-6, 0], [2e-6, 1e-3]], tolerance_m=0.05)
    [0, 2, 3]
    """
    if len(coordinates) <= 2:
        return list(range(len(coordinates)))
    line = shapely.LineString(coordinates)
    kept = shapely.simplify(line, tolerance_m / METRES_PER_DEGREE, preserve_topology=False)
    # Douglas–Peucker keeps original vertices: find each in order.
    indices: list[int] = []
    start = 0
    for x, y in kept.coords:
        for i in range(start, len(coordinates)):
            if math.isclose(coordinates[i][0], x) and math.isclose(coordinates[i][1], y):
                indices.append(i)
                start = i + 1
                break
    if not indices or indices[-1] != len(coordinates) - 1:
        indices.append(len(coordinates) - 1)
    return indices


def display_tracks(tracks: dict[str, Any]) -> dict[str, Any]:
    """Return ``tracks`` (a FeatureCollection) with only the true track, thinned for drawing.

    Every per-vertex property list (``time_s``) is thinned with the coordinates; the feature
    says how many vertices the stored track has (``stored_vertices``).
    """
    features = []
    for feature in tracks.get("features", []):
        props = dict(feature.get("properties") or {})
        if props.get("source") != "true":
            continue
        coords = feature["geometry"]["coordinates"]
        keep = thin_line(coords, tolerance_m=DISPLAY_TOLERANCE_M)
        for key, values in list(props.items()):
            if isinstance(values, list) and len(values) == len(coords):
                props[key] = [values[i] for i in keep]
        props["stored_vertices"] = len(coords)
        geometry = {**feature["geometry"], "coordinates": [coords[i] for i in keep]}
        features.append({**feature, "properties": props, "geometry": geometry})
    return {**tracks, "features": features}
