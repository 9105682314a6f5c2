"""``tillpath serve`` closes connections of clients that send too slowly or not at all, answers
503 with ``Retry-After`` past its connection limit, and notices a uvicorn it no longer fits."""

from __future__ import annotations

import asyncio
import json
import socket
import time
from collections.abc import Iterator
from contextlib import ExitStack
from urllib.parse import urlsplit

import httpx2
import pytest
import uvicorn
from uvicorn.protocols.http.h11_impl import H11Protocol

from app import serving
from app.main import create_app
from app.settings import Settings, get_settings
from app.testing import running_server

HEADER_TIMEOUT_S = 1.0
#: Connections the test server serves at once.
LIMIT = 4
#: The server's first account (``Authorization``), once the server runs.
HEADERS: dict[str, str] = {}


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, int]]:
    database = tmp_path_factory.mktemp("serving") / "tillpath.db"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("TILLPATH_HEADER_TIMEOUT_S", str(HEADER_TIMEOUT_S))
        patch.setenv("TILLPATH_BODY_IDLE_TIMEOUT_S", str(HEADER_TIMEOUT_S))
        patch.setenv("TILLPATH_LIMIT_CONCURRENCY", str(LIMIT))
        with running_server(f"sqlite:///{database}", serve_args=("--no-access-log",)) as base:
            HEADERS.update(base.headers)
            parts = urlsplit(base)
            assert parts.hostname and parts.port
            yield parts.hostname, parts.port


def closed_after(sock: socket.socket, limit_s: float) -> float:
    """Seconds until the server closes ``sock`` (reads EOF), or fail after ``limit_s``."""
    started = time.monotonic()
    sock.settimeout(limit_s)
    while True:
        try:
            data = sock.recv(1024)
        except ConnectionResetError:
            data = b""
        if not data:
            return time.monotonic() - started
        # a response (e.g. 408/400) is fine too; keep reading until closed


@pytest.mark.parametrize("send", [b"", b"GET /api/health HTTP/1.1\r\nHost: x\r\n"])
def test_a_client_silent_or_stuck_in_its_headers_is_disconnected(
    server: tuple[str, int], send: bytes
):
    with socket.create_connection(server) as sock:
        sock.sendall(send)
        assert closed_after(sock, 10 * HEADER_TIMEOUT_S) < 5 * HEADER_TIMEOUT_S


def test_headers_trickled_byte_by_byte_still_meet_the_deadline(server: tuple[str, int]):
    request = b"GET /api/health HTTP/1.1\r\nHost: x\r\nX-Padding: " + b"a" * 100
    with socket.create_connection(server) as sock:
        started = time.monotonic()
        try:
            for byte in request:
                sock.sendall(bytes([byte]))
                time.sleep(0.05)
        except (BrokenPipeError, ConnectionResetError):
            pass
        assert time.monotonic() - started < 5 * HEADER_TIMEOUT_S
        assert closed_after(sock, 10 * HEADER_TIMEOUT_S) < 5 * HEADER_TIMEOUT_S


def test_a_body_that_stops_arriving_is_disconnected_and_stores_nothing(server: tuple[str, int]):
    host, port = server
    with socket.create_connection(server) as sock:
        sock.sendall(
            b"POST /api/plans HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
            b'Content-Length: 1000\r\n\r\n{"interval_m": 4, '
        )
        assert closed_after(sock, 10 * HEADER_TIMEOUT_S) < 5 * HEADER_TIMEOUT_S
    assert httpx2.get(f"http://{host}:{port}/api/plans", headers=HEADERS).json()["total"] == 0


def test_a_prompt_client_is_served_on_a_kept_alive_connection(server: tuple[str, int]):
    host, port = server
    with httpx2.Client(base_url=f"http://{host}:{port}") as client:
        for _ in range(3):
            assert client.get("/api/health").status_code == 200
            time.sleep(HEADER_TIMEOUT_S * 1.5)  # idle between requests: keep-alive, not headers


def read_answer(sock: socket.socket, limit_s: float = 10.0) -> bytes:
    """Everything the server sends on ``sock`` until it closes the connection."""
    sock.settimeout(limit_s)
    answer = b""
    while chunk := sock.recv(65536):
        answer += chunk
    return answer


