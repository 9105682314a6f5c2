"""A bounded mixed load on a real server: no answer ≥ 500, no acknowledged write lost.

Plans, previews, uploads, live fixes, polls, simulations and deletes racing reads, from
several threads for a fixed time (:mod:`app.testing_load`), on SQLite and PostgreSQL; then the
same with the server killed (SIGKILL) and restarted in the middle.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any

import pytest

from app.testing import ServerProcess
from app.testing_load import mixed_load, verify
from tests.soak.conftest import LONG, SOAK_S, SOAK_THREADS, databases

#: Worker processes of the server: two (processes racing on one database) in the short run,
#: one and two in the long one.
WORKERS = [1, 2] if LONG else [2]

pytestmark = pytest.mark.soak


def describe(result: Any) -> str:
    return (
        f"{result.requests} requests, statuses {dict(sorted(result.statuses.items()))}, "
        f"p99 {result.percentile_ms(0.99):.0f} ms; 5xx: {result.server_errors[:5]}"
    )


@pytest.mark.parametrize("workers", WORKERS)
def test_mixed_load_answers_no_5xx_and_keeps_every_acknowledged_write(
    database_url: str, paper_polygon: dict[str, Any], tmp_path: Path, workers: int
):
    server = ServerProcess(
        database_url,
        log=tmp_path / "server.log",
        serve_args=("--workers", str(workers), "--no-access-log"),
    )
    base = server.start()
    try:
        result = mixed_load(
            lambda: base,
            paper_polygon,
            duration_s=SOAK_S,
            threads=SOAK_THREADS,
            headers=base.headers,
        )
        assert result.errors_5xx == 0, describe(result)
        assert result.statuses[0] == 0, describe(result)  # every request was answered
        assert result.plans and result.fixes and result.requests > 20, describe(result)
        assert verify(base, result, headers=base.headers) == []
        print(f"\n{database_url.split(':')[0]}, {workers} worker(s): {describe(result)}")
    finally:
        server.stop()


@pytest.mark.parametrize("database_url", databases("sqlite"), indirect=True)
def test_a_server_killed_mid_load_loses_no_acknowledged_write(
    database_url: str, paper_polygon: dict[str, Any], tmp_path: Path
):
    server = ServerProcess(
        database_url, log=tmp_path / "server.log", serve_args=("--no-access-log",)
    )
    headers = server.start().headers

    def kill_and_restart() -> None:
        time.sleep(SOAK_S / 2)
        server.kill()  # SIGKILL, mid-request: no shutdown, no commit
        server.start()

    restarter = threading.Thread(target=kill_and_restart)
    try:
        restarter.start()
        result = mixed_load(
            lambda: server.base_url,
            paper_polygon,
            duration_s=SOAK_S + 2,
            threads=SOAK_THREADS,
            headers=headers,
        )
        restarter.join()
        assert result.errors_5xx == 0, describe(result)
        assert result.statuses[0] > 0, describe(result)  # the kill did cut requests off
        assert verify(server.base_url, result, headers=headers) == []
    finally:
        restarter.join()
        server.stop()
