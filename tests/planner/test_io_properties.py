"""Property: a field anywhere, written by GDAL in its UTM zone or Web Mercator, reads back."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely import Polygon

from planner.io import read_fields
from planner.projection import geodesic_area_m2
from tests.planner.field_files import gpkg_bytes, zipped_utm_shapefile_bytes


@st.composite
def fields_lonlat(draw: st.DrawFn) -> Polygon:
    lon = draw(st.floats(-179.0, 179.0))
    lat = draw(st.floats(-70.0, 70.0))
    size_m = draw(st.floats(30.0, 800.0))
    seed = draw(st.integers(0, 2**32 - 1))
    points = np.random.default_rng(seed).uniform(-0.5, 0.5, (12, 2)) * size_m
    hull = shapely.MultiPoint(points).convex_hull
    metres_per_degree = 111_320.0
    scale = np.array([1 / (metres_per_degree * np.cos(np.radians(lat))), 1 / metres_per_degree])
    coords = np.asarray(hull.exterior.coords) * scale + [lon, lat]
    return Polygon(coords)


@settings(max_examples=12, deadline=None)
@given(field=fields_lonlat(), mercator=st.booleans())
def test_projected_field_files_read_back_in_lonlat(field: Polygon, mercator: bool) -> None:
    with tempfile.TemporaryDirectory() as scratch:
        tmp = Path(scratch)
        if mercator:
            data = gpkg_bytes(tmp, [field], ["f"], crs="EPSG:3857")
        else:
            data = zipped_utm_shapefile_bytes(tmp, field)
    (spec,) = read_fields(data, filename="f")
    back = spec.field_lonlat
    assert back.hausdorff_distance(field) < 1e-8  # degrees: about a millimetre
    assert abs(geodesic_area_m2(back) - geodesic_area_m2(field)) <= 1e-6 * geodesic_area_m2(field)
