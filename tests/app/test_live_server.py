"""The app under a real uvicorn server, on committed sessions: concurrency and streamed bodies.

Unlike the other API tests (one rolled-back session per test), these use the app's own
sessions on a database made for the test (a SQLite file, and a PostgreSQL database when
``TILLPATH_TEST_DATABASE_URL`` is set), which is dropped afterwards.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx2
import pytest
import uvicorn
from fastapi import FastAPI

from app.db import get_engine, upgrade_database
from app.main import create_app
from app.settings import Settings
from app.testing import ServerUrl, seed_account
from tests.conftest import PAPER_FIELD
from tests.databases import DATABASES, scratch_pg_database

MAX_BODY_BYTES = 64 * 1024
PAPER = json.loads(PAPER_FIELD.read_text())["features"][0]["geometry"]


@pytest.fixture(params=DATABASES)
def database_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """A freshly migrated database; PostgreSQL's is dropped after the test."""
    if request.param == "sqlite":
        url = f"sqlite:///{tmp_path / 'tillpath.db'}"
        upgrade_database(url)
        yield url
        get_engine(url).dispose()
        get_engine.cache_clear()
        return
    with scratch_pg_database("tillpath_live") as url:
        try:
            upgrade_database(url)
            yield url
        finally:
            get_engine(url).dispose()
            get_engine.cache_clear()


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@contextmanager
def serving(app: FastAPI) -> Iterator[str]:
    """Serve ``app`` with uvicorn on a loopback port, in a thread; yield its base URL."""
    port = free_port()
    config = uvicorn.Config(
        app, host="127.0.0.1", port=port, log_level="warning", lifespan="off", ws="none"
    )
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 10
    while not server.started:
        assert thread.is_alive() and time.monotonic() < deadline, "uvicorn did not start"
        time.sleep(0.01)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(timeout=10)


@pytest.fixture
def server_url(database_url: str) -> Iterator[ServerUrl]:
    """Serve the app with uvicorn on a loopback port, in a thread, for one test.

    The database has a first account; ``server_url.headers`` authenticates as it.
    """
    account = seed_account(database_url)
    app = create_app(Settings(database_url=database_url, max_body_bytes=MAX_BODY_BYTES))
    with serving(app) as url:
        yield ServerUrl(url, account)


def test_fifty_plans_from_ten_threads_are_all_stored_once(server_url: ServerUrl):
    def create_five(worker: int) -> list[dict[str, Any]]:
        created = []
        with httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=30) as client:
            for i in range(5):
                body = {"name": f"w{worker}-p{i}", "field": PAPER, "interval_m": 4}
                response = client.post("/api/plans", json=body)
                assert response.status_code == 201, response.text
                created.append(response.json())
        return created

    with ThreadPoolExecutor(max_workers=10) as pool:
        results = [plan for plans in pool.map(create_five, range(10)) for plan in plans]

    ids = [plan["id"] for plan in results]
    assert len(ids) == 50 and len(set(ids)) == 50
    with httpx2.Client(base_url=server_url, headers=server_url.headers) as client:
        listing = client.get("/api/plans", params={"limit": 200}).json()
        assert listing["total"] == 50
        assert sorted(item["id"] for item in listing["items"]) == sorted(ids)
        names = sorted(item["name"] for item in listing["items"])
        assert names == sorted(f"w{w}-p{i}" for w in range(10) for i in range(5))
        for plan in results[::10]:
            assert client.get(f"/api/plans/{plan['id']}").json()["name"] == plan["name"]


def test_streamed_body_over_limit_returns_413_and_stores_nothing(server_url: ServerUrl):
    def chunks() -> Iterator[bytes]:  # no Content-Length: sent chunked
        yield b'{"field": {"type": "Polygon", "coordinates": [[['
        for _ in range(MAX_BODY_BYTES // 1000 + 10):  # 1,000 bytes each
            yield b"115.298, -8.6265], [" * 50
        yield b'115.298, -8.6265]]]}, "interval_m": 4}'

    with httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=30) as client:
        response = client.post(
            "/api/plans", content=chunks(), headers={"content-type": "application/json"}
        )
        assert response.request.headers["transfer-encoding"] == "chunked"
        assert "content-length" not in response.request.headers
        assert response.status_code == 413
        assert response.json() == {
            "detail": f"body: the request is larger than the limit of {MAX_BODY_BYTES} bytes"
        }
        assert client.get("/api/plans").json() == {"items": [], "total": 0}


def test_health_pings_the_database(server_url: ServerUrl):
    response = httpx2.get(f"{server_url}/api/health")
    assert response.status_code == 200
    assert response.json() == {"status": "ok", "database": "ok"}


def test_tillpath_serve_migrates_then_serves(tmp_path: Path):
    database = tmp_path / "data" / "tillpath.db"
    port = free_port()
    script = Path(sys.executable).parent / "tillpath"
    command = [str(script)] if script.exists() else [sys.executable, "-m", "app.cli"]
    env = {**os.environ, "TILLPATH_DATABASE_URL": f"sqlite:///{database}"}
    process = subprocess.Popen(
        [*command, "serve", "--host", "127.0.0.1", "--port", str(port), "--workers", "1"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        # As app.testing's servers: start-up speed is not what this test is about (the
        # migration and the first answer are), and a loaded CI machine took 30.4 s once.
        deadline = time.monotonic() + 60
        while True:
            assert process.poll() is None, process.stderr.read() if process.stderr else ""
            assert time.monotonic() < deadline, "tillpath serve did not answer in 60 s"
            try:
                response = httpx2.get(f"http://127.0.0.1:{port}/api/health", timeout=1)
                break
            except httpx2.TransportError:
                time.sleep(0.1)
        assert response.json() == {"status": "ok", "database": "ok"}
        base = f"http://127.0.0.1:{port}"
        plan = {"name": "served", "field": PAPER, "interval_m": 4}
        refused = httpx2.post(f"{base}/api/plans", json=plan, timeout=10)
        assert refused.status_code == 401, refused.text
        # An empty server asks for its first account; the page then works with the cookie.
        assert httpx2.get(f"{base}/api/auth/setup").json() == {"needs_first_account": True}
        with httpx2.Client(base_url=base, timeout=10) as browser:
            me = browser.post(
                "/api/auth/signup", json={"username": "first", "password": "first password"}
            )
            assert me.status_code == 201, me.text
            created = browser.post(
                "/api/plans", json=plan, headers={"X-CSRF-Token": me.json()["csrf_token"]}
            )
            assert created.status_code == 201, created.text
        assert httpx2.get(f"{base}/api/auth/setup").json() == {"needs_first_account": False}
    finally:
        process.terminate()
        # The server also stops its local Dask cluster (worker processes) on the way out.
        process.wait(timeout=30)
        said = process.stderr.read().decode() if process.stderr else ""
        if process.stderr:
            process.stderr.close()
    assert database.is_file()  # migrated into a directory that did not exist
    assert f"no account yet: open http://127.0.0.1:{port}/ to create the first one" in said
