"""Who may call a route: the access dependencies every route declares (style.md §7).

A request is authenticated by, in order:

- ``Authorization: Bearer <token>``: a personal API token (acts as its user) or a device token
  (a tractor's logger: may only post fixes to, and open, live runs of its organisation);
- the ``tillpath_session`` cookie of a signed-in browser. Every write (any method but GET,
  HEAD, OPTIONS) made with the cookie must echo the session's CSRF token in the
  ``X-CSRF-Token`` header (synchronizer token; ``GET /api/me`` and the login answer give it).

The organisation a request acts in is the ``X-Organisation`` header (an organisation id) if
given, else the one chosen on the page (``PUT /api/me/organisation``), else the user's first.
A device token always acts in its own organisation.

Routes declare what they need as a parameter::

    def read_plan(plan_id: int, session: SessionDep, access: Viewer) -> Plan: ...
    def create_plan(body: PlanCreate, session: SessionDep, access: Planner) -> Plan: ...

``Viewer``, ``Planner`` and ``Owner`` need that role or a stronger one; ``FixPoster`` also lets a
device token in; ``CurrentUser`` needs a signed-in person (no device token) in any organisation;
public routes declare ``dependencies=[Depends(public)]``. Every query of an owned table goes
through :func:`owned` / :func:`read_owned`, which filter by ``Access.organisation_id``: what
belongs to another organisation is a 404 exactly as if it did not exist.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import secrets
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import Annotated, Any, Final, Literal, TypeVar

from fastapi import Depends, HTTPException, Request, status
from fastapi.security import APIKeyCookie, APIKeyHeader, HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy import Select, bindparam, select, update
from sqlalchemy.orm import Session

from app.auth_models import ROLES, ApiToken, LoginSession, Membership, Organisation, User
from app.db import Base, SessionDep, end_reads
from app.errors import NotFoundError
from app.models import utc_now

#: The session cookie's name.
SESSION_COOKIE: Final = "tillpath_session"
#: The header that carries the CSRF token of a cookie-authenticated write.
CSRF_HEADER: Final = "X-CSRF-Token"
#: The header that chooses the organisation a request acts in.
ORGANISATION_HEADER: Final = "X-Organisation"
#: Prefix of every API token, so a leaked one is recognisable (secret scanners, logs).
TOKEN_PREFIX: Final = "tp_"
#: Random bytes in a token or session id (256 bits).
TOKEN_BYTES: Final = 32
#: ``last_used_at`` is written at most this often per token [s] (a write per fix batch would
#: contend with the fixes themselves).
LAST_USED_RESOLUTION_S: Final = 60
#: Ids outside this range cannot exist (32-bit integer keys).
MAX_ID: Final = 2**31 - 1

Role = Literal["viewer", "planner", "owner"]
Via = Literal["session", "token", "device"]
RowT = TypeVar("RowT", bound=Base)

_SAFE_METHODS: Final = frozenset({"GET", "HEAD", "OPTIONS"})

# FastAPI's security classes: they read the credentials and document the schemes in OpenAPI.
_bearer = HTTPBearer(
    auto_error=False,
    scheme_name="bearerToken",
    description="A personal API token or a device token (`tillpath tokens create`).",
)
_cookie = APIKeyCookie(
    name=SESSION_COOKIE,
    auto_error=False,
    scheme_name="sessionCookie",
    description=(
        "The signed-in page's session (`POST /api/auth/login`); writes also need the "
        f"`{CSRF_HEADER}` header."
    ),
)
_csrf = APIKeyHeader(
    name=CSRF_HEADER,
    auto_error=False,
    scheme_name="csrfToken",
    description="The session's CSRF token, for writes made with the session cookie.",
)


def new_secret() -> str:
    """Return a fresh high-entropy URL-safe secret (token or session id)."""
    return secrets.token_urlsafe(TOKEN_BYTES)


def new_api_token() -> str:
    """Return a fresh API token: ``tp_`` and 43 URL-safe characters."""
    return TOKEN_PREFIX + new_secret()


def sha256_hex(secret: str) -> str:
    """Return the SHA-256 of ``secret`` as hex: how tokens and session ids are stored.

    A token carries 256 random bits, so a fast hash suffices (no salt or stretching needed,
    unlike passwords).
    """
    return hashlib.sha256(secret.encode()).hexdigest()


@dataclass(frozen=True, slots=True)
class Credentials:
    """Who is calling, before an organisation is chosen.

    ``roles`` is the user's role in each organisation (by id), read with the credentials
    themselves; None if it was not (:func:`resolve_access` then reads it).
    """

    user: User
    via: Via
    token: ApiToken | None = None
    login_session: LoginSession | None = None
    roles: dict[int, str] | None = None


@dataclass(frozen=True, slots=True)
class Access:
    """What a request may do: the organisation it acts in and its role there.

    Attributes
    ----------
    organisation_id : int
        Every owned row the request reads or writes has this ``organisation_id``.
    role : str
        ``viewer``, ``planner``, ``owner``, or ``device`` for a device token.
    user_id : int
        The user (for a device token, the user who made it).
    via : str
        ``session``, ``token`` or ``device``.
    token_id : int or None
        The API token used, if any.
    """

    organisation_id: int
    role: str
    user_id: int
    via: Via
    token_id: int | None = None

    def at_least(self, role: Role) -> bool:
        """Tell whether this access has ``role`` or a stronger one (a device has none)."""
        return self.role in ROLES and ROLES.index(self.role) >= ROLES.index(role)


def _unauthorized(detail: str) -> HTTPException:
    return HTTPException(
        status.HTTP_401_UNAUTHORIZED, detail, headers={"WWW-Authenticate": "Bearer"}
    )


def forbidden(detail: str) -> HTTPException:
    """Return a 403 whose detail says what was missing."""
    return HTTPException(status.HTTP_403_FORBIDDEN, detail)


@cache
def _credentials_query(
    model: type[ApiToken] | type[LoginSession],
) -> Select[Base, User, int, str]:
    """Return the look-up of :func:`_with_user_and_roles`, built once per model.

    Built afresh, the statement's construction and cache key took a third of the look-up's
    CPU on every request; built once, SQLAlchemy keys it once and reuses its compiled form.
    """
    return (
        select(model, User, Membership.organisation_id, Membership.role)
        .join(User, User.id == model.user_id)
        .outerjoin(Membership, Membership.user_id == User.id)
        .where(model.token_sha256 == bindparam("token_sha256"))
    )


def _with_user_and_roles(
    session: Session, model: type[ApiToken] | type[LoginSession], token_sha256: str
) -> tuple[Any, User, dict[int, str]] | None:
    """Return the token or login session with this hash, its user and the user's roles.

    One query (a row per membership) instead of three: every authenticated request makes
    it, and on the paper field's preview the separate ORM queries took longer than planning.
    """
    rows = session.execute(_credentials_query(model), {"token_sha256": token_sha256}).all()
    if not rows:
        return None
    roles = {org: role for _, _, org, role in rows if org is not None}
    return rows[0][0], rows[0][1], roles


def _token_credentials(session: Session, token: str) -> Credentials:
    found = _with_user_and_roles(session, ApiToken, sha256_hex(token))
    if found is None or found[0].revoked_at is not None:
        raise _unauthorized("authorization: the token is unknown or revoked")
    row, user, roles = found
    now = utc_now()
    if row.last_used_at is None or (now - row.last_used_at).total_seconds() > (
        LAST_USED_RESOLUTION_S
    ):
        end_reads(session)
        session.execute(update(ApiToken).where(ApiToken.id == row.id).values(last_used_at=now))
        session.commit()
        row.last_used_at = now
    via: Via = "device" if row.kind == "device" else "token"
    return Credentials(user=user, via=via, token=row, roles=roles)


def _session_credentials(session: Session, cookie: str) -> Credentials | None:
    found = _with_user_and_roles(session, LoginSession, sha256_hex(cookie))
    if found is None or found[0].expires_at <= utc_now():
        return None
    row, user, roles = found
    return Credentials(user=user, via="session", login_session=row, roles=roles)


BearerDep = Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)]
CookieDep = Annotated[str | None, Depends(_cookie)]
CsrfDep = Annotated[str | None, Depends(_csrf)]


def credentials(
    request: Request, session: SessionDep, bearer: BearerDep, cookie: CookieDep, csrf: CsrfDep
) -> Credentials:
    """Authenticate the request by bearer token or session cookie (with CSRF on writes).

    Raises
    ------
    HTTPException
        401 without valid credentials; 403 for a cookie-authenticated write without the
        session's CSRF token.
    """
    if bearer is not None:
        return _token_credentials(session, bearer.credentials)
    if request.headers.get("authorization"):
        raise _unauthorized("authorization: expected `Bearer <token>`")
    found = _session_credentials(session, cookie) if cookie else None
    if found is None:
        raise _unauthorized("sign in first, or send an API token as `Authorization: Bearer …`")
    assert found.login_session is not None
    if request.method not in _SAFE_METHODS and not (
        csrf and secrets.compare_digest(csrf, found.login_session.csrf_token)
    ):
        raise forbidden(
            f"{CSRF_HEADER}: missing or wrong; writes made with the session cookie must send "
            "the session's CSRF token (GET /api/me gives it)"
        )
    return found


CredentialsDep = Annotated[Credentials, Depends(credentials)]


def memberships(session: Session, user_id: int) -> list[tuple[Membership, Organisation]]:
    """Return a user's memberships with their organisations, by organisation id."""
    rows = session.execute(
        select(Membership, Organisation)
        .join(Organisation, Organisation.id == Membership.organisation_id)
        .where(Membership.user_id == user_id)
        .order_by(Organisation.id)
    ).all()
    return [(m, o) for m, o in rows]


