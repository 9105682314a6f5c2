"""The databases the tests run against: SQLite always, PostgreSQL when CI names a server.

On PostgreSQL every fixture works in a throw-away database of its own (``CREATE DATABASE``,
dropped afterwards), so tests neither see nor leave rows in the shared one.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from app import testing

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


@contextmanager
def scratch_pg_database(prefix: str = "tillpath_test") -> Iterator[str]:
    """A throw-away database on the server CI names (see :mod:`app.testing`)."""
    with testing.scratch_pg_database(pg_base_url(), prefix=prefix) as url:
        yield url
