"""Errors to HTTP answers, in one table (TiTiler's ``DEFAULT_STATUS_CODES``).

Routes never catch planner errors: they propagate here, and every error answer has the same
shape, ``{"detail": "<input>: <problem>"}`` with ``detail`` a string. FastAPI's validation
errors (a list of dicts) are turned into one such sentence too.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Final

from fastapi import FastAPI, HTTPException, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from sqlalchemy.exc import DataError, IntegrityError, OperationalError
from sqlalchemy.exc import TimeoutError as PoolTimeoutError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from app.i18n import DEFAULT_LANGUAGE, negotiate_language
from app.i18n_errors import translate_detail
from app.track_fixes import TrackFormatError
from navigation import NavigationError
from planner import InvalidFieldError, InvalidParameterError, PlannerError, PlanTooLargeError

logger = logging.getLogger(__name__)


class NotFoundError(LookupError):
    """A stored object does not exist: ``plan 42 not found``.

    Parameters
    ----------
    kind : str
        What was looked for (``plan``, ``simulation``, ``run``).
    ident : int
        Its id.
    """

    def __init__(self, kind: str, ident: int) -> None:
        super().__init__(f"{kind} {ident} not found")
        self.kind = kind
        self.ident = ident


class BodyTooLargeError(ValueError):
    """A request body over the configured limit.

    Parameters
    ----------
    limit : int
        The limit [bytes].
    """

    def __init__(self, limit: int) -> None:
        super().__init__(f"body: the request is larger than the limit of {limit} bytes")
        self.limit = limit


class UploadTooLargeError(BodyTooLargeError):
    """An uploaded track file over the configured limit.

    Parameters
    ----------
    limit : int
        The limit [bytes].
    """

    def __init__(self, limit: int) -> None:
        ValueError.__init__(self, f"file: the upload is larger than the limit of {limit} bytes")
        self.limit = limit


class ConflictError(ValueError):
    """The request does not fit the object's state (fixes posted to an uploaded run)."""


class AccountError(ValueError):
    """Bad account input (a name or password that cannot be used)."""


class SignInError(PermissionError):
    """Wrong username or password (which one is not said)."""

    def __init__(self) -> None:
        super().__init__("username or password is wrong")


class ThrottledError(PermissionError):
    """Too many failed sign-ins: answered with ``Retry-After``.

    Parameters
    ----------
    what : str
        ``this account`` or ``this address``.
    retry_after_s : int
        Seconds until sign-in is possible again.
    """

    def __init__(self, what: str, retry_after_s: int) -> None:
        minutes = max(1, round(retry_after_s / 60))
        super().__init__(
            f"too many failed sign-ins for {what}; try again in about {minutes} minutes"
        )
        self.retry_after_s = retry_after_s
        self.headers = {"Retry-After": str(retry_after_s)}


#: Seconds a client is asked to wait before retrying a 503 (``Retry-After``).
RETRY_AFTER_S: Final = 2


class ServerBusyError(RuntimeError):
    """Every slot for heavy work (planning, simulating, scoring) is taken and the queue is full.

    Parameters
    ----------
    what : str
        The work that was refused (``simulation``, ``upload`` …).
    """

    def __init__(self, what: str) -> None:
        super().__init__(
            f"{what}: the server is busy with other work; try again in {RETRY_AFTER_S} s"
        )
        self.what = what


class DatabaseBusyError(RuntimeError):
    """The database stayed locked by other writers through every retry of a write."""

    def __init__(self) -> None:
        super().__init__(
            f"database: busy with other writes; nothing was stored, try again in {RETRY_AFTER_S} s"
        )


class DatabaseUnavailableError(RuntimeError):
    """The database could not be reached or gave no connection in time."""


class UnavailableError(RuntimeError):
    """The server cannot do this now or in this setup (no job engine): 503."""


#: The one table: exception class -> HTTP status. Looked up along the class's MRO, so a
#: subclass without its own row gets its parent's status.
STATUS_CODES: Final[dict[type[Exception], int]] = {
    InvalidFieldError: 422,
    InvalidParameterError: 422,
    PlanTooLargeError: 422,
    PlannerError: 422,
    NavigationError: 422,
    TrackFormatError: 422,
    ConflictError: 409,
    AccountError: 422,
    SignInError: 401,
    ThrottledError: 429,
    RequestValidationError: 422,
    NotFoundError: 404,
    BodyTooLargeError: 413,
    ServerBusyError: 503,
    DatabaseBusyError: 503,
    DatabaseUnavailableError: 503,
    # Safety nets for what the routes do not turn into one of the above themselves.
    PoolTimeoutError: 503,
    OperationalError: 503,
    IntegrityError: 409,
    DataError: 422,
    UnavailableError: 503,
}