def _requested_organisation(request: Request) -> int | None:
    text = request.headers.get(ORGANISATION_HEADER)
    if text is None:
        return None
    try:
        ident = int(text)
    except ValueError:
        raise HTTPException(
            status.HTTP_422_UNPROCESSABLE_CONTENT,
            f"{ORGANISATION_HEADER}: must be an organisation id (a whole number), "
            f"got {text[:40]!r}",
        ) from None
    return ident


def resolve_access(request: Request, session: Session, creds: Credentials) -> Access:
    """Choose the organisation the request acts in and the caller's role there.

    Raises
    ------
    HTTPException
        404 if ``X-Organisation`` names an organisation the user does not belong to (as if it
        did not exist); 403 if the user belongs to none.
    """
    requested = _requested_organisation(request)
    if creds.via == "device":
        assert creds.token is not None and creds.token.organisation_id is not None
        if requested is not None and requested != creds.token.organisation_id:
            raise HTTPException(status.HTTP_404_NOT_FOUND, f"organisation {requested} not found")
        return Access(
            organisation_id=creds.token.organisation_id,
            role="device",
            user_id=creds.user.id,
            via="device",
            token_id=creds.token.id,
        )
    roles = creds.roles
    if roles is None:
        roles = {m.organisation_id: m.role for m, _ in memberships(session, creds.user.id)}
    if requested is not None:
        if requested not in roles:
            raise HTTPException(status.HTTP_404_NOT_FOUND, f"organisation {requested} not found")
        chosen = requested
    elif creds.login_session is not None and creds.login_session.organisation_id in roles:
        chosen = creds.login_session.organisation_id
    elif roles:
        chosen = min(roles)
    else:
        raise forbidden("you belong to no organisation: ask an owner to add you to one")
    return Access(
        organisation_id=chosen,
        role=roles[chosen],
        user_id=creds.user.id,
        via=creds.via,
        token_id=creds.token.id if creds.token else None,
    )


