"""Run the real server and real databases from tests, benchmarks and scripts.

The browser tests, the benchmarks and ``scripts/screenshot.py`` need the app as a user runs it
(``tillpath serve`` on a loopback port with a database of its own and no map tiles from
outside), and the PostgreSQL tests and benchmarks a database they may create and drop.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
import uuid
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

#: The repository root, where ``tillpath serve`` finds templates, static files and migrations.
REPO = Path(__file__).resolve().parents[1]
#: Port 9 (discard) on loopback: Chromium refuses it outright, so tiles never leave the machine.
NO_TILES = "http://127.0.0.1:9/{z}/{x}/{y}.png"
#: Debian's Chromium, headless, as root, on a machine whose only network is loopback: without
#: the background-networking flags it keeps trying to reach Google's hosts.
CHROMIUM_ARGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)


#: The first account of a server started for tests.
TEST_USERNAME = "tester"
TEST_PASSWORD = "tillpath test password"
TEST_ORGANISATION = "default"


@dataclass(frozen=True, slots=True)
class Account:
    """A user of a test database, with a personal API token."""

    username: str
    password: str
    organisation_id: int
    token: str

    @property
    def headers(self) -> dict[str, str]:
        """``Authorization: Bearer …`` for this account."""
        return {"Authorization": f"Bearer {self.token}"}


class ServerUrl(str):
    """A test server's base URL (a ``str``) that also knows its first account and process."""

    account: Account
    #: The ``tillpath serve`` process (None if not known): its tree holds the job workers.
    pid: int | None

    def __new__(cls, url: str, account: Account, pid: int | None = None) -> ServerUrl:
        """Make the URL string and attach ``account`` and ``pid``."""
        made = super().__new__(cls, url)
        made.account = account
        made.pid = pid
        return made

    @property
    def headers(self) -> dict[str, str]:
        """The first account's ``Authorization`` header."""
        return self.account.headers


def seed_account(
    database_url: str,
    *,
    username: str = TEST_USERNAME,
    password: str = TEST_PASSWORD,
    organisation: str = TEST_ORGANISATION,
    role: str = "owner",
) -> Account:
    """Migrate ``database_url`` and add a user with a personal token (as the CLI would).

    Returns
    -------
    Account
    """
    from sqlalchemy.orm import Session

    from app import accounts
    from app.db import make_engine, upgrade_database

    upgrade_database(database_url)
    engine = make_engine(database_url)
    try:
        with Session(engine, expire_on_commit=False) as session:
            user = accounts.create_user(
                session, username, password, organisation=organisation, role=role
            )
            org = accounts.get_or_create_organisation(session, organisation)
            token = accounts.create_token(session, user, name="tests").token
            return Account(username, password, org.id, token)
    finally:
        engine.dispose()


class ServerStartError(RuntimeError):
    """``tillpath serve`` exited or did not answer ``/api/health`` in time."""


def free_port() -> int:
    """Return a TCP port on 127.0.0.1 that nothing listens on right now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


def tillpath_command() -> list[str]:
    """Return this environment's ``tillpath`` command.

    ``make install`` puts the console script beside the interpreter; before the project is
    installed, the same entry point runs through the interpreter.
    """
    script = Path(sys.executable).with_name("tillpath")
    if script.is_file():
        return [str(script)]
    return [sys.executable, "-c", "from app.cli import main; main()"]


class ServerProcess:
    """``tillpath serve`` on a loopback port, as a child process that can be killed and restarted.

    Parameters
    ----------
    database_url : str
        ``TILLPATH_DATABASE_URL`` of the server (it migrates it on start).
    log : Path, optional
        Where the server's output goes (appended to; discarded if None).
    serve_args : sequence of str
        More ``tillpath serve`` options, e.g. ``("--workers", "2")``.
    env : mapping, optional
        More environment variables (``TILLPATH_*`` settings).
    first_account : bool
        Give the database its first account on the first start; without it the server asks
        for one (``base_url.account`` then names an account that does not exist).
    """

    def __init__(
        self,
        database_url: str,
        *,
        log: Path | None = None,
        serve_args: Sequence[str] = (),
        env: Mapping[str, str] | None = None,
        first_account: bool = True,
    ) -> None:
        self.database_url = database_url
        self.first_account = first_account
        self.log = log
        self.serve_args = tuple(serve_args)
        self.env = dict(env or {})
        self.port = free_port()
        self.process: subprocess.Popen[bytes] | None = None
        self.account: Account | None = None

    @property
    def base_url(self) -> ServerUrl:
        """``http://127.0.0.1:<port>``, with the first account (``.headers``) once started."""
        assert self.account is not None, "not started"
        pid = None if self.process is None else self.process.pid
        return ServerUrl(f"http://127.0.0.1:{self.port}", self.account, pid)

    @property
    def pid(self) -> int:
        """The server's process id (the uvicorn master with several workers)."""
        assert self.process is not None, "not started"
        return self.process.pid

    def start(self, *, timeout_s: float = 60.0) -> ServerUrl:
        """Start the server (on the same port as before, if restarted); return its base URL.

        The first start migrates the database and adds a first account (:func:`seed_account`)
        to it; the URL carries that account.

        Raises
        ------
        ServerStartError
            If it exits or does not answer ``/api/health`` within ``timeout_s``.
        """
        if self.account is None:
            self.account = (
                seed_account(self.database_url)
                if self.first_account
                else Account(TEST_USERNAME, TEST_PASSWORD, 0, "tp_no-account-yet")
            )
        env = {
            **os.environ,
            "TILLPATH_DATABASE_URL": self.database_url,
            "TILLPATH_SATELLITE_TILE_URL": NO_TILES,
            "TILLPATH_STREET_TILE_URL": NO_TILES,
            **self.env,
        }
        command = [
            *tillpath_command(),
            "serve",
            *("--host", "127.0.0.1", "--port", str(self.port)),
            *self.serve_args,
        ]
        with self.log.open("ab") if self.log else open(os.devnull, "wb") as out:
            self.process = subprocess.Popen(
                command, cwd=REPO, env=env, stdout=out, stderr=out, start_new_session=True
            )
        _wait_for_health(f"{self.base_url}/api/health", self.process, self.log, timeout_s)
        return self.base_url

    def kill(self) -> None:
        """Kill the server and its workers at once (SIGKILL), as a power cut would."""
        if self.process is not None and self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()

    def stop(self) -> None:
        """Stop the server gracefully (SIGTERM), killing it if it does not exit in 15 s."""
        if self.process is None or self.process.poll() is not None:
            return
        self.process.terminate()
        try:
            self.process.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.kill()


