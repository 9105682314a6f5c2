"""Errors mapped to HTTP in one place (app.errors): what the log keeps of a database error."""

from __future__ import annotations

import json
import logging
from collections.abc import Iterator
from contextlib import ExitStack
from pathlib import Path

import pytest
from sqlalchemy import Engine, create_engine, text
from sqlalchemy.exc import IntegrityError

from app.errors import error_response
from tests.databases import DATABASES, scratch_pg_database

#: What an INSERT of a new user binds: its password's Argon2 hash.
SECRET_HASH = "$argon2id$v=19$m=65536,t=3,p=4$c2FsdHNhbHQ$aGFzaGhhc2hoYXNo"


@pytest.mark.parametrize(
    "driver_text",
    [
        "UNIQUE constraint failed: users.username",  # SQLite
        'duplicate key value violates unique constraint "users_username_key"\n'
        "DETAIL:  Key (username)=(alice) already exists.",  # PostgreSQL (psycopg)
    ],
)
def test_a_conflict_is_logged_without_its_statement_or_parameters(
    driver_text: str, caplog: pytest.LogCaptureFixture
) -> None:
    conflict = IntegrityError(
        "INSERT INTO users (username, password_hash) VALUES (?, ?)",
        ("alice", SECRET_HASH),
        Exception(driver_text),
    )
    with caplog.at_level(logging.WARNING, logger="app.errors"):
        response = error_response(conflict)
    assert response.status_code == 409
    logged = caplog.text
    assert driver_text.splitlines()[0] in logged
    assert SECRET_HASH not in logged and "INSERT" not in logged and "DETAIL" not in logged


@pytest.fixture(params=DATABASES)
def engine(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Engine]:
    """A real database of each kind, with a table keyed as the registry keys its fields."""
    with ExitStack() as stack:
        if request.param == "sqlite":
            url = f"sqlite:///{tmp_path / 'conflicts.db'}"
        else:
            url = stack.enter_context(scratch_pg_database("tillpath_errors"))
        engine = create_engine(url)
        stack.callback(engine.dispose)
        with engine.begin() as connection:
            connection.execute(
                text(
                    "CREATE TABLE fields (id INTEGER PRIMARY KEY, organisation_id INTEGER NOT NULL,"
                    " name VARCHAR(80) NOT NULL, token_hash VARCHAR(80) UNIQUE,"
                    " UNIQUE (organisation_id, name))"
                )
            )
            connection.execute(
                text("INSERT INTO fields VALUES (1, 7, 'north paddy', :token)"),
                {"token": SECRET_HASH},
            )
        yield engine


@pytest.mark.parametrize(
    ("values", "named"),
    [
        ("(2, 7, 'north paddy', NULL)", "name"),  # a key of two columns: the last is named
        ("(3, 8, 'south paddy', :token)", "token_hash"),  # one column; its value never shown
        ("(4, 7, NULL, NULL)", "name"),  # NOT NULL
    ],
)
def test_a_conflict_names_the_input_the_database_names_and_never_its_value(
    engine: Engine, values: str, named: str
) -> None:
    with pytest.raises(IntegrityError) as raised, engine.begin() as connection:
        connection.execute(text(f"INSERT INTO fields VALUES {values}"), {"token": SECRET_HASH})
    response = error_response(raised.value)
    assert response.status_code == 409
    detail = json.loads(response.body)["detail"]
    assert detail == f"{named}: the request conflicts with a change made at the same time; retry"
    # In Indonesian the problem is translated and the input keeps its name.
    translated = json.loads(error_response(raised.value, "id").body)["detail"]
    assert translated.startswith(f"{named}: ") and translated != detail


def test_a_conflict_whose_driver_names_no_column_says_the_problem_alone() -> None:
    conflict = IntegrityError("INSERT", {}, Exception("FOREIGN KEY constraint failed"))
    detail = json.loads(error_response(conflict).body)["detail"]
    assert detail == "the request conflicts with a change made at the same time; retry"
