"""Signing in while a tractor streams its fixes: every sign-in is answered 200, none 503.

Under a real uvicorn server on committed sessions (SQLite file; PostgreSQL when configured).
On SQLite a sign-in that read the throttle table, checked the password (argon2, tens of ms) and
then wrote in the same transaction was refused "database is locked" whenever another client
had written meanwhile: SQLite cannot make a read transaction with an old snapshot a write one,
and it says so at once instead of waiting.
"""

from __future__ import annotations

import threading
from typing import Any

import httpx2

from app.testing import ServerUrl
from tests.app.test_live_server import PAPER, database_url, server_url  # noqa: F401

T0 = 1_795_305_600.0  # 2026-11-22T00:00:00Z [s]


def test_sign_in_while_fixes_stream_in_is_never_busy(server_url: ServerUrl):  # noqa: F811
    account = server_url.account
    with httpx2.Client(base_url=server_url, headers=account.headers, timeout=30) as tractor:
        plan = tractor.post("/api/plans", json={"field": PAPER, "interval_m": 4}).json()
        run = tractor.post(f"/api/plans/{plan['id']}/runs").json()
        stop = threading.Event()
        stored: list[int] = []
        failures: list[str] = []

        def stream() -> None:
            i = 0
            while not stop.is_set():
                fixes: list[dict[str, Any]] = [
                    {"t": T0 + (i + k) / 10, "lat": -8.6265 + (i + k) * 1e-8, "lon": 115.298}
                    for k in range(5)
                ]
                answer = tractor.post(f"/api/runs/{run['id']}/fixes", json=fixes)
                if answer.status_code != 200:
                    failures.append(answer.text)
                    return
                stored.append(answer.json()["stored"])
                i += 5

        writer = threading.Thread(target=stream, daemon=True)
        writer.start()
        try:
            with httpx2.Client(base_url=server_url, timeout=30) as technician:
                answers = [
                    technician.post(
                        "/api/auth/login",
                        json={"username": account.username, "password": account.password},
                    )
                    for _ in range(8)
                ]
        finally:
            stop.set()
            writer.join(timeout=30)
    assert [a.status_code for a in answers] == [200] * 8, [a.text for a in answers]
    assert not failures, failures
    assert len(stored) >= 8, "the fixes did not stream while the technician signed in"
