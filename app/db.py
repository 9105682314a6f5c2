"""Database plumbing: the declarative ``Base``, engines, sessions and migrations.

One engine per database URL, cached for the process. SQLite gets WAL, foreign keys and a busy
timeout on every connection, and SQLAlchemy's recipe for correct ``SAVEPOINT`` handling with
pysqlite (the driver's own transaction handling would otherwise skip ``BEGIN``). Migrations are
Alembic's, in ``migrations/`` beside ``alembic.ini`` at the top of the project.
"""

from __future__ import annotations

from collections.abc import Iterator
from functools import lru_cache
from pathlib import Path
from typing import Annotated, Any

from alembic import command
from alembic.config import Config
from fastapi import Depends
from sqlalchemy import Connection, Engine, MetaData, create_engine, event
from sqlalchemy.engine import make_url
from sqlalchemy.orm import DeclarativeBase, Session
from sqlalchemy.pool import NullPool

from app.settings import Settings, get_settings

#: Alembic's recommended constraint names, so that migrations can name what they drop.
NAMING_CONVENTION: dict[str, str] = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}

#: How long a SQLite connection waits for another writer before giving up [ms].
SQLITE_BUSY_TIMEOUT_MS = 5000


class Base(DeclarativeBase):
    """Declarative base of every table, with the Alembic naming convention."""

    metadata = MetaData(naming_convention=NAMING_CONVENTION)


def is_sqlite(url: str) -> bool:
    """Return True if ``url`` names a SQLite database."""
    return make_url(url).get_backend_name() == "sqlite"


def make_engine(url: str, **kwargs: Any) -> Engine:
    """Create an engine for ``url``, set up for this app.

    For a SQLite file, the directory is created if missing, and every connection gets
    ``journal_mode=WAL``, ``foreign_keys=ON`` and a busy timeout. Other databases get
    ``pool_pre_ping`` so that a restarted server does not fail the first request.

    Parameters
    ----------
    url : str
        SQLAlchemy database URL.
    **kwargs
        Passed to :func:`sqlalchemy.create_engine` (``poolclass``, ``connect_args`` …).

    Returns
    -------
    Engine
    """
    parsed = make_url(url)
    if parsed.get_backend_name() != "sqlite":
        kwargs.setdefault("pool_pre_ping", True)
        return create_engine(url, **kwargs)

    database = parsed.database
    if database and database != ":memory:" and not database.startswith("file:"):
        Path(database).expanduser().parent.mkdir(parents=True, exist_ok=True)
    connect_args = dict(kwargs.pop("connect_args", {}))
    connect_args.setdefault("check_same_thread", False)
    engine = create_engine(url, connect_args=connect_args, **kwargs)

    @event.listens_for(engine, "connect")
    def _sqlite_on_connect(dbapi_connection: Any, _record: Any) -> None:
        # Let SQLAlchemy emit BEGIN itself (pysqlite's own handling breaks SAVEPOINT).
        dbapi_connection.isolation_level = None
        cursor = dbapi_connection.cursor()
        cursor.execute("PRAGMA journal_mode=WAL")
        cursor.execute("PRAGMA foreign_keys=ON")
        cursor.execute(f"PRAGMA busy_timeout={SQLITE_BUSY_TIMEOUT_MS}")
        cursor.close()

    @event.listens_for(engine, "begin")
    def _sqlite_on_begin(connection: Connection) -> None:
        connection.exec_driver_sql("BEGIN")

    return engine


@lru_cache(maxsize=8)
def get_engine(url: str) -> Engine:
    """Return the process-wide engine for ``url`` (one per URL)."""
    return make_engine(url)


def get_session(settings: Annotated[Settings, Depends(get_settings)]) -> Iterator[Session]:
    """Yield a session on the configured database, closed after the request.

    Objects stay loaded after ``commit`` (``expire_on_commit=False``), so a route can return
    what it just stored without another query.
    """
    with Session(get_engine(settings.database_url), expire_on_commit=False) as session:
        yield session


SessionDep = Annotated[Session, Depends(get_session)]


def project_root() -> Path:
    """Return the directory that holds ``alembic.ini`` and ``migrations/``.

    That is the installed wheel's copy (:func:`app.resources.resource_root`), the checkout the
    ``app`` package was imported from, or else the current directory.
    """
    from app.resources import resource_root

    candidates = [resource_root(), Path(__file__).resolve().parent.parent, Path.cwd()]
    for root in candidates:
        if (root / "alembic.ini").is_file() and (root / "migrations" / "env.py").is_file():
            return root
    raise FileNotFoundError(
        "alembic.ini and migrations/ not found beside the app package nor in the current "
        "directory; run tillpath from the project directory"
    )


def alembic_config(url: str, *, connection: Connection | None = None) -> Config:
    """Build the Alembic configuration for ``url``.

    Parameters
    ----------
    url : str
        Database to migrate.
    connection : Connection, optional
        An open connection to migrate on (tests use it for in-memory SQLite); the URL is then
        only informative.

    Returns
    -------
    Config
    """
    root = project_root()
    config = Config(str(root / "alembic.ini"))
    config.set_main_option("script_location", str(root / "migrations"))
    # ConfigParser interpolates %; escape it (passwords may contain it).
    config.set_main_option("sqlalchemy.url", url.replace("%", "%%"))
    if connection is not None:
        config.attributes["connection"] = connection
    return config


def upgrade_database(url: str, *, revision: str = "head") -> None:
    """Apply the migrations to ``url`` up to ``revision``."""
    command.upgrade(alembic_config(url), revision)


def migration_engine(url: str) -> Engine:
    """Return an engine for running migrations once (no pool kept)."""
    return make_engine(url, poolclass=NullPool)
