"""``tillpath users create`` and ``tillpath tokens create`` as an administrator runs them."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from starlette.testclient import TestClient
from typer.testing import CliRunner

from app.cli import cli
from app.main import create_app
from app.settings import Settings, get_settings

TILLPATH = [sys.executable, "-c", "from app.cli import main; main()"]


@pytest.fixture
def database(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'data' / 'tillpath.db'}"


def run(database: str, *args: str, stdin: str = "") -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "TILLPATH_DATABASE_URL": database}
    return subprocess.run(
        [*TILLPATH, *args], input=stdin, capture_output=True, text=True, env=env, timeout=120
    )


@pytest.mark.slow
def test_users_and_tokens_from_the_command_line_work_on_the_api(database: str) -> None:
    made = run(
        database,
        "users",
        "create",
        "ayu",
        "--org",
        "Subak",
        "--role",
        "owner",
        "--password-stdin",
        stdin="a long password\n",
    )
    assert made.returncode == 0, made.stderr
    assert "created user 'ayu' the role owner in organisation 'Subak'" in made.stderr
    assert "a long password" not in made.stdout + made.stderr

    personal = run(database, "tokens", "create", "--user", "ayu", "--name", "scripts")
    device = run(database, "tokens", "create", "--user", "ayu", "--device", "--name", "tractor")
    assert personal.returncode == device.returncode == 0, personal.stderr + device.stderr
    token = personal.stdout.splitlines()[-1]
    device_token = device.stdout.splitlines()[-1]
    assert token.startswith("tp_") and device_token.startswith("tp_") and token != device_token

    app = create_app(Settings(database_url=database))
    with TestClient(app, headers={"Authorization": f"Bearer {token}"}) as script:
        me = script.get("/api/me").json()
        assert me["organisation"]["name"] == "Subak" and me["organisation"]["role"] == "owner"
        listed = {t["name"]: t["kind"] for t in script.get("/api/tokens").json()["items"]}
        assert listed == {"scripts": "personal", "tractor": "device"}
    with TestClient(app, headers={"Authorization": f"Bearer {device_token}"}) as logger:
        assert logger.get("/api/plans").status_code == 403
    with TestClient(app) as browser:
        login = browser.post(
            "/api/auth/login", json={"username": "ayu", "password": "a long password"}
        )
        assert login.status_code == 200


@pytest.mark.slow
def test_a_second_organisation_for_an_existing_user_keeps_the_password(database: str) -> None:
    assert run(database, "users", "create", "made", "--password-stdin", stdin="first pass\n")
    again = run(
        database,
        "users",
        "create",
        "made",
        "--org",
        "farm",
        "--role",
        "viewer",
        "--password-stdin",
        stdin="other pass\n",
    )
    assert again.returncode == 0 and "existing password was kept" in again.stderr
    app = create_app(Settings(database_url=database))
    with TestClient(app) as browser:
        ok = browser.post("/api/auth/login", json={"username": "made", "password": "first pass"})
        assert ok.status_code == 200
        assert {o["name"]: o["role"] for o in ok.json()["organisations"]} == {
            "default": "owner",
            "farm": "viewer",
        }


@pytest.mark.parametrize(
    ("args", "stdin", "message"),
    [
        (("users", "create", "x"), "", "error: --password-stdin: give the password"),
        (("users", "create", "x", "--password-stdin"), "short\n", "error: password: must be"),
        (("users", "create", "<x>", "--password-stdin"), "long enough\n", "error: username:"),
        (("tokens", "create", "--user", "nobody"), "", "error: --user: no user called 'nobody'"),
    ],
)
def test_bad_input_is_an_error_line_and_status_2(
    database: str,
    args: tuple[str, ...],
    stdin: str,
    message: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # In process (typer's runner), so that five cases do not start five interpreters.
    monkeypatch.setenv("TILLPATH_DATABASE_URL", database)
    get_settings.cache_clear()
    try:
        result = CliRunner().invoke(cli, list(args), input=stdin)
    finally:
        get_settings.cache_clear()
    assert result.exit_code == 2, result.output
    assert message in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
