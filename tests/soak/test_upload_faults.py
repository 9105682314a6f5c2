"""An upload cut off halfway, by the client or by the server dying, stores nothing.

Against a real ``tillpath serve`` on each database: a multipart upload whose client goes away
after half the file leaves no run; a server killed (SIGKILL) while it stores a 120,000-fix log
leaves either no run or the run with every one of its fixes, never a part.
"""

from __future__ import annotations

import socket
import threading
import time
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import httpx2
import pytest

from app.testing import ServerProcess, ServerUrl
from tests.soak.conftest import LONG, databases

pytestmark = pytest.mark.soak

T0_S = 1_795_305_600.0
#: Fixes of the log cut off halfway (a smaller one in the short run).
HALF_CUT_FIXES = 50_000 if LONG else 20_000


def csv_log(fixes: int) -> bytes:
    rows = [
        f"{T0_S + i / 10:.1f},{-8.62645 + (i % 100) * 1e-7:.8f},115.29805" for i in range(fixes)
    ]
    return ("time,lat,lon\n" + "\n".join(rows) + "\n").encode()


def multipart(data: bytes) -> tuple[bytes, bytes]:
    boundary = b"tillpathboundary"
    head = (
        b"--" + boundary + b'\r\nContent-Disposition: form-data; name="file"; filename="log.csv"'
        b"\r\nContent-Type: text/csv\r\n\r\n"
    )
    return boundary, head + data + b"\r\n--" + boundary + b"--\r\n"


def runs_of(base: ServerUrl, plan_id: int) -> list[dict[str, Any]]:
    response = httpx2.get(f"{base}/api/plans/{plan_id}/runs", headers=base.headers)
    items: list[dict[str, Any]] = response.json()["items"]
    return items


@pytest.mark.parametrize("database_url", databases("sqlite"), indirect=True)
def test_an_upload_whose_client_goes_away_halfway_stores_nothing(
    database_url: str, paper_polygon: dict[str, Any], tmp_path: Path
):
    server = ServerProcess(
        database_url, log=tmp_path / "server.log", serve_args=("--no-access-log",)
    )
    base = server.start()
    try:
        plan = httpx2.post(
            f"{base}/api/plans",
            json={"field": paper_polygon, "interval_m": 4},
            headers=base.headers,
        )
        plan_id = plan.json()["id"]
        boundary, body = multipart(csv_log(HALF_CUT_FIXES))
        parts = urlsplit(base)
        assert parts.hostname and parts.port
        with socket.create_connection((parts.hostname, parts.port)) as sock:
            sock.sendall(
                f"POST /api/plans/{plan_id}/runs HTTP/1.1\r\nHost: x\r\n"
                f"Authorization: {base.headers['Authorization']}\r\n"
                f"Content-Type: multipart/form-data; boundary={boundary.decode()}\r\n"
                f"Content-Length: {len(body)}\r\n\r\n".encode()
            )
            sock.sendall(body[: len(body) // 2])
            time.sleep(0.5)
        time.sleep(1.0)  # the server notices the disconnect
        assert runs_of(base, plan_id) == []
        # The server is still well: a whole upload of the same file is stored.
        whole = httpx2.post(
            f"{base}/api/plans/{plan_id}/runs",
            files={"file": ("log.csv", csv_log(HALF_CUT_FIXES))},
            headers=base.headers,
            timeout=120,
        )
        assert whole.status_code == 201 and whole.json()["fix_count"] == HALF_CUT_FIXES
    finally:
        server.stop()


@pytest.mark.parametrize("database_url", databases("postgresql"), indirect=True)
def test_a_server_killed_while_storing_a_log_stores_all_of_it_or_nothing(
    database_url: str, paper_polygon: dict[str, Any], tmp_path: Path
):
    server = ServerProcess(
        database_url, log=tmp_path / "server.log", serve_args=("--no-access-log",)
    )
    base = server.start()
    fixes = 120_000
    try:
        plan = httpx2.post(
            f"{base}/api/plans",
            json={"field": paper_polygon, "interval_m": 4},
            headers=base.headers,
        )
        plan_id = plan.json()["id"]
        data = csv_log(fixes)
        answers: list[int] = []

        def upload() -> None:
            try:
                response = httpx2.post(
                    f"{base}/api/plans/{plan_id}/runs",
                    files={"file": ("log.csv", data)},
                    timeout=120,
                )
                answers.append(response.status_code)
            except httpx2.TransportError:
                answers.append(0)

        uploader = threading.Thread(target=upload)
        uploader.start()
        time.sleep(2.5)  # parsing or storing by now, on this machine
        server.kill()
        uploader.join()
        base = server.start()
        stored = runs_of(base, plan_id)
        assert [run["fix_count"] for run in stored] in ([], [fixes])
        if answers == [201]:
            assert len(stored) == 1  # acknowledged, so it must be there
    finally:
        server.stop()
