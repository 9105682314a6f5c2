"""Fixtures of the migration tests: an empty database of each kind, dropped afterwards.

SQLite always; PostgreSQL too when ``TILLPATH_TEST_DATABASE_URL`` names a server (CI sets it).
On PostgreSQL each test gets a database of its own, made with ``CREATE DATABASE``.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from app.db import get_engine
from tests.databases import DATABASES, scratch_pg_database


@pytest.fixture(params=DATABASES)
def empty_database_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """The URL of a database with no tables at all."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'data' / 'tillpath.db'}"
        return
    with scratch_pg_database("tillpath_migrations") as url:
        try:
            yield url
        finally:
            get_engine.cache_clear()
