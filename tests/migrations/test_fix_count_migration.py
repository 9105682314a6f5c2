"""Revision 20261201_15 counts each existing run's fixes onto its row (both databases)."""

from __future__ import annotations

from alembic import command
from sqlalchemy import inspect

from app.db import alembic_config, migration_engine, upgrade_database
from tests.migrations.test_workspace_migration import rows, seed_pre_workspace_rows


def test_existing_runs_get_their_fix_counts_and_lose_them_on_the_way_back(
    empty_database_url: str,
):
    url = empty_database_url
    upgrade_database(url, revision="0003")
    seed_pre_workspace_rows(url)  # run 1 with 5 fixes, run 2 with none
    upgrade_database(url, revision="20261201_10")
    extra = [(1, t, -8.6, 115.3) for t in range(100, 103)]
    engine = migration_engine(url)
    try:
        with engine.begin() as conn:
            conn.exec_driver_sql(
                "INSERT INTO fixes (run_id, t, lat, lon) VALUES (?, ?, ?, ?)"
                if engine.dialect.name == "sqlite"
                else "INSERT INTO fixes (run_id, t, lat, lon) VALUES (%s, %s, %s, %s)",
                extra,
            )
    finally:
        engine.dispose()

    upgrade_database(url)
    assert rows(url, "SELECT id, fix_count FROM runs ORDER BY id") == [(1, 8), (2, 0)]

    command.downgrade(alembic_config(url), "20261201_10")
    engine = migration_engine(url)
    try:
        assert "fix_count" not in {c["name"] for c in inspect(engine).get_columns("runs")}
    finally:
        engine.dispose()
    assert rows(url, "SELECT count(*) FROM fixes") == [(8,)]
