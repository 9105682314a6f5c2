"""The workspace migration moves existing rows into ``default``, losing nothing (both databases)."""

from __future__ import annotations

import datetime as dt
import json
from typing import Any

import sqlalchemy as sa
from alembic import command

from app.db import alembic_config, migration_engine, upgrade_database
from app.fields import boundary_sha256

SQUARE = {
    "type": "Polygon",
    "coordinates": [
        [[115.298, -8.6265], [115.2982, -8.6265], [115.2982, -8.6263], [115.298, -8.6265]]
    ],
}


def rows(url: str, sql: str) -> list[Any]:
    engine = migration_engine(url)
    try:
        with engine.connect() as conn:
            return list(conn.execute(sa.text(sql)).all())
    finally:
        engine.dispose()


def seed_pre_workspace_rows(url: str) -> None:
    """Three plans (one nameless), a simulation, two runs and fixes, as revision 0003 had."""
    engine = migration_engine(url)
    created = dt.datetime(2026, 11, 22, 3, 0, tzinfo=dt.UTC)
    if engine.dialect.name == "sqlite":
        created = created.replace(tzinfo=None)
    try:
        with engine.begin() as conn:
            for i, name in enumerate(["Sawah A", None, "Sawah <C>"], start=1):
                request = {
                    "name": name,
                    "field": SQUARE,
                    "interval_m": 4,
                    "start": [115.298, -8.6266],
                    "finish": None,
                }
                conn.execute(
                    sa.text(
                        "INSERT INTO plans (id, name, created_at, request, stats, waypoints, "
                        "geojson) "
                        "VALUES (:id, :name, :created, :request, '{}', '[]', :geojson)"
                    ),
                    {
                        "id": i,
                        "name": name,
                        "created": created,
                        "request": json.dumps(request),
                        "geojson": json.dumps({"type": "FeatureCollection", "features": []}),
                    },
                )
            conn.execute(
                sa.text(
                    "INSERT INTO simulations (id, plan_id, created_at, config, metrics, tracks) "
                    "VALUES (1, 1, :c, '{}', '{}', '{}')"
                ),
                {"c": created},
            )
            for run_id, plan_id in ((1, 1), (2, 3)):
                conn.execute(
                    sa.text(
                        "INSERT INTO runs (id, plan_id, name, source, created_at, import_report) "
                        "VALUES (:r, :p, 'run', 'live', :c, '{}')"
                    ),
                    {"r": run_id, "p": plan_id, "c": created},
                )
            for t in range(5):
                conn.execute(
                    sa.text("INSERT INTO fixes (run_id, t, lat, lon) VALUES (1, :t, -8.6, 115.3)"),
                    {"t": t},
                )
    finally:
        engine.dispose()


def test_existing_plans_move_into_default_each_with_its_own_field(empty_database_url: str):
    url = empty_database_url
    upgrade_database(url, revision="0003")
    seed_pre_workspace_rows(url)
    upgrade_database(url)

    (org,) = rows(url, "SELECT id, name FROM organisations")
    assert org[1] == "default"
    plans = rows(url, "SELECT id, name, organisation_id, field_id FROM plans ORDER BY id")
    assert [(p[0], p[1]) for p in plans] == [(1, "Sawah A"), (2, None), (3, "Sawah <C>")]
    assert {p[2] for p in plans} == {org[0]}
    fields = {
        f[0]: f
        for f in rows(
            url, "SELECT id, organisation_id, name, boundary, boundary_sha256, start FROM fields"
        )
    }
    assert len(fields) == 3 and len({p[3] for p in plans}) == 3  # a field of its own each
    by_plan = {p[0]: fields[p[3]] for p in plans}
    assert [by_plan[i][2] for i in (1, 2, 3)] == ["Sawah A", "plan 2", "Sawah <C>"]
    for field in fields.values():
        boundary = field[3] if isinstance(field[3], dict) else json.loads(field[3])
        assert boundary == SQUARE and field[4] == boundary_sha256(SQUARE)
        start = field[5] if isinstance(field[5], list) else json.loads(field[5])
        assert start == [115.298, -8.6266]
    assert rows(url, "SELECT organisation_id FROM simulations") == [(org[0],)]
    assert sorted(rows(url, "SELECT id, organisation_id FROM runs")) == [(1, org[0]), (2, org[0])]
    # Rebuilding plans on SQLite must not cascade into its runs and their fixes.
    assert rows(url, "SELECT count(*) FROM fixes") == [(5,)]

    # And back: the rows stay, only the new columns and tables go.
    command.downgrade(alembic_config(url), "0003")
    assert rows(url, "SELECT count(*) FROM plans") == [(3,)]
    assert rows(url, "SELECT count(*) FROM fixes") == [(5,)]


def test_an_empty_database_gets_no_default_organisation(empty_database_url: str):
    upgrade_database(empty_database_url)
    assert rows(empty_database_url, "SELECT count(*) FROM organisations") == [(0,)]