def test_past_the_connection_limit_the_answer_is_503_with_retry_after(server: tuple[str, int]):
    with ExitStack() as stack:
        for _ in range(LIMIT):  # connections open, nothing sent yet (within the header timeout)
            stack.enter_context(socket.create_connection(server))
        time.sleep(0.2)  # accepted by the server
        with socket.create_connection(server) as sock:
            sock.sendall(b"GET /api/health HTTP/1.1\r\nHost: x\r\nAccept-Language: id\r\n\r\n")
            answer = read_answer(sock)  # and the server closes the connection
    head, _, body = answer.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    headers = {k.lower(): v for k, v in (line.split(": ", 1) for line in lines[1:])}
    assert lines[0] == "HTTP/1.1 503 Service Unavailable"
    assert headers["retry-after"] == "2"
    assert headers["connection"] == "close"
    assert headers["content-type"] == "application/json"
    assert json.loads(body)["detail"].startswith("request: ")  # in Indonesian
    assert "busy" not in json.loads(body)["detail"]
    # The idle connections gone, the server answers again.
    time.sleep(0.2)
    host, port = server
    assert httpx2.get(f"http://{host}:{port}/api/health").status_code == 200


def test_the_installed_uvicorn_is_the_one_the_guard_fits():
    serving.check_uvicorn()
    assert asyncio.run(serving.probe()).startswith(b"HTTP/1.1 204")
    refused = asyncio.run(serving.probe(limit=0))
    assert refused.startswith(b"HTTP/1.1 503") and b"retry-after: 2\r\n" in refused


def guarded(app: object) -> serving.GuardedH11Protocol:
    """The guard of one connection to ``app``, as uvicorn builds it (proxy headers on)."""
    from uvicorn.server import ServerState

    class Guarded(serving.GuardedH11Protocol):
        load = serving.Load()

    config = uvicorn.Config(app, log_config=None, lifespan="off", access_log=False)
    return Guarded(config=config, server_state=ServerState(), app_state={})


def test_an_app_made_with_other_settings_is_guarded_by_those():
    """Limit and read timeouts of the settings the app was made with, not the environment's."""
    settings = Settings(database_url="sqlite://", limit_concurrency=1, header_timeout_s=0.05)
    assert settings.limit_concurrency != get_settings().limit_concurrency
    app = create_app(settings)

    async def silent_client_closed() -> bool:
        protocol, transport = guarded(app), serving._ProbeTransport()
        protocol.connection_made(transport)
        await asyncio.sleep(0.5)  # the environment's 10 s would still wait
        closed = transport.closed
        protocol.connection_lost(None)
        return closed

    async def second_connection_answer() -> bytes:
        protocol, transport = guarded(app), serving._ProbeTransport()
        protocol.load.connections = 1  # another client holds the one connection allowed
        protocol.connection_made(transport)
        protocol.data_received(b"GET /nowhere HTTP/1.1\r\nHost: x\r\n\r\n")
        for _ in range(100):
            if b"\r\n\r\n" in transport.written:
                break
            await asyncio.sleep(0.01)
        protocol.connection_lost(None)
        return bytes(transport.written)

    assert asyncio.run(silent_client_closed())
    assert asyncio.run(second_connection_answer()).startswith(b"HTTP/1.1 503")


def test_an_app_without_settings_is_guarded_by_the_environments():
    async def app(scope: object, receive: object, send: object) -> None: ...

    async def limit() -> int:
        return guarded(app)._limit  # uvicorn's protocol is made on a running loop

    assert asyncio.run(limit()) == get_settings().limit_concurrency


def test_a_uvicorn_that_bypasses_the_guard_stops_the_server_from_starting(
    monkeypatch: pytest.MonkeyPatch,
):
    # As if a new uvicorn called the configured app directly instead of the protocol's .app.
    original = H11Protocol.handle_events

    def handle_events(self: H11Protocol) -> None:
        self.app = self.config.loaded_app
        original(self)

    monkeypatch.setattr(H11Protocol, "handle_events", handle_events)
    with pytest.raises(serving.UvicornChangedError, match="did not answer past the limit"):
        serving.check_uvicorn()


def test_a_uvicorn_whose_protocol_methods_changed_is_refused(monkeypatch: pytest.MonkeyPatch):
    def data_received(self: H11Protocol, data: bytes, more: bool = False) -> None: ...

    monkeypatch.setattr(H11Protocol, "data_received", data_received)
    with pytest.raises(serving.UvicornChangedError, match="H11Protocol.data_received takes"):
        serving.check_uvicorn()


def test_tillpath_serve_refuses_to_start_on_a_uvicorn_it_no_longer_fits(
    monkeypatch: pytest.MonkeyPatch,
):
    from typer.testing import CliRunner

    from app.cli import cli

    def changed() -> None:
        raise serving.UvicornChangedError("uvicorn 9.9 (app.serving was written for 0.54.0): x")

    monkeypatch.setattr(serving, "check_uvicorn", changed)
    result = CliRunner().invoke(cli, ["serve", "--port", "9"])
    assert result.exit_code == 2
    assert "error: uvicorn 9.9 (app.serving was written for 0.54.0): x; install the locked" in (
        result.output
    )
