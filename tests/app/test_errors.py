"""Errors mapped to HTTP in one place (app.errors): what the log keeps of a database error."""

from __future__ import annotations

import logging

import pytest
from sqlalchemy.exc import IntegrityError

from app.errors import error_response

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
