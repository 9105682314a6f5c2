"""Accounts under concurrent writers: one first owner, one new member, no Argon2 under the lock.

On committed sessions of a database made for the test (a SQLite file; PostgreSQL too when
``TILLPATH_TEST_DATABASE_URL`` is set), as in :mod:`tests.app.test_live_server`.
"""

from __future__ import annotations

import sqlite3
import statistics
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx2
from sqlalchemy import select
from sqlalchemy.orm import Session

from app import accounts, members
from app.auth_models import Membership, Organisation, User
from app.db import get_engine, make_engine, upgrade_database
from app.main import create_app
from app.settings import Settings
from app.testing import ServerUrl
from tests.app.test_live_server import database_url, server_url, serving  # noqa: F401

#: First sign-ups sent at once.
SIGN_UPS = 4
PASSWORD = "a long password"


def test_concurrent_first_sign_ups_make_exactly_one_owner(database_url: str):  # noqa: F811
    start = threading.Barrier(SIGN_UPS)

    def sign_up(base_url: str, i: int) -> httpx2.Response:
        with httpx2.Client(base_url=base_url, timeout=60) as browser:
            body = {"username": f"first{i}", "password": PASSWORD, "organisation": f"farm {i}"}
            start.wait()
            return browser.post("/api/auth/signup", json=body)

    with (
        serving(create_app(Settings(database_url=database_url))) as base_url,
        ThreadPoolExecutor(SIGN_UPS) as pool,
    ):
        answers = list(pool.map(lambda i: sign_up(base_url, i), range(SIGN_UPS)))

    codes = [a.status_code for a in answers]
    assert sorted(codes) == [201] + [409] * (SIGN_UPS - 1), [a.text for a in answers]
    winner = codes.index(201)
    assert answers[winner].json()["user"]["username"] == f"first{winner}"
    with Session(get_engine(database_url)) as session:
        memberships = session.execute(
            select(User.username, Organisation.name, Membership.role)
            .join(Membership, Membership.user_id == User.id)
            .join(Organisation, Organisation.id == Membership.organisation_id)
        ).all()
        assert [tuple(m) for m in memberships] == [(f"first{winner}", f"farm {winner}", "owner")]
        assert accounts.user_count(session) == 1


def test_add_member_hashes_the_new_password_before_taking_the_write_lock(tmp_path: Path):
    """Another SQLite writer is never kept waiting for an Argon2 hash (~0.1 s of CPU).

    A probe connection with no busy timeout tries ``BEGIN IMMEDIATE`` every half millisecond
    while three new members are added; the longest run of "database is locked" is how long a
    tractor's fixes would wait. It must be well under one hash.
    """
    path = tmp_path / "tillpath.db"
    url = f"sqlite:///{path}"
    upgrade_database(url)
    engine = make_engine(url)
    with Session(engine) as session:
        organisation = Organisation(name="farm")
        session.add(organisation)
        session.commit()
        organisation_id = organisation.id
    hash_s = statistics.median(_timed(accounts.hash_password, PASSWORD) for _ in range(3))

    stop = threading.Event()
    locked_spans_s: list[float] = []
    errors: list[str] = []
    writes = 0

    def probe() -> None:
        nonlocal writes
        writer = sqlite3.connect(path, timeout=0, isolation_level=None)
        locked_since: float | None = None
        try:
            while not stop.is_set():
                try:
                    writer.execute("BEGIN IMMEDIATE")
                    writer.execute("ROLLBACK")
                    writes += 1
                    if locked_since is not None:
                        locked_spans_s.append(time.perf_counter() - locked_since)
                        locked_since = None
                except sqlite3.OperationalError as exc:
                    if "locked" not in str(exc):
                        errors.append(str(exc))
                        return
                    if locked_since is None:
                        locked_since = time.perf_counter()
                time.sleep(0.0005)
        finally:
            writer.close()

    thread = threading.Thread(target=probe, daemon=True)
    thread.start()
    try:
        for i in range(3):
            with Session(engine, expire_on_commit=False) as session:
                user, member = members.add_member(
                    session, organisation_id, f"new{i}", "viewer", PASSWORD
                )
                assert member.role == "viewer"
            assert accounts.verify_password(user.password_hash, PASSWORD)
    finally:
        stop.set()
        thread.join(timeout=10)
        engine.dispose()
    assert not errors and writes > 0, errors
    longest_s = max(locked_spans_s, default=0.0)
    assert longest_s < hash_s / 2, (
        f"another writer waited {longest_s * 1000:.0f} ms; one hash takes {hash_s * 1000:.0f} ms"
    )


def _timed(function: Callable[..., object], *args: object) -> float:
    """Return how long ``function(*args)`` takes [s]."""
    start = time.perf_counter()
    function(*args)
    return time.perf_counter() - start


#: Owners' "add member" requests for one new username sent at once, and rounds of them.
SAME_MEMBER_REQUESTS = 6
SAME_MEMBER_ROUNDS = 3


def test_concurrent_adds_of_one_new_member_all_succeed_and_make_one_user(
    database_url: str,  # noqa: F811
    server_url: ServerUrl,  # noqa: F811
):
    """A double-click or a client's retry adds one user and one membership, and no 5xx.

    Every request reads "no such user" and hashes the password before the write transaction,
    so on PostgreSQL all but the first then insert the same username (or membership) and hit
    the unique constraint; each must then see the user the first made and give it the role,
    as if the requests had come one after another.
    """
    start = threading.Barrier(SAME_MEMBER_REQUESTS)

    def add(username: str) -> httpx2.Response:
        with httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=60) as owner:
            body = {"username": username, "role": "planner", "password": PASSWORD}
            start.wait()
            return owner.post("/api/members", json=body)

    names = [f"newcomer{r}" for r in range(SAME_MEMBER_ROUNDS)]
    with ThreadPoolExecutor(SAME_MEMBER_REQUESTS) as pool:
        for name in names:
            answers = list(pool.map(add, [name] * SAME_MEMBER_REQUESTS))
            codes = [a.status_code for a in answers]
            assert codes == [201] * SAME_MEMBER_REQUESTS, [a.text for a in answers]
            assert len({a.json()["user_id"] for a in answers}) == 1
            assert {a.json()["role"] for a in answers} == {"planner"}

    with Session(get_engine(database_url)) as session:
        rows = session.execute(
            select(User.username, Membership.role)
            .join(Membership, Membership.user_id == User.id)
            .where(
                User.username.in_(names),
                Membership.organisation_id == server_url.account.organisation_id,
            )
            .order_by(User.username)
        ).all()
        assert [tuple(r) for r in rows] == [(name, "planner") for name in names]
