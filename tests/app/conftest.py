"""Fixtures of the API tests: one database per kind, a rolled-back session per test, a client.

Every API test runs against SQLite, and again against PostgreSQL when
``TILLPATH_TEST_DATABASE_URL`` names a server (CI sets it). On PostgreSQL the tests make a
database of their own (``CREATE DATABASE``) and drop it at the end, so they neither see nor
leave rows in the shared one. The schema is made by ``alembic upgrade head``, never by
``create_all``, so the migrations are what the tests exercise.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from alembic import command
from fastapi import FastAPI
from sqlalchemy import Engine
from sqlalchemy.orm import Session
from sqlalchemy.pool import StaticPool
from starlette.testclient import TestClient

from app.db import alembic_config, get_session, make_engine, upgrade_database
from app.main import create_app
from app.settings import Settings
from tests.databases import DATABASES, scratch_pg_database

SHARED = Path(__file__).resolve().parents[3] / "shared"
PAPER_FIELD = SHARED / "fields" / "paper_ketewel.geojson"
GPX_XSD = SHARED / "schemas" / "gpx-1.1.xsd"
#: Body limit of the test app: small, so that 413 is cheap to provoke.
TEST_MAX_BODY_BYTES = 256 * 1024
#: Upload limit of the test app: above the test track files (about 300 kB), cheap to exceed.
TEST_MAX_UPLOAD_BYTES = 1024 * 1024


@pytest.fixture(scope="session", params=DATABASES)
def engine(request: pytest.FixtureRequest) -> Iterator[Engine]:
    """An engine on a freshly migrated database of each kind, for the whole session."""
    if request.param == "sqlite":
        engine = make_engine("sqlite://", poolclass=StaticPool)
        with engine.connect() as conn:
            config = alembic_config("sqlite://", connection=conn)
            config.attributes["configure_logger"] = False
            command.upgrade(config, "head")
            conn.commit()
        yield engine
        engine.dispose()
        return
    with scratch_pg_database() as url:
        engine = make_engine(url)
        try:
            upgrade_database(url)
            yield engine
        finally:
            engine.dispose()


@pytest.fixture
def session(engine: Engine) -> Iterator[Session]:
    """A session inside an outer transaction that is rolled back after the test."""
    with engine.connect() as conn:
        outer = conn.begin()
        session = Session(
            bind=conn, join_transaction_mode="create_savepoint", expire_on_commit=False
        )
        try:
            yield session
        finally:
            session.close()
            outer.rollback()


@pytest.fixture
def app(session: Session) -> Iterator[FastAPI]:
    app = create_app(
        Settings(
            database_url="sqlite://",
            max_body_bytes=TEST_MAX_BODY_BYTES,
            max_upload_bytes=TEST_MAX_UPLOAD_BYTES,
        )
    )

    def override_session() -> Iterator[Session]:
        yield session

    app.dependency_overrides[get_session] = override_session
    yield app
    app.dependency_overrides.clear()


@pytest.fixture
def client(app: FastAPI) -> Iterator[TestClient]:
    with TestClient(app) as client:
        yield client


@pytest.fixture(scope="session")
def paper_geojson() -> dict[str, Any]:
    """The paper's field as a FeatureCollection with start and finish points."""
    data: dict[str, Any] = json.loads(PAPER_FIELD.read_text())
    return data


@pytest.fixture
def paper_body(paper_geojson: dict[str, Any]) -> dict[str, Any]:
    """A valid request: the paper field at 4 m, named."""
    return {"name": "Sawah Ketewel", "field": paper_geojson, "interval_m": 4}
