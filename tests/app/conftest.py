"""Fixtures of the API tests: one database per kind, a rolled-back session per test, clients.

``client`` acts as the owner of the organisation ``default`` (a personal API token), so tests
of plans, runs and simulations need no ceremony; ``workspace`` holds the other callers of the
access rules (viewer, planner, another organisation's owner, a device token), and
``client_as`` makes a client for any of them (``client_as(None)``: no credentials).

Every API test runs against SQLite, and again against PostgreSQL when
``TILLPATH_TEST_DATABASE_URL`` names a server (CI sets it). On PostgreSQL the tests make a
database of their own (``CREATE DATABASE``) and drop it at the end, so they neither see nor
leave rows in the shared one. The schema is made by ``alembic upgrade head``, never by
``create_all``, so the migrations are what the tests exercise.
"""

from __future__ import annotations

import json
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import pytest
from alembic import command
from fastapi import FastAPI
from sqlalchemy import Engine
from sqlalchemy.orm import Session
from sqlalchemy.pool import StaticPool
from starlette.testclient import TestClient

from app import accounts
from app.auth_models import Membership, Organisation, User
from app.db import alembic_config, get_engine, get_session, make_engine, upgrade_database
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


#: The password of every user of ``workspace``.
TEST_PASSWORD = "correct horse battery staple"


@cache
def test_password_hash() -> str:
    """One Argon2 hash for all test users (hashing costs ~50 ms; tests make many users)."""
    return accounts.hash_password(TEST_PASSWORD)


@dataclass(frozen=True)
class Workspace:
    """Two organisations and a caller of each kind; ``tokens`` maps caller -> bearer token."""

    organisation_id: int
    other_organisation_id: int
    users: dict[str, User]
    tokens: dict[str, str]


def add_user(session: Session, username: str, roles: dict[int, str]) -> User:
    """Add a user with the test password and ``{organisation_id: role}`` memberships."""
    user = User(username=username, password_hash=test_password_hash())
    session.add(user)
    session.flush()
    for org_id, role in roles.items():
        session.add(Membership(user_id=user.id, organisation_id=org_id, role=role))
    session.commit()
    return user


@pytest.fixture
def workspace(session: Session) -> Workspace:
    """Organisation ``default`` (owner, planner, viewer, a device token) and ``other``."""
    org = Organisation(name="default")
    other = Organisation(name="other")
    session.add_all([org, other])
    session.flush()
    users = {
        "owner": add_user(session, "owner", {org.id: "owner"}),
        "planner": add_user(session, "planner", {org.id: "planner"}),
        "viewer": add_user(session, "viewer", {org.id: "viewer"}),
        "other": add_user(session, "other-owner", {other.id: "owner"}),
    }
    tokens = {
        name: accounts.create_token(session, user, name=f"{name} token").token
        for name, user in users.items()
    }
    tokens["device"] = accounts.create_token(
        session, users["owner"], name="tractor 1", device=True, organisation_id=org.id
    ).token
    return Workspace(
        organisation_id=org.id, other_organisation_id=other.id, users=users, tokens=tokens
    )


ClientFactory = Callable[[str | None], TestClient]


@pytest.fixture
def client_as(app: FastAPI, workspace: Workspace) -> Iterator[ClientFactory]:
    """Make a client for a caller of ``workspace`` (``None``: no credentials)."""
    made: list[TestClient] = []

    def factory(caller: str | None) -> TestClient:
        headers = {} if caller is None else {"Authorization": f"Bearer {workspace.tokens[caller]}"}
        client = TestClient(app, headers=headers)
        made.append(client)
        return client

    yield factory
    for client in made:
        client.close()


@pytest.fixture
def client(client_as: ClientFactory) -> TestClient:
    """A client acting as the owner of organisation ``default``."""
    return client_as("owner")


@pytest.fixture
def anon_client(client_as: ClientFactory) -> TestClient:
    """A client with no credentials."""
    return client_as(None)


@pytest.fixture
def viewer_client(client_as: ClientFactory) -> TestClient:
    return client_as("viewer")