AccessRule = Literal["viewer", "planner", "owner", "fixes"]


def _rule(dependency: Callable[..., Any], rule: str) -> Callable[..., Any]:
    """Mark an access dependency with its rule (the access-matrix test reads it)."""
    dependency.access_rule = rule  # type: ignore[attr-defined]
    return dependency


def require_role(role: Role) -> Callable[..., Access]:
    """Build the dependency that lets in ``role`` and stronger roles, never a device token.

    Parameters
    ----------
    role : {"viewer", "planner", "owner"}
        The weakest role allowed.

    Returns
    -------
    callable
        A FastAPI dependency returning the request's :class:`Access`; 401 without
        credentials, 403 naming the role needed.
    """

    def dependency(
        request: Request, session: SessionDep, bearer: BearerDep, cookie: CookieDep, csrf: CsrfDep
    ) -> Access:
        # Authenticated here rather than through CredentialsDep: FastAPI runs each sync
        # dependency in a worker thread of its own, and a thread hop less counts per request.
        creds = credentials(request, session, bearer, cookie, csrf)
        access = resolve_access(request, session, creds)
        if access.via == "device":
            raise forbidden(
                "a device token may only post fixes to live runs of its organisation; "
                "use a personal token or sign in"
            )
        if not access.at_least(role):
            raise forbidden(f"this needs the {role} role (you are {access.role})")
        end_reads(session)
        return access

    dependency.__name__ = f"require_{role}"
    return _rule(dependency, role)


