"""Schemathesis over the OpenAPI spec of a real server: no answer ≥ 500 on either database.

Schemathesis (pinned in pyproject.toml) generates requests from ``/openapi.json`` (examples,
boundary and malformed values, random data and, in the long run, chains of calls that follow
the API's links) and checks ``not_a_server_error`` on every answer. Only in ``make soak``
(every phase, 50 examples): in ``make test`` and CI, tests/app/test_schemathesis.py runs
schemathesis over every operation on both databases already.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from app.testing import ServerProcess

pytestmark = pytest.mark.soak

MAX_EXAMPLES = 50
PHASES = "examples,coverage,fuzzing,stateful"


def test_schemathesis_finds_no_server_error(database_url: str, tmp_path: Path):
    server = ServerProcess(
        database_url, log=tmp_path / "server.log", serve_args=("--no-access-log",)
    )
    base = server.start()
    try:
        command = [
            *(sys.executable, "-m", "schemathesis.cli", "run", f"{base}/openapi.json"),
            *("--checks", "not_a_server_error"),
            *("--max-examples", str(MAX_EXAMPLES), "--phases", PHASES),
            *("--seed", "15", "--workers", "1", "--request-timeout", "60"),
            *("--generation-database", "none", "--no-color"),
            *("--header", f"Authorization: {base.headers['Authorization']}"),
        ]
        done = subprocess.run(
            command, cwd=tmp_path, capture_output=True, text=True, timeout=900, check=False
        )
    finally:
        server.stop()
    summary = re.search(r"(\d+) generated, (\d+) passed", done.stdout)
    assert done.returncode == 0 and summary, done.stdout[-8000:] + done.stderr[-2000:]
    assert int(summary.group(1)) > 50 and summary.group(1) == summary.group(2)
    print(f"\n{database_url.split(':')[0]}: schemathesis {summary.group(0)}")