#: What the client reads for the database's own errors (their text would leak SQL).
_DATABASE_DETAILS: Final[dict[type[Exception], str]] = {
    PoolTimeoutError: "database: every connection is in use; try again in {s} s",
    OperationalError: "database: not reachable or busy; try again in {s} s",
    IntegrityError: "the request conflicts with a change made at the same time; retry",
    DataError: "body: holds a value the database cannot store (out of range or a NUL character)",
}

#: What FastAPI says when the body is not JSON it can decode (bad UTF-8, nesting too deep).
_FASTAPI_BODY_PARSE_ERROR = "There was an error parsing the body"


def status_for(exc: BaseException) -> int:
    """Return the HTTP status of ``exc`` from :data:`STATUS_CODES` (500 if not listed)."""
    for cls in type(exc).__mro__:
        if cls in STATUS_CODES:
            return STATUS_CODES[cls]
    return 500


def _cause(exc: Exception) -> str:
    """Return the database's own first line for ``exc``: no SQL, no parameters.

    SQLAlchemy's text of an error carries the statement and its parameters, which can hold a
    password's or a token's hash; the driver's first line names the constraint or the cause
    (PostgreSQL puts the key's value on a DETAIL line after it).
    """
    orig = getattr(exc, "orig", None)
    cause = exc if orig is None else orig
    text = str(cause).strip().splitlines()
    return f"{type(cause).__name__}: {text[0] if text else ''}"


#: Where a driver names the key of a violated constraint: SQLite ``UNIQUE constraint failed:
#: fields.organisation_id, fields.name`` (NOT NULL alike), PostgreSQL's detail line
#: ``Key (organisation_id, name)=(…) already exists.``
_SQLITE_KEY = re.compile(r"constraint failed: (\w+\.\w+(?:, \w+\.\w+)*)")
_POSTGRES_KEY = re.compile(r"^Key \(([\w, ]+)\)=.*(?:already exists|is not present in table)")


def conflicting_input(exc: IntegrityError) -> str | None:
    """Return the input a database constraint violation is about, if its driver names one.

    The column of a NOT NULL violation, or the last column of a key that already exists or
    refers to a row that does not (those before it scope it: an organisation, a plan); never
    the key's value, which can be a secret's hash. None where the driver names no column
    (SQLite's foreign keys; a row still referenced, which is no input of the request).
    """
    orig = getattr(exc, "orig", None)
    diag = getattr(orig, "diag", None)  # psycopg's parts of a PostgreSQL error
    column = getattr(diag, "column_name", None)
    if isinstance(column, str) and column:
        return column
    # Only the detail line: the message of a CHECK violation quotes the row's values.
    key = _POSTGRES_KEY.search(str(getattr(diag, "message_detail", None) or ""))
    if key:
        return key[1].split(",")[-1].strip()
    key = _SQLITE_KEY.search(str(orig))
    if key:
        return key[1].split(",")[-1].strip().split(".", 1)[1]
    return None


def error_response(exc: Exception, lang: str = DEFAULT_LANGUAGE) -> JSONResponse:
    """Build the JSON answer for ``exc``: its status from the table, ``str(exc)`` as detail.

    ``lang`` is the language of the detail (``app.i18n_errors`` translates it).
    """
    if isinstance(exc, RequestValidationError):
        detail = format_validation_errors(exc.errors())
    else:
        detail = str(exc)
    for cls, text in _DATABASE_DETAILS.items():
        if isinstance(exc, cls):
            logger.warning("database error answered %s: %s", status_for(exc), _cause(exc))
            detail = text.format(s=RETRY_AFTER_S)
            if isinstance(exc, IntegrityError):
                column = conflicting_input(exc)
                detail = detail if column is None else f"{column}: {detail}"
            break
    code = status_for(exc)
    headers: dict[str, str] | None = getattr(exc, "headers", None)
    if code == 503:
        headers = {**(headers or {}), "Retry-After": str(RETRY_AFTER_S)}
    return JSONResponse(
        {"detail": translate_detail(detail, lang)}, status_code=code, headers=headers
    )