def require_fix_poster(
    request: Request, session: SessionDep, bearer: BearerDep, cookie: CookieDep, csrf: CsrfDep
) -> Access:
    """Let in a device token of the organisation, or a planner or owner."""
    creds = credentials(request, session, bearer, cookie, csrf)  # as in require_role
    access = resolve_access(request, session, creds)
    if access.via != "device" and not access.at_least("planner"):
        raise forbidden(f"this needs the planner role or a device token (you are {access.role})")
    end_reads(session)
    return access


_rule(require_fix_poster, "fixes")


def current_user(session: SessionDep, creds: CredentialsDep) -> User:
    """Return the signed-in person (session or personal token); 403 for a device token."""
    if creds.via == "device":
        raise forbidden("a device token may only post fixes to live runs of its organisation")
    end_reads(session)
    return creds.user


_rule(current_user, "user")


def public() -> None:
    """Mark a route that needs no credentials (health, login, sign-up)."""


_rule(public, "public")


def declared_rules(route: Any) -> set[str]:
    """Return the access rules a route declares (``public``, ``user``, a role, ``fixes``).

    Walks the route's dependency tree for the dependencies of this module; the access-matrix
    test uses it so that a route that declares none fails.
    """
    found: set[str] = set()
    stack = list(getattr(getattr(route, "dependant", None), "dependencies", []))
    while stack:
        dependant = stack.pop()
        rule = getattr(dependant.call, "access_rule", None)
        if rule is not None:
            found.add(rule)
        stack.extend(dependant.dependencies)
    return found


Viewer = Annotated[Access, Depends(require_role("viewer"))]
Planner = Annotated[Access, Depends(require_role("planner"))]
Owner = Annotated[Access, Depends(require_role("owner"))]
FixPoster = Annotated[Access, Depends(require_fix_poster)]
CurrentUser = Annotated[User, Depends(current_user)]


# --- The one way to query an owned table -----------------------------------------------------


def owned(model: type[RowT], access: Access) -> Select[RowT]:
    """Return ``select(model)`` limited to the rows of the request's organisation.

    Every query of a table with ``organisation_id`` (fields, plans, simulations, runs, jobs)
    starts here, so a forgotten filter cannot leak another organisation's rows.
    """
    column = model.__table__.c.organisation_id
    return select(model).where(column == access.organisation_id)


def read_owned(
    session: Session, model: type[RowT], ident: int, access: Access, *, kind: str
) -> RowT:
    """Return the ``model`` row ``ident`` of the request's organisation.

    Raises
    ------
    NotFoundError
        ``<kind> <ident> not found`` if there is no such row, or it belongs to another
        organisation (the same answer, so ids of other organisations cannot be probed).
    """
    found = None
    if 1 <= ident <= MAX_ID:
        found = session.get(model, ident)
        if found is not None and getattr(found, "organisation_id", None) != access.organisation_id:
            found = None
    if found is None:
        raise NotFoundError(kind, ident)
    return found


def session_lifetime() -> dt.timedelta:
    """How long a sign-in lasts without signing in again."""
    return dt.timedelta(days=14)