@pytest.fixture
def planner_client(client_as: ClientFactory) -> TestClient:
    return client_as("planner")


@pytest.fixture
def other_client(client_as: ClientFactory) -> TestClient:
    """The owner of another organisation: must see nothing of ``default``."""
    return client_as("other")


@pytest.fixture
def device_client(client_as: ClientFactory) -> TestClient:
    """A device token of ``default``: may open live runs and post fixes, nothing else."""
    return client_as("device")


@pytest.fixture(scope="session")
def paper_geojson() -> dict[str, Any]:
    """The paper's field as a FeatureCollection with start and finish points."""
    data: dict[str, Any] = json.loads(PAPER_FIELD.read_text())
    return data


@pytest.fixture
def paper_body(paper_geojson: dict[str, Any]) -> dict[str, Any]:
    """A valid request: the paper field at 4 m, named."""
    return {"name": "Sawah Ketewel", "field": paper_geojson, "interval_m": 4}


# --- Background jobs: a real Dask cluster and a database its worker processes can open -------


@pytest.fixture(scope="session", params=DATABASES)
def jobs_database_url(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[str]:
    """A migrated database of each kind that worker processes can open (a file, or a server)."""
    if request.param == "sqlite":
        url = f"sqlite:///{tmp_path_factory.mktemp('jobs') / 'jobs.db'}"
        upgrade_database(url)
        yield url
        get_engine(url).dispose()
        return
    with scratch_pg_database() as url:
        upgrade_database(url)
        yield url
        get_engine(url).dispose()


@dataclass(frozen=True)
class JobsCaller:
    """An organisation of its own in the jobs database, and its owner's token."""

    organisation_id: int
    user_id: int
    token: str


@pytest.fixture
def jobs_caller(jobs_session: Session) -> JobsCaller:
    """A fresh organisation and owner for each test (the jobs database lives for the session)."""
    tag = uuid.uuid4().hex[:10]
    org = Organisation(name=f"jobs-{tag}")
    jobs_session.add(org)
    jobs_session.flush()
    user = add_user(jobs_session, f"jobs-owner-{tag}", {org.id: "owner"})
    token = accounts.create_token(jobs_session, user, name="jobs test").token
    caller = JobsCaller(organisation_id=org.id, user_id=user.id, token=token)
    # Leave no read transaction open: the test's later reads must see what workers commit.
    jobs_session.commit()
    return caller


@pytest.fixture
def jobs_client(
    jobs_database_url: str, dask_scheduler: str, jobs_caller: JobsCaller
) -> Iterator[TestClient]:
    """A client of an app whose jobs run on the session's Dask cluster, as an owner."""
    app = create_app(
        Settings(
            database_url=jobs_database_url,
            dask_scheduler=dask_scheduler,
            max_body_bytes=TEST_MAX_BODY_BYTES,
            max_upload_bytes=TEST_MAX_UPLOAD_BYTES,
        )
    )
    with TestClient(app, headers={"Authorization": f"Bearer {jobs_caller.token}"}) as client:
        yield client


@pytest.fixture
def jobs_session(jobs_database_url: str) -> Iterator[Session]:
    """A session on the jobs database, to look at what the workers stored."""
    with Session(get_engine(jobs_database_url)) as session:
        yield session
    # Close the pooled connections once the session (torn down after the client) is closed:
    # another test may clear get_engine's cache, and an engine dropped with open connections
    # warns when it is collected.
    get_engine(jobs_database_url).dispose()


def wait_for_job(
    client: TestClient, location: str, *, timeout_s: float = 60.0, until: tuple[str, ...] = ()
) -> dict[str, Any]:
    """Poll a job until it has finished (or reached a status of ``until``); return it."""
    import time

    final = ("done", "failed", "cancelled", *until)
    deadline = time.monotonic() + timeout_s
    while True:
        response = client.get(location)
        assert response.status_code == 200, response.text
        job: dict[str, Any] = response.json()
        if job["status"] in final:
            return job
        assert time.monotonic() < deadline, f"job still {job['status']} after {timeout_s} s"
        time.sleep(0.1)
