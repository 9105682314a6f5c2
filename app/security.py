"""Security headers on every answer (product.md §12, "Hardening").

The Content-Security-Policy allows scripts and styles from this server only (no inline script,
no ``style=`` attributes, no ``eval``), images from here and the configured tile servers, and
no framing (``frame-ancestors 'none'``). Leaflet positions its panes through the CSSOM
(``element.style``), which a CSP does not restrict.
"""

from __future__ import annotations

from urllib.parse import urlsplit

from starlette.datastructures import MutableHeaders
from starlette.types import ASGIApp, Message, Receive, Scope, Send


def _origin(url: str) -> str | None:
    parts = urlsplit(url)
    if parts.scheme in ("http", "https") and parts.netloc:
        return f"{parts.scheme}://{parts.netloc}"
    return None


def content_security_policy(tile_urls: list[str]) -> str:
    """Return the page's CSP, with the tile servers' origins allowed as image sources.

    Examples
    --------
    >>> "frame-ancestors 'none'" in content_security_policy(["https://t.example/{z}/{x}/{y}"])
    True
    >>> "img-src 'self' data: blob: https://t.example;" in content_security_policy(
    ...     ["https://t.example/{z}/{x}/{y}"])
    True
    """
    tiles = sorted({o for url in tile_urls if (o := _origin(url))})
    img = " ".join(["'self'", "data:", "blob:", *tiles])
    return (
        "default-src 'self'; "
        "script-src 'self'; "
        "style-src 'self'; "
        f"img-src {img}; "
        "connect-src 'self'; "
        "font-src 'self'; "
        "object-src 'none'; "
        "base-uri 'none'; "
        "form-action 'self'; "
        "frame-ancestors 'none'"
    )


class SecurityHeadersMiddleware:
    """ASGI middleware adding the security headers to every HTTP answer.

    Parameters
    ----------
    app : ASGIApp
    csp : str
        The ``Content-Security-Policy`` value.
    """

    def __init__(self, app: ASGIApp, *, csp: str) -> None:
        self.app = app
        self.headers = {
            "Content-Security-Policy": csp,
            "X-Content-Type-Options": "nosniff",
            "X-Frame-Options": "DENY",
            "Referrer-Policy": "same-origin",
            "Cross-Origin-Opener-Policy": "same-origin",
        }

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Pass the request on; add the headers to the answer's start."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                for name, value in self.headers.items():
                    if name not in headers:
                        headers[name] = value
            await send(message)

        await self.app(scope, receive, send_with_headers)
