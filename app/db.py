"""Database plumbing: the declarative ``Base``, engines, sessions and migrations.

One engine per database URL, cached for the process. SQLite gets WAL, foreign keys and a busy
timeout on every connection, and SQLAlchemy's recipe for correct ``SAVEPOINT`` handling with
pysqlite (the driver's own transaction handling would otherwise skip ``BEGIN``). Migrations are
Alembic's, in ``migrations/`` beside ``alembic.ini`` at the top of the project.

Writes are short and separate from reads (:func:`write`): a route reads what it needs, ends that
read transaction (:func:`end_reads`, which also hands the connection back to the pool), computes
(planning, scoring, simulating) with no connection held, and then stores the result in one write
transaction of its own, retried when it races another writer. On SQLite that transaction starts
with ``BEGIN IMMEDIATE``, so it waits for the write lock (the busy timeout) instead of failing
with "database is locked" when a read transaction would have to become a write one.
"""

from __future__ import annotations

import random
import time
from collections.abc import AsyncIterator, Callable
from functools import lru_cache
from pathlib import Path
from typing import Annotated, Any, Final, TypeVar

from alembic import command
from alembic.config import Config
from fastapi import Depends
from fastapi.concurrency import run_in_threadpool
from sqlalchemy import (
    Connection,
    CursorResult,
    Engine,
    MetaData,
    create_engine,
    delete,
    event,
    inspect,
    select,
    text,
)
from sqlalchemy.engine import make_url
from sqlalchemy.exc import DBAPIError, IntegrityError
from sqlalchemy.orm import DeclarativeBase, Session
from sqlalchemy.pool import NullPool

from app.dependencies import SettingsDep
from app.errors import ConflictError, DatabaseBusyError, NotFoundError

#: Alembic's recommended constraint names, so that migrations can name what they drop.
NAMING_CONVENTION: dict[str, str] = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}

#: How long a SQLite connection waits for another writer before giving up [ms].
SQLITE_BUSY_TIMEOUT_MS = 10_000
#: Connections an engine keeps open, how many more it may open under load, and how long a
#: request waits for one before the answer is 503 [s]. A request holds one only for its
#: database work, so a pool this size serves the threads of one worker.
POOL_SIZE: Final = 10
POOL_MAX_OVERFLOW: Final = 20
POOL_TIMEOUT_S: Final = 10.0
#: Tries of a write transaction that races another writer, and the first back-off [s].
WRITE_ATTEMPTS: Final = 4
WRITE_BACKOFF_S: Final = 0.05
#: Execution option that makes SQLite's next ``BEGIN`` a ``BEGIN IMMEDIATE``.
_IMMEDIATE: Final = "tillpath_begin_immediate"
#: SQLSTATEs of PostgreSQL errors that a retried transaction can overcome.
_PG_RETRY_SQLSTATES: Final = frozenset({"40001", "40P01", "55P03"})

T = TypeVar("T")


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
    if kwargs.get("poolclass") is None and parsed.database not in (None, "", ":memory:"):
        kwargs.setdefault("pool_size", POOL_SIZE)
        kwargs.setdefault("max_overflow", POOL_MAX_OVERFLOW)
        kwargs.setdefault("pool_timeout", POOL_TIMEOUT_S)
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
        immediate = connection.get_execution_options().get(_IMMEDIATE, False)
        connection.exec_driver_sql("BEGIN IMMEDIATE" if immediate else "BEGIN")

    return engine


@lru_cache(maxsize=8)
def get_engine(url: str) -> Engine:
    """Return the process-wide engine for ``url`` (one per URL)."""
    return make_engine(url)


async def get_session(
    settings: SettingsDep,
) -> AsyncIterator[Session]:
    """Yield a session on the configured database, closed after the request.

    Objects stay loaded after ``commit`` (``expire_on_commit=False``), so a route can return
    what it just stored without another query.

    Async so that FastAPI runs it on the event loop, not in a worker thread (two thread hops
    per request otherwise): making a session does no I/O (it connects at its first query),
    and closing one does none either once its transaction has ended. A session still in a
    transaction (a read route) is closed in a worker thread, since its rollback may wait for
    the database.
    """
    session = Session(get_engine(settings.database_url), expire_on_commit=False)
    try:
        yield session
    finally:
        if session.in_transaction():
            await run_in_threadpool(session.close)
        else:
            session.close()


SessionDep = Annotated[Session, Depends(get_session)]


# --- short transactions --------------------------------------------------------------------


def end_reads(session: Session) -> None:
    """End the session's read transaction, if any, and hand its connection back to the pool.

    Call it after loading what a computation needs and before computing: the connection is
    then free for other requests, and SQLite holds no snapshot open. Nothing has been written,
    so committing changes nothing; objects stay loaded (``expire_on_commit=False``).
    """
    if session.in_transaction():
        session.commit()


def begin_write(session: Session) -> None:
    """End the session's reads and begin the transaction that reads and writes a change.

    For a change whose checks must hold when it is written (the last owner of an
    organisation, a token the caller may see): the checks and the writes share one
    transaction, which on SQLite begins with ``BEGIN IMMEDIATE`` and so waits for the write
    lock (the busy timeout). Begun as a read, it would fail at once with "database is locked"
    whenever another client (a tractor's fixes) wrote before it did. The caller commits.
    """
    end_reads(session)
    session.connection(execution_options={_IMMEDIATE: True})


