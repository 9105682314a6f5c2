"""Tables of the cooperative's workspace (product.md §12): organisations, users, tokens, sessions.

Secrets are never stored: passwords as Argon2 hashes (argon2-cffi), API tokens and session ids
as the SHA-256 of a high-entropy random value (``secrets.token_urlsafe``), so a copy of the
database lets nobody sign in.
"""

from __future__ import annotations

import datetime as dt

from sqlalchemy import Boolean, ForeignKey, Integer, String, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from app.db import Base
from app.models import UTCDateTime, utc_now

#: Longest user, organisation and token name [characters].
NAME_MAX_LENGTH = 100
#: The roles, weakest first: each may do what the ones before it may.
ROLES = ("viewer", "planner", "owner")
#: Kinds of API token.
TOKEN_KINDS = ("personal", "device")


class Organisation(Base):
    """A cooperative, a farm or a service provider: owns fields, plans, simulations and runs."""

    __tablename__ = "organisations"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(NAME_MAX_LENGTH), unique=True)
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)


class User(Base):
    """A person who signs in; ``password_hash`` is an Argon2id hash string."""

    __tablename__ = "users"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    username: Mapped[str] = mapped_column(String(NAME_MAX_LENGTH), unique=True)
    password_hash: Mapped[str] = mapped_column(String(255))
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)


class Membership(Base):
    """A user's role in an organisation: ``viewer``, ``planner`` or ``owner``."""

    __tablename__ = "memberships"
    __table_args__ = (UniqueConstraint("user_id", "organisation_id"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    organisation_id: Mapped[int] = mapped_column(
        ForeignKey("organisations.id", ondelete="CASCADE"), index=True
    )
    role: Mapped[str] = mapped_column(String(16))


class ApiToken(Base):
    """A bearer token: ``personal`` (acts as its user) or ``device`` (posts fixes only).

    A personal token reaches every organisation of its user (choose one with the
    ``X-Organisation`` header); a device token belongs to one organisation.
    """

    __tablename__ = "api_tokens"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    organisation_id: Mapped[int | None] = mapped_column(
        ForeignKey("organisations.id", ondelete="CASCADE"), index=True
    )
    kind: Mapped[str] = mapped_column(String(16))
    name: Mapped[str] = mapped_column(String(NAME_MAX_LENGTH))
    token_sha256: Mapped[str] = mapped_column(String(64), unique=True)
    #: The token's first characters, shown in lists so a person can tell tokens apart.
    prefix: Mapped[str] = mapped_column(String(16))
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)
    last_used_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime())
    revoked_at: Mapped[dt.datetime | None] = mapped_column(UTCDateTime())


class LoginSession(Base):
    """A signed-in browser: the cookie holds a random id, the table its SHA-256.

    ``csrf_token`` is the synchronizer token every cookie-authenticated write must echo in the
    ``X-CSRF-Token`` header; ``organisation_id`` is the organisation chosen on the page.
    """

    __tablename__ = "login_sessions"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    token_sha256: Mapped[str] = mapped_column(String(64), unique=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"), index=True)
    organisation_id: Mapped[int | None] = mapped_column(
        ForeignKey("organisations.id", ondelete="SET NULL")
    )
    csrf_token: Mapped[str] = mapped_column(String(64))
    created_at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now)
    expires_at: Mapped[dt.datetime] = mapped_column(UTCDateTime())


class LoginAttempt(Base):
    """One failed sign-in, for throttling per account and per address."""

    __tablename__ = "login_attempts"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    username: Mapped[str] = mapped_column(String(NAME_MAX_LENGTH), index=True)
    address: Mapped[str] = mapped_column(String(64), index=True)
    at: Mapped[dt.datetime] = mapped_column(UTCDateTime(), default=utc_now, index=True)
    succeeded: Mapped[bool] = mapped_column(Boolean, default=False)