def _language(request: Request) -> str:
    """Return the language the request asks its errors in (``Accept-Language``)."""
    return negotiate_language(request.headers.get("accept-language"))


async def _handle_listed(request: Request, exc: Exception) -> JSONResponse:
    return error_response(exc, _language(request))


async def _handle_http_exception(request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, StarletteHTTPException)
    lang = _language(request)
    if exc.status_code == 400 and exc.detail == _FASTAPI_BODY_PARSE_ERROR:
        detail = translate_detail("body: is not valid JSON text", lang)
        return JSONResponse({"detail": detail}, status_code=422)
    return JSONResponse(
        {"detail": translate_detail(str(exc.detail), lang)},
        status_code=exc.status_code,
        headers=exc.headers,
    )


async def _handle_unexpected(request: Request, exc: Exception) -> JSONResponse:
    logger.exception("unhandled error", exc_info=exc)
    detail = translate_detail("internal error", _language(request))
    return JSONResponse({"detail": detail}, status_code=500)


def register_error_handlers(app: FastAPI) -> None:
    """Install a handler for every row of :data:`STATUS_CODES`, plus HTTP and catch-all ones."""
    for cls in STATUS_CODES:
        app.add_exception_handler(cls, _handle_listed)
    app.add_exception_handler(StarletteHTTPException, _handle_http_exception)
    app.add_exception_handler(Exception, _handle_unexpected)


# --- FastAPI validation errors as one sentence -------------------------------------------

_TYPE_MESSAGES: Final[dict[str, str]] = {
    "missing": "is required",
    "extra_forbidden": "is not a known input",
    "float_type": "must be a number",
    "float_parsing": "must be a number",
    "finite_number": "must be a finite number",
    "int_type": "must be a whole number",
    "int_parsing": "must be a whole number",
    "int_from_float": "must be a whole number",
    "bool_type": "must be true or false",
    "string_type": "must be a string",
    "dict_type": "must be a JSON object",
    "model_type": "must be a JSON object",
    "model_attributes_type": "must be a JSON object",
    "tuple_type": "must be a [lon, lat] pair of numbers",
    "list_type": "must be a list",
    "none_required": "must be null",
}


def _location(loc: Sequence[int | str]) -> str:
    parts = list(loc)
    if len(parts) > 1 and parts[0] in ("body", "query", "path", "header", "cookie"):
        parts = parts[1:]
    text = ""
    for part in parts:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += f".{part}" if text else str(part)
    return text or "body"


def _problem(error: Mapping[str, Any]) -> str:
    kind = str(error.get("type", ""))
    ctx: Mapping[str, Any] = error.get("ctx") or {}
    if kind == "json_invalid":
        return f"is not valid JSON ({ctx.get('error', 'decode error')})"
    if kind == "literal_error":
        return f"must be {ctx.get('expected', 'one of the allowed values')}"
    if kind in ("too_long", "string_too_long"):
        limit = ctx.get("max_length")
        return f"is too long (at most {limit} characters)" if limit else "is too long"
    if kind == "value_error" and ctx.get("error") is not None:
        return str(ctx["error"])  # a validator's own sentence
    if kind in ("too_short", "string_too_short"):
        return "is too short"
    if kind == "greater_than_equal":
        return f"must be at least {ctx.get('ge')}"
    if kind == "greater_than":
        return f"must be greater than {ctx.get('gt')}"
    if kind == "less_than_equal":
        return f"must be at most {ctx.get('le')}"
    if kind == "less_than":
        return f"must be less than {ctx.get('lt')}"
    if kind == "model_attributes_type" and isinstance(error.get("input"), (bytes, str)):
        return "must be a JSON object sent as Content-Type: application/json"
    if kind in _TYPE_MESSAGES:
        return _TYPE_MESSAGES[kind]
    if kind == "value_error" and ctx.get("error") is not None:
        return str(ctx["error"])
    message = str(error.get("msg", "is not valid"))
    return message[:1].lower() + message[1:]


