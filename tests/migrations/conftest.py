"""Fixtures of the migration tests: an empty database of each kind, dropped afterwards.

SQLite always; PostgreSQL too when ``TILLPATH_TEST_DATABASE_URL`` names a server (CI sets it).
On PostgreSQL each test gets a database of its own, made with ``CREATE DATABASE``.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from app.db import get_engine

PG_URL_ENV = "TILLPATH_TEST_DATABASE_URL"

DATABASES = [
    "sqlite",
    *(
        [pytest.param("postgresql", marks=pytest.mark.postgres)]
        if os.environ.get(PG_URL_ENV)
        else []
    ),
]


def _admin(base_url: str, sql: str) -> None:
    engine = create_engine(base_url, isolation_level="AUTOCOMMIT")
    try:
        with engine.connect() as conn:
            conn.execute(text(sql))
    finally:
        engine.dispose()


@pytest.fixture(params=DATABASES)
def empty_database_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """The URL of a database with no tables at all."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'data' / 'tillpath.db'}"
        return
    base_url = os.environ[PG_URL_ENV]
    name = f"tillpath_migrations_{uuid.uuid4().hex[:12]}"
    _admin(base_url, f'CREATE DATABASE "{name}"')
    url = make_url(base_url).set(database=name).render_as_string(hide_password=False)
    try:
        yield url
    finally:
        get_engine.cache_clear()
        _admin(base_url, f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
