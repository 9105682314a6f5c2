"""The databases the tests run against: SQLite always, PostgreSQL when CI names a server.

On PostgreSQL every fixture works in a throw-away database of its own (``CREATE DATABASE``,
dropped afterwards), so tests neither see nor leave rows in the shared one.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from contextlib import contextmanager

import pytest
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

PG_URL_ENV = "TILLPATH_TEST_DATABASE_URL"

#: Parameters for fixtures that run once per database kind.
DATABASES = [
    "sqlite",
    *(
        [pytest.param("postgresql", marks=pytest.mark.postgres)]
        if os.environ.get(PG_URL_ENV)
        else []
    ),
]


def pg_base_url() -> str:
    url = os.environ.get(PG_URL_ENV)
    assert url, f"{PG_URL_ENV} is not set"
    return url


def _admin(base_url: str, sql: str) -> None:
    engine = create_engine(base_url, isolation_level="AUTOCOMMIT")
    try:
        with engine.connect() as conn:
            conn.execute(text(sql))
    finally:
        engine.dispose()


@contextmanager
def scratch_pg_database(prefix: str = "tillpath_test") -> Iterator[str]:
    """Create an empty PostgreSQL database, yield its URL, drop it afterwards."""
    base_url = pg_base_url()
    name = f"{prefix}_{uuid.uuid4().hex[:12]}"
    _admin(base_url, f'CREATE DATABASE "{name}"')
    try:
        yield make_url(base_url).set(database=name).render_as_string(hide_password=False)
    finally:
        _admin(base_url, f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
