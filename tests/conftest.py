"""Shared shapes and helpers for all tests.

Fields are built in a local metric frame and converted to WGS84, so that their size in metres
is exact wherever on Earth they are put.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import shapely
from hypothesis import settings
from shapely import Polygon

# Shared with the benches, which do not import the tests.
from bench.shapes import BALI as BALI
from bench.shapes import field_from_local as field_from_local

# The same examples on every run (CI and a developer's `make test` see the same); set
# HYPOTHESIS_PROFILE=explore to search new random examples (failures are kept in .hypothesis/).
settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(scope="session", autouse=True)
def _kernel_cache() -> None:
    """Load the planner's numba kernels once per session, before any test is timed.

    A fresh clone has no numba cache: the first plan compiles them (about 9 s of CPU), which
    inside a test would count against its timeouts (a subprocess, a server, a page, a
    Hypothesis deadline). Compiled here, they load from the cache everywhere after (0.35 s).
    """
    from app.testing import warm_kernel_cache

    warm_kernel_cache()


@pytest.fixture(scope="session")
def dask_scheduler() -> Iterator[str]:
    """The address of a small real Dask cluster (one worker process) for the whole session."""
    from app.local_cluster import start_local_cluster

    cluster = start_local_cluster(1)
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close()


ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared"
FIELDS_DIR = SHARED / "fields"
GPX_XSD = SHARED / "schemas" / "gpx-1.1.xsd"
PAPER_FIELD = ROOT / "tests" / "data" / "paper_ketewel.geojson"


def load_geojson(path: Path) -> Any:
    return json.loads(path.read_text(encoding="utf-8"))


@pytest.fixture
def paper_geojson() -> Any:
    return load_geojson(PAPER_FIELD)


@pytest.fixture
def square_field() -> Polygon:
    """A 40 m × 40 m square."""
    return field_from_local([(-20, -20), (20, -20), (20, 20), (-20, 20)])


@pytest.fixture
def l_field() -> Polygon:
    """An L-shaped field, 60 m × 60 m with a 30 m × 30 m corner missing (not convex)."""
    return field_from_local([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])


@pytest.fixture
def field_with_hole() -> Polygon:
    """A 50 m × 40 m field with a 10 m × 8 m hut in it."""
    return field_from_local(
        [(0, 0), (50, 0), (50, 40), (0, 40)], [[(20, 15), (30, 15), (30, 23), (20, 23)]]
    )


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20221121)


def local_geometry(plan_field: Polygon, geometry: Any) -> Any:
    """``geometry`` (WGS84) in the planner's frame for ``plan_field``."""
    from planner.projection import field_frame

    return field_frame(plan_field).to_local(geometry)


def convex_polygon(points_m: np.ndarray) -> Polygon:
    return shapely.orient_polygons(shapely.MultiPoint(points_m).convex_hull)
