"""Accounts (product.md §12): sign-up, sign-in and -out, who am I, organisations and tokens."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Depends, Request, Response, status

from app import accounts
from app.auth import (
    SESSION_COOKIE,
    Credentials,
    CredentialsDep,
    CurrentUser,
    forbidden,
    memberships,
    public,
    resolve_access,
    session_lifetime,
)
from app.auth_models import User
from app.auth_schemas import (
    LoginBody,
    MeRead,
    OrganisationChoice,
    OrganisationRole,
    SetupRead,
    SignUpBody,
    TokenCreate,
    TokenCreated,
    TokenList,
    TokenRead,
    UserRead,
)
from app.db import SessionDep
from app.dependencies import SettingsDep
from app.errors import ConflictError
from app.schemas import ErrorRead
from app.settings import Settings

router = APIRouter(tags=["accounts"])

_ERRORS: dict[int | str, dict[str, Any]] = {
    401: {"model": ErrorRead, "description": "Not signed in, or a wrong username or password"},
    422: {"model": ErrorRead, "description": "The input named in `detail` is wrong"},
}


def _address(request: Request) -> str:
    return request.client.host if request.client else "unknown"


def _set_cookie(response: Response, value: str, settings: Settings) -> None:
    response.set_cookie(
        SESSION_COOKIE,
        value,
        max_age=int(session_lifetime().total_seconds()),
        httponly=True,
        samesite="lax",
        secure=settings.secure_cookies,
        path="/",
    )


def _me(request: Request, session: SessionDep, creds: Credentials) -> MeRead:
    access = resolve_access(request, session, creds)
    orgs = [
        OrganisationRole(id=o.id, name=o.name, role=m.role)  # type: ignore[arg-type]
        for m, o in memberships(session, creds.user.id)
    ]
    current = next(o for o in orgs if o.id == access.organisation_id)
    return MeRead(
        user=UserRead.model_validate(creds.user),
        organisation=current,
        organisations=orgs,
        via="session" if creds.via == "session" else "token",
        csrf_token=creds.login_session.csrf_token if creds.login_session else None,
    )


def _signed_in(
    request: Request, session: SessionDep, user: User, settings: Settings, response: Response
) -> MeRead:
    started = accounts.start_login_session(session, user)
    _set_cookie(response, started.cookie, settings)
    creds = Credentials(user=user, via="session", login_session=started.row)
    return _me(request, session, creds)


@router.get("/auth/setup", response_model=SetupRead, dependencies=[Depends(public)])
def read_setup(session: SessionDep) -> SetupRead:
    """Tell whether the server has no account yet (the page then asks for the first one)."""
    return SetupRead(needs_first_account=accounts.user_count(session) == 0)


@router.post(
    "/auth/signup",
    response_model=MeRead,
    status_code=status.HTTP_201_CREATED,
    dependencies=[Depends(public)],
    responses={**_ERRORS, 409: {"model": ErrorRead, "description": "Accounts exist already"}},
)
def sign_up(
    body: SignUpBody,
    request: Request,
    session: SessionDep,
    response: Response,
    settings: SettingsDep,
) -> MeRead:
    """Create the first account of an empty server (its owner) and sign in."""
    user = accounts.sign_up_first(session, body.username, body.password, body.organisation)
    return _signed_in(request, session, user, settings, response)


@router.post(
    "/auth/login",
    response_model=MeRead,
    dependencies=[Depends(public)],
    responses={**_ERRORS, 429: {"model": ErrorRead, "description": "Too many failed sign-ins"}},
)
def log_in(
    body: LoginBody,
    request: Request,
    session: SessionDep,
    response: Response,
    settings: SettingsDep,
) -> MeRead:
    """Sign in: sets the `HttpOnly`, `SameSite=Lax` session cookie; answers the CSRF token.

    A wrong username and a wrong password get the same answer. Twenty failures of an account
    (or a hundred from one address) within 15 minutes stop sign-in there for the rest of the
    15 minutes (429 with `Retry-After`).
    """
    user = accounts.authenticate_password(session, body.username, body.password, _address(request))
    return _signed_in(request, session, user, settings, response)


@router.post(
    "/auth/logout",
    status_code=status.HTTP_204_NO_CONTENT,
    response_class=Response,
    responses=_ERRORS,
)
def log_out(
    user: CurrentUser,
    creds: CredentialsDep,
    session: SessionDep,
    settings: SettingsDep,
) -> Response:
    """Sign out: the session ends at once (a token is revoked with `DELETE /api/tokens/{id}`)."""
    if creds.login_session is not None:
        accounts.end_login_session(session, creds.login_session)
    response = Response(status_code=status.HTTP_204_NO_CONTENT)
    response.delete_cookie(
        SESSION_COOKIE, path="/", httponly=True, samesite="lax", secure=settings.secure_cookies
    )
    return response


@router.get("/me", response_model=MeRead, responses=_ERRORS)
def read_me(
    user: CurrentUser, creds: CredentialsDep, request: Request, session: SessionDep
) -> MeRead:
    """Who is signed in, their organisations and roles, and the session's CSRF token."""
    return _me(request, session, creds)


