"""Fixtures of the soak and fault suite: a real ``tillpath serve`` on each database.

The suite runs in ``make test`` (and so in CI) in a short version, about 1.5 minutes in all: a
few seconds of load per test, three clients, smaller logs, the fault tests on one database each,
schemathesis left to tests/app/test_schemathesis.py. ``make soak`` runs all of it on both
databases for longer (``TILLPATH_SOAK_S``, seconds of load per test, 30 or more).
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
SOAK_S = float(os.environ.get("TILLPATH_SOAK_S", "3"))
#: The long version (``make soak``): every worker count, every schemathesis phase, bigger logs.
LONG = SOAK_S >= 30
#: The long schemathesis run (every phase) is collected by ``make soak`` only: in ``make test``,
#: tests/app/test_schemathesis.py runs schemathesis over every operation on both databases.
collect_ignore = [] if LONG else ["test_schemathesis.py"]
#: Concurrent clients of the mixed load.
SOAK_THREADS = int(os.environ.get("TILLPATH_SOAK_THREADS", "6" if LONG else "3"))


def databases(short_run: str) -> list[Any]:
    """The databases of a test: both in ``make soak``; ``short_run`` alone in the short run.

    (The short run falls back to SQLite when PostgreSQL is not configured.)
    """
    if LONG:
        return DATABASES
    kept = [p for p in DATABASES if (p if isinstance(p, str) else p.values[0]) == short_run]
    return kept or ["sqlite"]


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
