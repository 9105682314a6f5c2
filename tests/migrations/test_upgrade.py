"""Alembic migrations: up to head and back to base on an empty database, on both databases."""

from __future__ import annotations

from pathlib import Path

import pytest
from alembic import command
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import inspect
from typer.testing import CliRunner

import app.models  # noqa: F401  (registers the tables)
from app.cli import cli
from app.db import Base, alembic_config, make_engine, migration_engine, upgrade_database
from app.settings import get_settings

#: Every table at head.
HEAD_TABLES = {
    "alembic_version",
    "plans",
    "simulations",
    "runs",
    "fixes",
    "organisations",
    "users",
    "memberships",
    "api_tokens",
    "login_sessions",
    "login_attempts",
    "fields",
    "jobs",
}


def head_revision(url: str) -> str:
    head = ScriptDirectory.from_config(alembic_config(url)).get_current_head()
    assert head is not None
    return head


def current_revision(url: str) -> str | None:
    engine = migration_engine(url)
    try:
        with engine.connect() as conn:
            return MigrationContext.configure(conn).get_current_revision()
    finally:
        engine.dispose()


def tables(url: str) -> set[str]:
    engine = migration_engine(url)
    try:
        return set(inspect(engine).get_table_names())
    finally:
        engine.dispose()


def test_upgrade_head_then_downgrade_base(empty_database_url: str):
    url = empty_database_url
    assert tables(url) == set()

    upgrade_database(url)
    assert current_revision(url) == head_revision(url)
    assert tables(url) == HEAD_TABLES
    engine = migration_engine(url)
    try:
        inspector = inspect(engine)
        columns = {c["name"]: c for c in inspector.get_columns("plans")}
        assert set(columns) == {
            "id",
            "name",
            "created_at",
            "request",
            "stats",
            "waypoints",
            "geojson",
            "organisation_id",
            "field_id",
        }
        assert not columns["created_at"]["nullable"]
        assert columns["name"]["nullable"]
        assert sorted(i["name"] for i in inspector.get_indexes("plans")) == [
            "ix_plans_created_at",
            "ix_plans_field_id",
            "ix_plans_organisation_id",
        ]
        if engine.dialect.name == "postgresql":
            assert inspector.get_pk_constraint("plans")["name"] == "pk_plans"
    finally:
        engine.dispose()

    command.downgrade(alembic_config(url), "base")
    assert current_revision(url) is None
    assert tables(url) == {"alembic_version"}


def test_upgrade_is_idempotent(empty_database_url: str):
    upgrade_database(empty_database_url)
    upgrade_database(empty_database_url)
    assert current_revision(empty_database_url) == head_revision(empty_database_url)


def test_models_match_migrations(empty_database_url: str):
    upgrade_database(empty_database_url)
    engine = migration_engine(empty_database_url)
    try:
        with engine.connect() as conn:
            context = MigrationContext.configure(conn, opts={"compare_type": True})
            assert compare_metadata(context, Base.metadata) == []
    finally:
        engine.dispose()


def test_sqlite_file_gets_directory_wal_and_foreign_keys(tmp_path: Path):
    path = tmp_path / "nested" / "data" / "tillpath.db"
    engine = make_engine(f"sqlite:///{path}")
    try:
        with engine.connect() as conn:
            assert conn.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
            assert conn.exec_driver_sql("PRAGMA foreign_keys").scalar() == 1
    finally:
        engine.dispose()
    assert path.is_file()


@pytest.fixture
def settings_from_env(monkeypatch: pytest.MonkeyPatch, empty_database_url: str):
    monkeypatch.setenv("TILLPATH_DATABASE_URL", empty_database_url)
    get_settings.cache_clear()
    yield empty_database_url
    get_settings.cache_clear()


def test_cli_db_upgrade_migrates_the_configured_database(settings_from_env: str):
    result = CliRunner().invoke(cli, ["db", "upgrade"])
    assert result.exit_code == 0, result.output
    assert "up to date" in result.output
    assert tables(settings_from_env) == HEAD_TABLES


def test_cli_db_upgrade_unreachable_database_fails_cleanly(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv("TILLPATH_DATABASE_URL", f"sqlite:///{blocker}/sub/tillpath.db")
    get_settings.cache_clear()
    try:
        result = CliRunner().invoke(cli, ["db", "upgrade"])
    finally:
        get_settings.cache_clear()
    assert result.exit_code == 2
    assert "error: database: cannot migrate" in result.output


def test_alembic_config_points_at_this_project():
    config = alembic_config("sqlite://")
    assert Path(config.get_main_option("script_location") or "").name == "migrations"
    assert (Path(config.get_main_option("script_location") or "") / "env.py").is_file()


def test_fixes_are_keyed_by_run_and_time_and_cascade_from_plans(empty_database_url: str):
    url = empty_database_url
    upgrade_database(url)
    engine = migration_engine(url)
    try:
        inspector = inspect(engine)
        assert inspector.get_pk_constraint("fixes")["constrained_columns"] == ["run_id", "t"]
        for table, column, parent in [
            ("simulations", "plan_id", "plans"),
            ("runs", "plan_id", "plans"),
            ("fixes", "run_id", "runs"),
        ]:
            (fk,) = [
                fk
                for fk in inspector.get_foreign_keys(table)
                if fk["constrained_columns"] == [column]
            ]
            assert fk["referred_table"] == parent
            assert fk["options"].get("ondelete") == "CASCADE"
    finally:
        engine.dispose()


def test_each_revision_downgrades_to_its_parent(empty_database_url: str):
    url = empty_database_url
    upgrade_database(url)
    command.downgrade(alembic_config(url), "0002")
    assert tables(url) == {"alembic_version", "plans", "simulations"}
    command.downgrade(alembic_config(url), "0001")
    assert tables(url) == {"alembic_version", "plans"}
    upgrade_database(url)
    assert "fixes" in tables(url)
