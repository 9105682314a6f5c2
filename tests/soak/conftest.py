"""Fixtures of the soak and fault suite: a real ``tillpath serve`` on each database.

The suite runs in ``make test`` (and so in CI) in a short version, a few seconds of load per
test; ``make soak`` runs it for longer (``TILLPATH_SOAK_S``, seconds of load per test).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import PAPER_FIELD
from tests.databases import DATABASES, scratch_pg_database

#: Seconds of load per test: short in ``make test``, longer in ``make soak``.
SOAK_S = float(os.environ.get("TILLPATH_SOAK_S", "6"))
#: Concurrent clients of the mixed load.
SOAK_THREADS = int(os.environ.get("TILLPATH_SOAK_THREADS", "6"))


@pytest.fixture(params=DATABASES)
def database_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """An empty database of each kind; ``tillpath serve`` migrates it."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'soak.db'}"
        return
    with scratch_pg_database("tillpath_soak") as url:
        yield url


@pytest.fixture(scope="session")
def paper_polygon() -> dict[str, Any]:
    """The paper's field as a bare GeoJSON Polygon."""
    geometry: dict[str, Any] = json.loads(PAPER_FIELD.read_text())["features"][0]["geometry"]
    return geometry