def serialise_writes(session: Session, key: int) -> None:
    """Make the session's write transaction wait until no other holds ``key``, and hold it.

    For a check that must see what a concurrent transaction of the same kind committed, such
    as "no user yet" before the first sign-up. On PostgreSQL (READ COMMITTED) two such
    transactions would each see no user and both add one; this takes the transaction-level
    advisory lock ``key``, released at commit or rollback, and every statement after it sees
    what the previous holder committed. On SQLite nothing is needed: the write transaction
    (:func:`begin_write`, ``BEGIN IMMEDIATE``) already holds the database's one write lock.
    Call it first in the write transaction.
    """
    connection = session.connection()
    if connection.dialect.name == "postgresql":
        connection.execute(text("SELECT pg_advisory_xact_lock(:key)"), {"key": key})


def is_transient(exc: BaseException) -> bool:
    """Return True if ``exc`` is a write that lost a race and may succeed when retried.

    SQLite's "database is locked"/"busy" (another writer held the lock past the busy timeout)
    and PostgreSQL's serialization failures, deadlocks and lock timeouts.
    """
    if not isinstance(exc, DBAPIError):
        return False
    orig = exc.orig
    if getattr(orig, "sqlstate", None) in _PG_RETRY_SQLSTATES:
        return True
    message = str(orig).lower()
    return "database is locked" in message or "database is busy" in message


def write(
    session: Session,
    work: Callable[[Session], T],
    *,
    parent: tuple[type[Base], int, str] | None = None,
    attempts: int = WRITE_ATTEMPTS,
) -> T:
    """Run ``work`` in a write transaction of its own, commit it, and return what it returns.

    The session's read transaction is ended first (:func:`end_reads`). On SQLite the write
    starts with ``BEGIN IMMEDIATE``. A transaction that loses a race (see :func:`is_transient`)
    is rolled back and run again, after a short random back-off; ``work`` must therefore make
    its rows afresh each time it is called, from values read beforehand (a rollback expires
    every row the session had loaded).

    Parameters
    ----------
    session : Session
    work : callable
        ``work(session)`` adds or changes rows; it must not commit.
    parent : (model, id, kind), optional
        The row the new rows refer to (a run's plan, say). If the write fails on a foreign
        key because that row was deleted meanwhile, the answer is ``<kind> <id> not found``.
    attempts : int
        Tries before giving up.

    Returns
    -------
    object
        What ``work`` returned.

    Raises
    ------
    NotFoundError
        If ``parent`` no longer exists.
    ConflictError
        If the write breaks another constraint (a concurrent change).
    DatabaseBusyError
        If the database stayed locked through every try (503 with ``Retry-After``).
    """
    end_reads(session)
    for attempt in range(1, attempts + 1):
        try:
            session.connection(execution_options={_IMMEDIATE: True})
            result = work(session)
            session.commit()
            return result
        except IntegrityError as exc:
            session.rollback()
            if parent is not None and not _exists(session, *parent[:2]):
                raise NotFoundError(parent[2], parent[1]) from exc
            raise ConflictError(
                "the request conflicts with a change made at the same time; read the object "
                "again and retry"
            ) from exc
        except DBAPIError as exc:
            session.rollback()
            if not is_transient(exc):
                raise
            if attempt == attempts:
                raise DatabaseBusyError() from exc
            time.sleep(WRITE_BACKOFF_S * 2 ** (attempt - 1) * (0.5 + random.random()))
        except BaseException:
            session.rollback()
            raise
    raise AssertionError("unreachable")  # pragma: no cover


RowT = TypeVar("RowT", bound="Base")


def add_row(
    session: Session, row: RowT, *, parent: tuple[type[Base], int, str] | None = None
) -> RowT:
    """Store the new ``row`` in a short write transaction (see :func:`write`); return it stored.

    ``row`` is a template: each try adds a fresh copy of its column values (a rolled-back try
    leaves its generated id on the object it added), and the stored copy is returned, loaded.
    """

    def work(s: Session) -> RowT:
        fresh = copy_row(row)
        s.add(fresh)
        s.flush()
        return fresh

    return write(session, work, parent=parent)


def copy_row(row: RowT) -> RowT:
    """Return a new, unsaved row with ``row``'s column values but not its generated key."""
    values = {
        attr.key: getattr(row, attr.key)
        for attr in inspect(type(row)).column_attrs
        if getattr(row, attr.key) is not None
        and not (attr.columns[0].primary_key and attr.columns[0].autoincrement is not False)
    }
    return type(row)(**values)


def delete_row(session: Session, model: type[Base], ident: int, *, kind: str) -> None:
    """Delete row ``ident`` of ``model`` (the database cascades to what refers to it).

    One ``DELETE`` in a write transaction of its own: two requests deleting the same row at
    once get 204 and 404, never an error.

    Raises
    ------
    NotFoundError
        If there is no such row (any more).
    """
    if not 1 <= ident <= 2**31 - 1:
        raise NotFoundError(kind, ident)
    primary_key = model.__mapper__.primary_key[0]

    def work(s: Session) -> int:
        result = s.execute(delete(model).where(primary_key == ident))
        assert isinstance(result, CursorResult)
        return result.rowcount

    if write(session, work) == 0:
        raise NotFoundError(kind, ident)
    session.expunge_all()


def _exists(session: Session, model: type[Base], ident: int) -> bool:
    primary_key = model.__mapper__.primary_key[0]
    try:
        return session.scalar(select(primary_key).where(primary_key == ident)) is not None
    finally:
        end_reads(session)


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
