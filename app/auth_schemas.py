"""Schemas of accounts, organisations and tokens (``/api/auth``, ``/api/me``, ``/api/tokens``)."""

from __future__ import annotations

import datetime as dt
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from app.auth_models import NAME_MAX_LENGTH
from app.schemas import StoredText

RoleName = Literal["viewer", "planner", "owner"]


class LoginBody(BaseModel):
    """Body of ``POST /api/auth/login``."""

    model_config = ConfigDict(extra="forbid")

    username: str = Field(max_length=NAME_MAX_LENGTH)
    password: str = Field(max_length=1024)


class SignUpBody(BaseModel):
    """Body of ``POST /api/auth/signup``: the first account of an empty server."""

    model_config = ConfigDict(extra="forbid")

    username: str = Field(min_length=1, max_length=NAME_MAX_LENGTH)
    password: str = Field(min_length=8, max_length=1024)
    organisation: StoredText = Field(
        default="default",
        min_length=1,
        max_length=NAME_MAX_LENGTH,
        description="Name of the first organisation (plans from before accounts go there).",
    )


class SetupRead(BaseModel):
    """Answer of ``GET /api/auth/setup``: whether the server still needs its first account."""

    needs_first_account: bool


class UserRead(BaseModel):
    """A user, without secrets."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    username: str


class OrganisationRole(BaseModel):
    """An organisation of the user and the user's role in it."""

    id: int
    name: str
    role: RoleName


class MeRead(BaseModel):
    """Who is signed in, in which organisation, and the CSRF token of a cookie session."""

    user: UserRead
    organisation: OrganisationRole = Field(description="The organisation requests act in.")
    organisations: list[OrganisationRole]
    via: Literal["session", "token"]
    csrf_token: str | None = Field(
        default=None,
        description="Send it as `X-CSRF-Token` with every write made with the session cookie.",
    )


class OrganisationChoice(BaseModel):
    """Body of ``PUT /api/me/organisation``."""

    model_config = ConfigDict(extra="forbid")

    organisation_id: int = Field(ge=1, le=2**31 - 1)


class TokenCreate(BaseModel):
    """Body of ``POST /api/tokens``."""

    model_config = ConfigDict(extra="forbid")

    name: StoredText = Field(default="", max_length=NAME_MAX_LENGTH, description="A label.")
    device: bool = Field(
        default=False,
        description="A device token for a tractor's logger: posts fixes to live runs of the "
        "current organisation, nothing else (owners only).",
    )


class TokenRead(BaseModel):
    """A token as listed: never the token itself."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    name: str
    kind: Literal["personal", "device"]
    prefix: str = Field(description="The token's first characters.")
    organisation_id: int | None
    created_at: dt.datetime
    last_used_at: dt.datetime | None
    revoked_at: dt.datetime | None


class TokenCreated(TokenRead):
    """A token just made: ``token`` is shown this once."""

    token: str


class TokenList(BaseModel):
    """The tokens the user may see and revoke."""

    items: list[TokenRead]


class MemberRead(BaseModel):
    """A member of the organisation and their role."""

    user_id: int
    username: str
    role: RoleName


class MemberList(BaseModel):
    """The organisation's members, by username."""

    items: list[MemberRead]


class MemberCreate(BaseModel):
    """Body of ``POST /api/members``: add a user (made when a password is given) with a role."""

    model_config = ConfigDict(extra="forbid")

    username: str = Field(min_length=1, max_length=NAME_MAX_LENGTH)
    role: RoleName = "viewer"
    password: str | None = Field(
        default=None,
        max_length=1024,
        description="For a new user: their password (at least 8 characters). An existing "
        "user keeps theirs.",
    )


class MemberUpdate(BaseModel):
    """Body of ``PATCH /api/members/{user_id}``."""

    model_config = ConfigDict(extra="forbid")

    role: RoleName