@router.put(
    "/me/organisation",
    response_model=MeRead,
    responses={**_ERRORS, 404: {"model": ErrorRead, "description": "Not a member"}},
)
def choose_organisation(
    body: OrganisationChoice,
    user: CurrentUser,
    creds: CredentialsDep,
    request: Request,
    session: SessionDep,
) -> MeRead:
    """Switch the organisation the signed-in page acts in (tokens send `X-Organisation`)."""
    if creds.login_session is None:
        raise ConflictError(
            "organisation: a token chooses its organisation per request with the "
            "X-Organisation header"
        )
    accounts.choose_organisation(session, creds.login_session, body.organisation_id)
    return _me(request, session, creds)


@router.get("/tokens", response_model=TokenList, responses=_ERRORS)
def list_tokens(
    user: CurrentUser, creds: CredentialsDep, request: Request, session: SessionDep
) -> TokenList:
    """List your personal tokens and, for an owner, the organisation's device tokens."""
    access = resolve_access(request, session, creds)
    tokens = accounts.visible_tokens(session, user, access)
    return TokenList(items=[TokenRead.model_validate(t) for t in tokens])


@router.post(
    "/tokens",
    response_model=TokenCreated,
    status_code=status.HTTP_201_CREATED,
    responses={**_ERRORS, 403: {"model": ErrorRead, "description": "Device tokens: owners"}},
)
def create_token(
    body: TokenCreate,
    user: CurrentUser,
    creds: CredentialsDep,
    request: Request,
    session: SessionDep,
    response: Response,
) -> TokenCreated:
    """Make a personal token, or (owners) a device token of the current organisation.

    The token is in this answer only; it is stored hashed and cannot be shown again.
    """
    access = resolve_access(request, session, creds)
    if body.device and not access.at_least("owner"):
        raise forbidden(f"a device token needs the owner role (you are {access.role})")
    made = accounts.create_token(
        session,
        user,
        name=body.name,
        device=body.device,
        organisation_id=access.organisation_id if body.device else None,
    )
    response.headers["Location"] = f"/api/tokens/{made.row.id}"
    return TokenCreated(**TokenRead.model_validate(made.row).model_dump(), token=made.token)


@router.delete(
    "/tokens/{token_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    response_class=Response,
    responses={**_ERRORS, 404: {"model": ErrorRead, "description": "No such token"}},
)
def revoke_token(
    token_id: int, user: CurrentUser, creds: CredentialsDep, request: Request, session: SessionDep
) -> None:
    """Revoke a token: it stops working at once."""
    access = resolve_access(request, session, creds)
    accounts.revoke_token(session, user, access, token_id)