def format_validation_errors(errors: Iterable[Mapping[str, Any]]) -> str:
    """Turn FastAPI's list of validation errors into one sentence.

    Parameters
    ----------
    errors : iterable of dict
        ``RequestValidationError.errors()``: dicts with ``loc``, ``type``, ``msg``, ``ctx``.

    Returns
    -------
    str
        ``"<input>: <problem>"`` per error, joined with ``"; "``.

    Examples
    --------
    >>> format_validation_errors([{"loc": ("body", "interval_m"), "type": "missing"}])
    'interval_m: is required'
    >>> format_validation_errors([{"loc": ("body", "start", 0), "type": "float_parsing"}])
    'start[0]: must be a number'
    """
    sentences: list[str] = []
    for error in errors:
        kind = str(error.get("type", ""))
        loc = tuple(error.get("loc", ()))
        if kind == "json_invalid":
            loc = loc[:1]  # FastAPI puts the character offset after "body"
        sentence = f"{_location(loc)}: {_problem(error)}"
        if sentence not in sentences:
            sentences.append(sentence)
    return "; ".join(sentences) or "body: is not valid"


# --- Request body limit ---------------------------------------------------------------------


class BodySizeLimitMiddleware:
    """ASGI middleware answering 413 to request bodies over ``max_body_bytes``.

    A declared ``Content-Length`` over the limit is refused before anything is read. Otherwise
    the body is read (at most ``max_body_bytes`` of it) and counted as it streams in, so a
    chunked or lying request is refused as soon as it passes the limit; a body within the limit
    is handed to the app unchanged. Uploads are not buffered here: they stream through to the
    multipart parser (which spools files to disk past 1 MiB), counted on the way, and the
    request fails with 413 the moment they pass ``upload_bytes``.

    Parameters
    ----------
    app : ASGIApp
        The application to protect.
    max_body_bytes : int
        Largest body accepted [bytes].
    upload_bytes : int, optional
        Larger limit for the requests that upload files (``POST`` to a path matching
        ``upload_path``) [bytes].
    upload_path : str
        Regular expression of the upload paths.
    """

    def __init__(
        self,
        app: ASGIApp,
        *,
        max_body_bytes: int,
        upload_bytes: int | None = None,
        upload_path: str = r"^/api/plans/[^/]+/runs/?$",
    ) -> None:
        self.app = app
        self.max_body_bytes = max_body_bytes
        self.upload_bytes = upload_bytes
        self.upload_path = re.compile(upload_path)

    def _limit(self, scope: Scope) -> tuple[int, bool]:
        if (
            self.upload_bytes is not None
            and scope.get("method") == "POST"
            and self.upload_path.match(scope.get("path", ""))
        ):
            return max(self.upload_bytes, self.max_body_bytes), True
        return self.max_body_bytes, False

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Buffer and count the body, then run the app or answer 413."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit, upload = self._limit(scope)
        too_large = UploadTooLargeError(limit) if upload else BodyTooLargeError(limit)
        if _declared_length(scope) > limit:
            await error_response(too_large, _scope_language(scope))(scope, receive, send)
            return
        if upload:
            await self.app(scope, _counted(receive, limit, too_large), send)
            return

        chunks: list[bytes] = []
        size = 0
        while True:
            message = await receive()
            if message["type"] != "http.request":  # the client went away
                return
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > limit:
                await error_response(too_large, _scope_language(scope))(scope, receive, send)
                return
            chunks.append(chunk)
            if not message.get("more_body", False):
                break

        replayed = False

        async def replay() -> Message:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": b"".join(chunks), "more_body": False}
            return await receive()

        await self.app(scope, replay, send)


def _counted(receive: Receive, limit: int, too_large: BodyTooLargeError) -> Receive:
    """Wrap ``receive`` so that a body passing ``limit`` bytes fails the request with 413."""
    size = 0

    async def counted() -> Message:
        nonlocal size
        message = await receive()
        if message["type"] == "http.request":
            size += len(message.get("body", b""))
            if size > limit:
                # Raised inside the app's body parsing: FastAPI passes HTTPException through.
                raise HTTPException(status_code=413, detail=str(too_large))
        return message

    return counted


def _scope_language(scope: Scope) -> str:
    for key, value in scope.get("headers", ()):
        if key == b"accept-language":
            return negotiate_language(value.decode("latin-1"))
    return DEFAULT_LANGUAGE


def _declared_length(scope: Scope) -> int:
    for key, value in scope.get("headers", ()):
        if key == b"content-length":
            try:
                return int(value)
            except ValueError:
                return -1
    return -1
