"""How ``tillpath serve`` runs uvicorn: connection limits and timeouts for slow or idle clients.

uvicorn closes an idle keep-alive connection (``timeout_keep_alive``), but it waits forever
for a client that opens a connection and sends its request slowly or not at all, and the 503
it answers past its own ``limit_concurrency`` says neither why nor when to retry.
:class:`GuardedH11Protocol` adds what a reverse proxy would:

- the two read timeouts of nginx's ``client_header_timeout`` and ``client_body_timeout``: the
  request line and headers must arrive within ``header_timeout_s`` of their first byte (or of
  the connection opening), however slowly they trickle in; while the app waits for more of a
  request body, the connection may go ``body_idle_timeout_s`` without data. A connection that
  misses either is closed. Nothing is timed while the app computes an answer.
- the connection limit itself: past ``limit_concurrency`` connections or requests in this
  process, a request is answered **503 with** ``Retry-After`` and a JSON ``detail``, like every
  other 503 of the app, and its connection closed (uvicorn's own limit is not used).

What it takes from uvicorn (pinned in ``pyproject.toml`` and ``requirements.lock``;
:func:`check_uvicorn`, run as ``tillpath serve`` starts, and ``tests/app/test_serving.py``
fail if any of it changes):

- ``H11Protocol``, an :class:`asyncio.Protocol`, whose constructor is passed through untouched
  and which calls the ASGI app it keeps in ``self.app`` for each request (the guard wraps it);
- the protocol methods of :class:`asyncio.Protocol` (``connection_made``, ``data_received``,
  ``connection_lost``), each overridden to do its part and then call uvicorn's.

Everything else (where a request starts, when its body is read, when its answer is complete)
the guard learns from the ASGI messages the app exchanges, which the ASGI specification fixes,
not from uvicorn's internal state.
"""

from __future__ import annotations

import asyncio
import inspect
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Final

import uvicorn
from starlette.types import ASGIApp, Message, Receive, Scope, Send
from uvicorn.protocols.http.h11_impl import H11Protocol

from app.errors import ServerBusyError, error_response
from app.i18n import negotiate_language
from app.settings import Settings, get_settings

#: The uvicorn version the guard was written and tested against (``requirements.lock``).
TESTED_UVICORN: Final = "0.54.0"


class UvicornChangedError(RuntimeError):
    """The installed uvicorn no longer offers what :class:`GuardedH11Protocol` relies on."""


@dataclass(slots=True)
class Load:
    """Connections open and requests in progress in this process (one uvicorn server)."""

    connections: int = 0
    requests: int = 0


def served_settings(app: object) -> Settings:
    """Return the settings the served app was made with, else the environment's.

    ``create_app(settings)`` keeps them in ``app.state.settings`` (as
    :func:`app.dependencies.request_settings` reads them); uvicorn wraps the app in its own
    middleware (``ProxyHeadersMiddleware`` and the like), each keeping the app it wraps in
    ``.app``, so the chain is followed down to it. An app that keeps no settings (not made by
    :func:`app.main.create_app`, as :func:`probe`'s) is served with the environment's.
    """
    for _ in range(_MAX_WRAPPERS):
        settings = getattr(getattr(app, "state", None), "settings", None)
        if isinstance(settings, Settings):
            return settings
        app = getattr(app, "app", None)
        if app is None:
            break
    return get_settings()


#: How many ASGI wrappers :func:`served_settings` looks through (uvicorn adds at most three).
_MAX_WRAPPERS: Final = 8


class GuardedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with read timeouts and a connection limit (see the module doc)."""

    #: Shared by every connection of the process (a test may give a subclass its own).
    load: Load = Load()

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        app = getattr(self, "app", None)
        if not callable(app):
            raise UvicornChangedError(
                f"uvicorn {uvicorn.__version__}: H11Protocol keeps no ASGI app in .app; "
                f"app.serving was written for uvicorn {TESTED_UVICORN}"
            )
        settings = served_settings(app)
        self._header_timeout_s = settings.header_timeout_s
        self._body_idle_timeout_s = settings.body_idle_timeout_s
        self._limit = settings.limit_concurrency
        self._app: ASGIApp = app
        self.app = self._guarded  # uvicorn calls this for every request
        self._guard_transport: asyncio.BaseTransport | None = None
        self._guard_loop: asyncio.AbstractEventLoop | None = None
        self._timer: asyncio.TimerHandle | None = None
        self._counted = False
        self._request = 0  # the request in progress (0: none); numbers each request
        self._requests = 0
        self._unread = False  # bytes arrived during a request that no receive() has returned

    # --- asyncio.Protocol ------------------------------------------------------------------

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        """Count the connection and start the header deadline as it opens."""
        self._guard_transport = transport
        self._guard_loop = asyncio.get_running_loop()
        self.load.connections += 1
        self._counted = True
        super().connection_made(transport)  # type: ignore[arg-type]
        self._arm(self._header_timeout_s)

    def data_received(self, data: bytes) -> None:
        """Start the header deadline at the first byte of a request, then let uvicorn read."""
        if self._request:
            self._unread = True
        elif self._timer is None:
            self._arm(self._header_timeout_s)
        super().data_received(data)

    def connection_lost(self, exc: Exception | None) -> None:
        """Stop the timer and uncount the connection."""
        self._cancel()
        if self._counted:
            self._counted = False
            self.load.connections -= 1
        super().connection_lost(exc)

    # --- the ASGI app, wrapped -------------------------------------------------------------

    async def _guarded(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Run one request: the headers are in; time its body, refuse it past the limit."""
        self._cancel()  # the headers are in
        self._requests += 1
        number = self._request = self._requests
        self._unread = False
        self.load.requests += 1
        try:
            if max(self.load.connections, self.load.requests) > self._limit:
                await self._refuse(scope, receive, send)
                return
            await self._app(scope, self._timed_receive(receive), self._watched_send(send))
        finally:
            self.load.requests -= 1
            if self._request == number:
                self._finished()

    def _timed_receive(self, receive: Receive) -> Receive:
        """``receive`` that closes the connection if the body stops arriving while awaited."""
        body_done = False

        async def timed() -> Message:
            nonlocal body_done
            if body_done:  # only http.disconnect is left: the app's own wait, not timed
                return await receive()
            self._arm(self._body_idle_timeout_s)
            try:
                message = await receive()
            finally:
                self._cancel()
            if message["type"] != "http.request" or not message.get("more_body", False):
                body_done = True
            self._unread = False
            return message

        return timed

    def _watched_send(self, send: Send) -> Send:
        """``send`` that notes when the response is complete."""
        number = self._request

        async def watched(message: Message) -> None:
            await send(message)
            complete = message["type"] == "http.response.body" and not message.get(
                "more_body", False
            )
            if complete and self._request == number:
                self._finished()

        return watched

    def _finished(self) -> None:
        """Mark the request done: the connection waits for the next (uvicorn's keep-alive)."""
        self._request = 0
        self._cancel()
        if self._unread:  # bytes of a pipelined request, or a body the app never read
            self._unread = False
            self._arm(self._header_timeout_s)

    async def _refuse(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Answer 503 with ``Retry-After`` (as the app's own 503s) and close the connection."""
        headers = dict(
            (k.decode("latin-1"), v.decode("latin-1")) for k, v in scope.get("headers", ())
        )
        language = negotiate_language(headers.get("accept-language"))
        response = error_response(ServerBusyError("request"), language)
        response.headers["Connection"] = "close"
        await response(scope, receive, send)

    # --- timers ------------------------------------------------------------------------------

    def _arm(self, delay_s: float) -> None:
        self._cancel()
        if self._guard_loop is not None:
            self._timer = self._guard_loop.call_later(delay_s, self._timed_out)

    def _cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _timed_out(self) -> None:
        self._timer = None
        transport = self._guard_transport
        if transport is not None and not transport.is_closing():
            transport.close()


#: The methods of :class:`asyncio.Protocol` the guard overrides, with the parameters it
#: passes on to uvicorn's.
_PROTOCOL_METHODS: Final = {
    "connection_made": ["self", "transport"],
    "data_received": ["self", "data"],
    "connection_lost": ["self", "exc"],
}


class _ProbeTransport(asyncio.Transport):
    """An in-memory transport: what the protocol writes, and whether it closed."""

    def __init__(self) -> None:
        super().__init__()
        self.written = bytearray()
        self.closed = False

    def write(self, data: bytes | bytearray | memoryview) -> None:  # noqa: D102
        self.written += data

    def close(self) -> None:  # noqa: D102
        self.closed = True

    def is_closing(self) -> bool:  # noqa: D102
        return self.closed

    def get_extra_info(self, name: str, default: Any = None) -> Any:  # noqa: D102
        return {"sockname": ("127.0.0.1", 8000), "peername": ("127.0.0.1", 50000)}.get(
            name, default
        )

    def pause_reading(self) -> None:  # noqa: D102
        pass

    def resume_reading(self) -> None:  # noqa: D102
        pass


async def probe(limit: int | None = None) -> bytes:
    """Send one request through :class:`GuardedH11Protocol` in memory; return the answer.

    The app answers 204; with ``limit`` set (0: every request is past it), the guard answers
    instead. Used by :func:`check_uvicorn` and the tests of this module.
    """
    from uvicorn.server import ServerState

    async def app(scope: Scope, receive: Receive, send: Send) -> None:
        await receive()
        await send({"type": "http.response.start", "status": 204, "headers": []})
        await send({"type": "http.response.body", "body": b""})

    class Probe(GuardedH11Protocol):
        load = Load()

    config = uvicorn.Config(app, log_config=None, lifespan="off", access_log=False)
    protocol = Probe(config=config, server_state=ServerState(), app_state={})
    if limit is not None:
        protocol._limit = limit
    transport = _ProbeTransport()
    protocol.connection_made(transport)
    protocol.data_received(b"GET /probe HTTP/1.1\r\nHost: probe\r\n\r\n")
    for _ in range(100):  # the request runs as a task of its own
        if b"\r\n\r\n" in transport.written and protocol._request == 0:
            break
        await asyncio.sleep(0)
    protocol.connection_lost(None)
    return bytes(transport.written)


def check_uvicorn() -> None:
    """Fail at start if uvicorn's ``H11Protocol`` no longer does what the guard relies on.

    The overridden methods must take what they took, and a request sent in memory must go
    through the guard (:func:`probe`): answered by the app, and 503 with ``Retry-After`` past
    the limit.

    Raises
    ------
    UvicornChangedError
        Naming what changed (then pin uvicorn back, or update this module and its tests).
    """
    where = f"uvicorn {uvicorn.__version__} (app.serving was written for {TESTED_UVICORN})"
    if not issubclass(H11Protocol, asyncio.Protocol):
        raise UvicornChangedError(f"{where}: H11Protocol is no longer an asyncio.Protocol")
    for name, parameters in _PROTOCOL_METHODS.items():
        method = getattr(H11Protocol, name, None)
        found = list(inspect.signature(method).parameters) if callable(method) else None
        if found != parameters:
            raise UvicornChangedError(
                f"{where}: H11Protocol.{name} takes {found}, the guard passes {parameters}"
            )
    try:
        # In a thread of its own: the caller's thread may already run an event loop (a test
        # session's browser driver, a notebook), where asyncio.run refuses to start.
        with ThreadPoolExecutor(max_workers=1) as thread:
            served = thread.submit(lambda: asyncio.run(probe())).result()
            refused = thread.submit(lambda: asyncio.run(probe(limit=0))).result()
    except UvicornChangedError:
        raise
    except Exception as exc:  # an import, a constructor or a call that changed
        raise UvicornChangedError(f"{where}: a request in memory failed: {exc!r}") from exc
    if not served.startswith(b"HTTP/1.1 204"):
        raise UvicornChangedError(f"{where}: the app was not reached: {served[:80]!r}")
    if not (refused.startswith(b"HTTP/1.1 503") and b"\r\nretry-after: " in refused.lower()):
        raise UvicornChangedError(
            f"{where}: the guard did not answer past the limit: {refused[:80]!r}"
        )


def uvicorn_options(settings: Settings) -> dict[str, Any]:
    """Return the keyword arguments of ``uvicorn.run`` that bound connections and waits.

    Checks the installed uvicorn first (:func:`check_uvicorn`).

    Parameters
    ----------
    settings : Settings
        ``keep_alive_s`` and ``backlog`` (``limit_concurrency`` and the read timeouts are
        applied by :class:`GuardedH11Protocol`).

    Returns
    -------
    dict
    """
    check_uvicorn()
    return {
        "http": "app.serving:GuardedH11Protocol",
        "timeout_keep_alive": settings.keep_alive_s,
        "limit_concurrency": None,  # GuardedH11Protocol's, with Retry-After
        "ws": "none",  # no WebSocket upgrades: a connection stays this protocol's
        "backlog": settings.backlog,
        "timeout_graceful_shutdown": 10,
        "h11_max_incomplete_event_size": 64 * 1024,  # request line and headers [bytes]
    }
