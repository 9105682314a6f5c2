"""Alembic environment: migrate the database named by the caller or by the app's settings.

The URL comes, in order, from an open connection the caller hands over
(``config.attributes["connection"]``, used by tests on in-memory SQLite), from
``sqlalchemy.url`` set by the caller (``app.db.alembic_config``), or from
``TILLPATH_DATABASE_URL`` through the app's settings. SQLite gets batch mode so that later
migrations can alter columns.
"""

from __future__ import annotations

from logging.config import fileConfig

from alembic import context
from sqlalchemy import Connection

import app.models  # noqa: F401  (registers the tables on Base.metadata)
from app.db import Base, migration_engine
from app.settings import get_settings

config = context.config
if config.config_file_name is not None and config.attributes.get("configure_logger", True):
    fileConfig(config.config_file_name, disable_existing_loggers=False)

target_metadata = Base.metadata


def database_url() -> str:
    url = config.get_main_option("sqlalchemy.url")
    return url or get_settings().database_url


def _sqlite_foreign_keys(connection: Connection, on: bool) -> None:
    """Turn SQLite's foreign keys off for a migration, back on after it.

    Batch migrations rebuild a table by copying it and dropping the old one; with foreign keys
    on, that DROP deletes the rows that reference it (ON DELETE CASCADE). The PRAGMA only
    works outside a transaction, so it goes straight to the driver's connection (the app's
    connections let SQLAlchemy emit BEGIN itself; see app.db).
    """
    if connection.dialect.name != "sqlite" or connection.in_transaction():
        return
    dbapi = connection.connection.dbapi_connection
    assert dbapi is not None
    dbapi.execute(f"PRAGMA foreign_keys={'ON' if on else 'OFF'}")


def run_with(connection: Connection) -> None:
    _sqlite_foreign_keys(connection, on=False)
    try:
        _run_with(connection)
    finally:
        _sqlite_foreign_keys(connection, on=True)


def _run_with(connection: Connection) -> None:
    context.configure(
        connection=connection,
        target_metadata=target_metadata,
        render_as_batch=connection.dialect.name == "sqlite",
        # app.db makes SQLAlchemy emit BEGIN on SQLite, so its DDL is transactional too.
        transactional_ddl=True,
        compare_type=True,
    )
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_offline() -> None:
    url = database_url()
    context.configure(
        url=url,
        target_metadata=target_metadata,
        literal_binds=True,
        dialect_opts={"paramstyle": "named"},
        render_as_batch=url.startswith("sqlite"),
    )
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_online() -> None:
    connection = config.attributes.get("connection")
    if connection is not None:
        run_with(connection)
        return
    engine = migration_engine(database_url())
    try:
        with engine.connect() as connection:
            run_with(connection)
            connection.commit()
    finally:
        engine.dispose()


if context.is_offline_mode():
    run_migrations_offline()
else:
    run_migrations_online()
