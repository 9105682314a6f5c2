"""While a tractor streams its fixes, sign-in and the workspace's changes are never busy (503).

Under a real uvicorn server on committed sessions (SQLite file; PostgreSQL when configured).
On SQLite, a change that read (the throttle table, the caller's token, the last owner) and then
wrote in the same transaction was refused "database is locked" whenever another client had
written meanwhile: SQLite cannot make a read transaction with an old snapshot a write one, and
says so at once instead of waiting.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import httpx2

from app.testing import ServerUrl
from tests.app.test_live_server import PAPER, database_url, server_url  # noqa: F401

T0 = 1_795_305_600.0  # 2026-11-22T00:00:00Z [s]


@contextmanager
def fixes_streaming(base: ServerUrl) -> Iterator[list[int]]:
    """Post fixes to a new run, five at a time, until the block ends; yield what was stored."""
    with httpx2.Client(base_url=base, headers=base.headers, timeout=30) as tractor:
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
            yield stored
        finally:
            stop.set()
            writer.join(timeout=30)
    assert not failures, failures


def test_sign_in_while_fixes_stream_in_is_never_busy(server_url: ServerUrl):  # noqa: F811
    account = server_url.account
    with fixes_streaming(server_url) as stored, httpx2.Client(base_url=server_url) as technician:
        answers = [
            technician.post(
                "/api/auth/login",
                json={"username": account.username, "password": account.password},
            )
            for _ in range(8)
        ]
    assert [a.status_code for a in answers] == [200] * 8, [a.text for a in answers]
    assert len(stored) >= 8, "the fixes did not stream while the technician signed in"


def test_workspace_changes_while_fixes_stream_in_are_never_busy(
    server_url: ServerUrl,  # noqa: F811
):
    changes = 0

    def done(answer: httpx2.Response) -> Any:
        nonlocal changes
        assert not answer.is_error, (answer.request.method, answer.request.url.path, answer.text)
        changes += 1
        return answer.json() if answer.content else None

    with (
        fixes_streaming(server_url) as stored,
        httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=30) as owner,
    ):
        for round_ in range(3):
            field = done(owner.post("/api/fields", json={"name": f"n{round_}", "boundary": PAPER}))
            done(owner.patch(f"/api/fields/{field['id']}", json={"name": f"south {round_}"}))
            done(owner.delete(f"/api/fields/{field['id']}", params={"plans": "keep"}))
            token = done(owner.post("/api/tokens", json={"name": f"script {round_}"}))
            done(owner.delete(f"/api/tokens/{token['id']}"))
            body = {"username": f"helper{round_}", "role": "viewer", "password": "a" * 12}
            member = done(owner.post("/api/members", json=body))
            done(owner.patch(f"/api/members/{member['user_id']}", json={"role": "planner"}))
            done(owner.delete(f"/api/members/{member['user_id']}"))
    assert changes == 24
    assert len(stored) >= 8, "the fixes did not stream while the owner changed the workspace"
