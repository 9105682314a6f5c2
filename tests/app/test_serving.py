"""``tillpath serve`` closes connections of clients that send too slowly or not at all."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator
from urllib.parse import urlsplit

import httpx2
import pytest

from app.testing import running_server

HEADER_TIMEOUT_S = 1.0
#: The server's first account (``Authorization``), once the server runs.
HEADERS: dict[str, str] = {}


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, int]]:
    database = tmp_path_factory.mktemp("serving") / "tillpath.db"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("TILLPATH_HEADER_TIMEOUT_S", str(HEADER_TIMEOUT_S))
        patch.setenv("TILLPATH_BODY_IDLE_TIMEOUT_S", str(HEADER_TIMEOUT_S))
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
