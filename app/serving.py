"""How ``tillpath serve`` runs uvicorn: connection limits and timeouts for slow or idle clients.

uvicorn closes an idle keep-alive connection (``timeout_keep_alive``) and answers 503 past
``limit_concurrency`` connections, but it waits forever for a client that opens a connection
and sends its request slowly or not at all. :class:`GuardedH11Protocol` adds the two read
timeouts a reverse proxy would (nginx's ``client_header_timeout`` and ``client_body_timeout``):

- the request line and headers must arrive within ``header_timeout_s`` of the first byte (or of
  the connection opening), however slowly they trickle in;
- while a request body is being received, the connection may go ``body_idle_timeout_s``
  without data.

A connection that misses either is closed. Nothing is timed while the app computes an answer.
"""

from __future__ import annotations

import asyncio
from typing import Any

from uvicorn.protocols.http.h11_impl import H11Protocol

from app.settings import Settings, get_settings


class GuardedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with header and body read timeouts (see the module docstring)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        settings = get_settings()
        self._header_timeout_s = settings.header_timeout_s
        self._body_idle_timeout_s = settings.body_idle_timeout_s
        self._read_timer: asyncio.TimerHandle | None = None
        self._reading_headers = False

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        """Start the header deadline as the connection opens."""
        super().connection_made(transport)
        self._start_headers()

    def data_received(self, data: bytes) -> None:
        """Feed h11, then time what the connection waits for next."""
        super().data_received(data)
        if self.transport.is_closing():
            return
        cycle = self.cycle
        if cycle is None or cycle.response_complete:  # (the rest of) a request's headers
            if not self._reading_headers:
                self._start_headers()
        elif cycle.more_body:  # a body arriving: an idle timer, restarted by each chunk
            self._reading_headers = False
            self._arm(self._body_idle_timeout_s)
        else:  # the whole request is in: the app's turn
            self._reading_headers = False
            self._cancel()

    def on_response_complete(self) -> None:
        """Leave the idle connection to uvicorn's keep-alive timeout."""
        self._reading_headers = False
        self._cancel()
        super().on_response_complete()

    def connection_lost(self, exc: Exception | None) -> None:
        """Stop the timer with the connection."""
        self._cancel()
        super().connection_lost(exc)

    def _start_headers(self) -> None:
        self._reading_headers = True
        self._arm(self._header_timeout_s)

    def _arm(self, delay_s: float) -> None:
        self._cancel()
        self._read_timer = self.loop.call_later(delay_s, self._timed_out)

    def _cancel(self) -> None:
        if self._read_timer is not None:
            self._read_timer.cancel()
            self._read_timer = None

    def _timed_out(self) -> None:
        self._read_timer = None
        if not self.transport.is_closing():
            self.transport.close()


def uvicorn_options(settings: Settings) -> dict[str, Any]:
    """Return the keyword arguments of ``uvicorn.run`` that bound connections and waits.

    Parameters
    ----------
    settings : Settings
        ``keep_alive_s``, ``limit_concurrency``, ``backlog`` and the read timeouts.

    Returns
    -------
    dict
    """
    return {
        "http": "app.serving:GuardedH11Protocol",
        "timeout_keep_alive": settings.keep_alive_s,
        "limit_concurrency": settings.limit_concurrency,
        "backlog": settings.backlog,
        "timeout_graceful_shutdown": 10,
        "h11_max_incomplete_event_size": 64 * 1024,  # request line and headers [bytes]
    }