@contextmanager
def running_server(
    database_url: str,
    *,
    log: Path | None = None,
    serve_args: Sequence[str] = (),
    timeout_s: float = 60.0,
    first_account: bool = True,
    env: Mapping[str, str] | None = None,
) -> Iterator[ServerUrl]:
    """Serve the app with ``tillpath serve`` until the block ends; yield its base URL.

    The database gets a first account (:func:`seed_account`) before the server starts; the
    yielded URL carries it (``url.account``, ``url.headers``).

    Parameters
    ----------
    database_url : str
        ``TILLPATH_DATABASE_URL`` of the server (it migrates it on start).
    log : Path, optional
        Where the server's output goes (discarded if None).
    serve_args : sequence of str
        More ``tillpath serve`` options, e.g. ``("--workers", "1")``.
    timeout_s : float
        How long to wait for ``/api/health`` [s].
    first_account : bool
        Give the database its first account before the server starts; without it the
        server asks for one (``url.account`` then names an account that does not exist).
    env : mapping, optional
        More environment variables of the server (``TILLPATH_*`` settings).

    Raises
    ------
    ServerStartError
        If the server exits or does not answer in time (with its log, if kept).
    """
    if log is not None:
        log.write_bytes(b"")
    warm_kernel_cache()
    server = ServerProcess(
        database_url, log=log, serve_args=serve_args, env=env, first_account=first_account
    )
    try:
        yield server.start(timeout_s=timeout_s)
    finally:
        server.stop()


def warm_kernel_cache() -> None:
    """Fill the planner's numba cache, if cold, before a test starts planning processes.

    A fresh clone has no cache: the first process that plans compiles the kernels (about 9 s of
    CPU, :mod:`planner.kernels`), and a server or CLI started by a test would do it while the
    test's timeouts run. Compiled here once, they load from the cache in every process after.
    """
    from planner.warm_up import warm_up

    warm_up()


def _wait_for_health(
    url: str, process: subprocess.Popen[bytes], log: Path | None, timeout_s: float
) -> None:
    def output() -> str:
        return log.read_text() if log else "(log discarded)"

    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise ServerStartError(f"tillpath serve exited with {process.returncode}:\n{output()}")
        try:
            with urllib.request.urlopen(url, timeout=2) as response:
                if response.status == 200:
                    return
        except (urllib.error.URLError, ConnectionError, TimeoutError):
            pass
        time.sleep(0.2)
    raise ServerStartError(f"tillpath serve did not answer {url} in {timeout_s:g} s:\n{output()}")


@contextmanager
def scratch_pg_database(base_url: str, *, prefix: str = "tillpath_test") -> Iterator[str]:
    """Create an empty database on the server of ``base_url``; yield its URL; drop it.

    Tests and benchmarks work in a database of their own, so they neither see nor leave rows
    in the one ``base_url`` names (``CREATE DATABASE`` rights needed).
    """
    name = f"{prefix}_{uuid.uuid4().hex[:12]}"
    _admin(base_url, f'CREATE DATABASE "{name}"')
    try:
        yield make_url(base_url).set(database=name).render_as_string(hide_password=False)
    finally:
        _admin(base_url, f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


def _admin(base_url: str, sql: str) -> None:
    engine = create_engine(base_url, isolation_level="AUTOCOMMIT")
    try:
        with engine.connect() as conn:
            conn.execute(text(sql))
    finally:
        engine.dispose()
