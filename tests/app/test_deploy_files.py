"""docker-compose.yml and the Dockerfile carry what a deployment needs (Docker is not run here)."""

from __future__ import annotations

import re
import shlex
from pathlib import Path
from typing import Any

import yaml
from sqlalchemy.engine import make_url

ROOT = Path(__file__).resolve().parents[2]


def interpolate(value: str) -> str:
    """Resolve Compose's ``${VAR:-default}`` with the defaults, as on a machine without .env.

    A required variable (``${VAR:?message}``) becomes ``<VAR>``.
    """
    value = re.sub(r"\$\{([A-Z_]+):\?[^}]*\}", r"<\1>", value)
    return re.sub(r"\$\{[A-Z_]+:-([^}]*)\}", r"\1", value)


def test_compose_has_no_default_password():
    """Secrets come from the environment: Compose refuses to start without the password."""
    text = (ROOT / "docker-compose.yml").read_text()
    assert not re.search(r"PASSWORD:-", text)
    assert "${POSTGRES_PASSWORD:?" in text
    services = compose()["services"]
    assert interpolate(services["db"]["environment"]["POSTGRES_PASSWORD"]) == "<POSTGRES_PASSWORD>"


def compose() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load((ROOT / "docker-compose.yml").read_text())
    return data


def test_compose_runs_app_on_postgres_16_with_volume_and_healthcheck():
    services = compose()["services"]
    assert set(services) == {"app", "db"}
    db = services["db"]
    assert db["image"] == "postgres:16"
    volume, mount = db["volumes"][0].split(":")
    assert mount == "/var/lib/postgresql/data"
    assert volume in compose()["volumes"]  # a named volume, not a bind mount
    test = " ".join(db["healthcheck"]["test"])
    assert "pg_isready" in test
    assert f"-U {db['environment']['POSTGRES_USER']}" in test


def test_compose_app_waits_for_healthy_db_and_uses_its_url():
    services = compose()["services"]
    app, db = services["app"], services["db"]
    assert app["depends_on"]["db"]["condition"] == "service_healthy"
    assert app["build"] == "."
    url = make_url(interpolate(app["environment"]["TILLPATH_DATABASE_URL"]))
    env = db["environment"]
    assert url.drivername == "postgresql+psycopg"
    assert (url.host, url.port) == ("db", 5432)
    assert url.username == env["POSTGRES_USER"]
    assert url.password == interpolate(env["POSTGRES_PASSWORD"])
    assert url.database == env["POSTGRES_DB"]
    command = [interpolate(str(part)) for part in app["command"]]
    assert command[:2] == ["tillpath", "serve"]
    assert command[command.index("--host") + 1] == "0.0.0.0"
    port = command[command.index("--port") + 1]
    assert int(command[command.index("--workers") + 1]) >= 1
    assert any(interpolate(p).endswith(f":{port}") for p in app["ports"])


def dockerfile_instructions() -> list[tuple[str, str]]:
    text = (ROOT / "Dockerfile").read_text().replace("\\\n", " ")
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            keyword, _, rest = line.partition(" ")
            rows.append((keyword.upper(), rest.strip()))
    return rows


def test_dockerfile_builds_the_app_the_way_the_contract_says():
    rows = dockerfile_instructions()
    froms = [rest for keyword, rest in rows if keyword == "FROM"]
    assert froms[-1] == "python:3.11-slim"
    runs = " ".join(rest for keyword, rest in rows if keyword == "RUN")
    assert "npm ci" in runs
    assert "pip install ." in runs
    cmd = next(rest for keyword, rest in reversed(rows) if keyword == "CMD")
    assert cmd.startswith("[")
    args = yaml.safe_load(cmd)  # a JSON array is YAML too
    assert args[:2] == ["tillpath", "serve"] and args[args.index("--host") + 1] == "0.0.0.0"


def test_dockerfile_copies_only_files_that_exist():
    for keyword, rest in dockerfile_instructions():
        if keyword == "COPY" and not rest.startswith("--from"):
            *sources, _dest = shlex.split(rest)
            for source in sources:
                assert (ROOT / source).exists(), f"Dockerfile copies missing {source}"


def test_dockerignore_keeps_local_state_out_of_the_image():
    ignored = (ROOT / ".dockerignore").read_text().split()
    for entry in (".venv", "node_modules", "data", ".git"):
        assert entry in ignored
    for needed in ("app", "planner", "migrations", "templates", "static", "alembic.ini"):
        assert needed not in ignored
