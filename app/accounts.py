"""Accounts: users, organisations, API tokens, sign-in sessions and throttling.

An organisation's members (roles, the last owner) are :mod:`app.members`'s.

Passwords are hashed with Argon2id by argon2-cffi (its ``PasswordHasher`` defaults, RFC 9106's
low-memory profile); tokens and session ids are 256-bit ``secrets.token_urlsafe`` values stored
as their SHA-256 (:mod:`app.auth`). Nothing here is home-made cryptography.
"""

from __future__ import annotations

import datetime as dt
import re
from dataclasses import dataclass
from typing import Final

from argon2 import PasswordHasher
from argon2.exceptions import InvalidHashError, VerificationError
from sqlalchemy import delete, func, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from app.auth import (
    Access,
    new_api_token,
    new_secret,
    session_lifetime,
    sha256_hex,
)
from app.auth_models import (
    NAME_MAX_LENGTH,
    ROLES,
    ApiToken,
    LoginAttempt,
    LoginSession,
    Membership,
    Organisation,
    User,
)
from app.db import begin_write, end_reads, serialise_writes, write
from app.errors import (
    AccountError,
    ConflictError,
    NotFoundError,
    SignInError,
    ThrottledError,
)
from app.models import utc_now

#: The organisation of the first account, and of the plans made before organisations existed.
DEFAULT_ORGANISATION: Final = "default"
#: Shortest password accepted [characters].
PASSWORD_MIN_LENGTH: Final = 8
#: Longest password accepted [characters] (Argon2 takes any length; this bounds the work).
PASSWORD_MAX_LENGTH: Final = 1024
#: Failed sign-ins of one account within :data:`THROTTLE_WINDOW` that lock it for the rest of
#: the window.
ACCOUNT_FAILURE_LIMIT: Final = 20
#: Failed sign-ins from one address within :data:`THROTTLE_WINDOW` that stop it for the rest
#: of the window.
ADDRESS_FAILURE_LIMIT: Final = 100
THROTTLE_WINDOW: Final = dt.timedelta(minutes=15)
#: Key of the PostgreSQL advisory lock that first sign-ups take one at a time (any constant no
#: other lock of the app uses).
FIRST_ACCOUNT_LOCK_KEY: Final = 0x7469_6C6C_0001

_USERNAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._@-]*$")
_hasher = PasswordHasher()
#: Verified against when the user does not exist, so that an unknown name takes as long.
_DUMMY_HASH: Final = _hasher.hash("not a password of anyone")


def check_username(username: str) -> str:
    """Return ``username`` stripped, or raise :class:`AccountError` saying what is wrong."""
    name = username.strip()
    if not 1 <= len(name) <= NAME_MAX_LENGTH or not _USERNAME.match(name):
        raise AccountError(
            f"username: {name[:40]!r} must be 1–{NAME_MAX_LENGTH} letters, digits or . _ @ -, "
            "starting with a letter or digit"
        )
    return name


def check_password(password: str) -> str:
    """Return ``password`` if it may be used, else raise :class:`AccountError`."""
    if not PASSWORD_MIN_LENGTH <= len(password) <= PASSWORD_MAX_LENGTH:
        raise AccountError(
            f"password: must be {PASSWORD_MIN_LENGTH} to {PASSWORD_MAX_LENGTH} characters long"
        )
    return password


def hash_password(password: str) -> str:
    """Return the Argon2id hash string of ``password``."""
    return _hasher.hash(password)


def verify_password(password_hash: str, password: str) -> bool:
    """Tell whether ``password`` matches ``password_hash`` (never raises on a mismatch)."""
    try:
        return _hasher.verify(password_hash, password)
    except (VerificationError, InvalidHashError):
        return False


def check_role(role: str) -> str:
    """Return ``role`` if it is one of :data:`ROLES`, else raise :class:`AccountError`."""
    if role not in ROLES:
        raise AccountError(f"role: must be one of {', '.join(ROLES)}, got {role!r}")
    return role


def get_or_create_organisation(session: Session, name: str) -> Organisation:
    """Return the organisation called ``name``, adding it if missing (flushed)."""
    name = name.strip()
    if not 1 <= len(name) <= NAME_MAX_LENGTH:
        raise AccountError(f"organisation: must be 1–{NAME_MAX_LENGTH} characters")
    found = session.scalar(select(Organisation).where(Organisation.name == name))
    if found is None:
        found = Organisation(name=name)
        session.add(found)
        session.flush()
    return found


def user_count(session: Session) -> int:
    """Return how many users there are (0: the server asks for the first account)."""
    return session.scalar(select(func.count()).select_from(User)) or 0


def _hash_in_advance(password: str) -> str | AccountError:
    """Return ``password``'s Argon2 hash, or the error saying why it cannot be used.

    Called with no transaction open, so that no Argon2 (tens of ms of CPU) runs while SQLite's
    write lock is held and every other writer (a tractor's fixes) waits. The error matters only
    if the user turns out to be new: an existing user keeps their password, whatever was given.
    """
    try:
        return hash_password(check_password(password))
    except AccountError as exc:
        return exc


def _user_named(session: Session, name: str) -> User | None:
    return session.scalar(select(User).where(User.username == name))


def begin_user_write(
    session: Session, name: str, password: str | None
) -> tuple[User | None, str | AccountError | None]:
    """Begin the write transaction (the caller commits) that adds user ``name`` or gives a role.

    Whether the user exists is read first, without the write lock; ``password`` is hashed, still
    without it, only if not: an existing user keeps their password, so costs no Argon2.

    Returns
    -------
    user : User or None
        The user, read in the write transaction; None if there is none.
    password_hash : str or AccountError or None
        ``password``'s hash, or the error saying why it cannot be used
        (:func:`_hash_in_advance`); None if no ``password`` was given, or if the user existed
        when first read (``user`` is then not None).
    """
    exists = session.scalar(select(User.id).where(User.username == name)) is not None
    end_reads(session)
    password_hash = None if password is None or exists else _hash_in_advance(password)
    begin_write(session)
    user = _user_named(session, name)
    if user is None and password is not None and password_hash is None:
        # Deleted since the read. Hashing now would hold SQLite's write lock for ~0.1 s, so the
        # transaction (nothing written yet) ends, the hash is made, and the write starts again
        # once. That second pass has the hash whatever it finds, so it cannot come back here;
        # an AccountError instead would refuse a valid request because of someone else's delete.
        end_reads(session)
        password_hash = _hash_in_advance(password)
        begin_write(session)
        user = _user_named(session, name)
    return user, password_hash


def new_user(session: Session, name: str, password_hash: str | AccountError | None) -> User:
    """Add user ``name`` (flushed); raise AccountError if the password is missing or bad."""
    if password_hash is None:
        raise AccountError(f"username: no user called {name!r}; give a password to make one")
    if isinstance(password_hash, AccountError):
        raise password_hash
    user = User(username=name, password_hash=password_hash)
    session.add(user)
    session.flush()
    return user


def create_user(
    session: Session,
    username: str,
    password: str,
    *,
    organisation: str = DEFAULT_ORGANISATION,
    role: str = "owner",
) -> User:
    """Add a user with a role in ``organisation`` (made if missing) and commit.

    A user that exists already keeps its password and gets the role in the organisation. The
    password is hashed only for a new user, before the write transaction that shares the reads
    and writes (:func:`begin_user_write`).

    Raises
    ------
    AccountError
        For a name, password or role that cannot be used.
    """
    name = check_username(username)
    check_role(role)
    user, password_hash = begin_user_write(session, name, password)
    return _store_user(session, name, user, password_hash, organisation=organisation, role=role)


def _store_user(
    session: Session,
    name: str,
    user: User | None,
    password_hash: str | AccountError | None,
    *,
    organisation: str,
    role: str,
) -> User:
    """Do :func:`create_user`'s writes in the caller's write transaction; commit.

    ``user`` is the user called ``name`` as read in that transaction (None: add it).
    """
    if user is None:
        user = new_user(session, name, password_hash)
    org = get_or_create_organisation(session, organisation)
    membership = session.scalar(
        select(Membership).where(
            Membership.user_id == user.id, Membership.organisation_id == org.id
        )
    )
    if membership is None:
        session.add(Membership(user_id=user.id, organisation_id=org.id, role=role))
    else:
        membership.role = role
    try:
        session.commit()
    except IntegrityError:
        session.rollback()
        raise AccountError(f"username: {name!r} was just taken; choose another") from None
    return user


def find_user(session: Session, username: str) -> User:
    """Return the user called ``username``.

    Raises
    ------
    NotFoundError
        If there is none.
    """
    user = session.scalar(select(User).where(User.username == username.strip()))
    if user is None:
        raise AccountError(f"--user: no user called {username!r}")
    return user


@dataclass(frozen=True, slots=True)
class NewToken:
    """A token just made: its row, and the token itself (shown once, never stored)."""

    row: ApiToken
    token: str


def create_token(
    session: Session,
    user: User,
    *,
    name: str,
    device: bool = False,
    organisation_id: int | None = None,
) -> NewToken:
    """Make an API token for ``user`` and commit; only its SHA-256 is stored.

    Parameters
    ----------
    name : str
        A label (the tractor's name, the script's purpose).
    device : bool
        A device token (posts fixes only, in ``organisation_id``) instead of a personal one.
    organisation_id : int, optional
        The device token's organisation (required for a device token).
    """
    begin_write(session)
    label = name.strip()[:NAME_MAX_LENGTH] or ("device" if device else "token")
    if device and organisation_id is None:
        raise AccountError("organisation: a device token belongs to one organisation")
    token = new_api_token()
    row = ApiToken(
        user_id=user.id,
        organisation_id=organisation_id if device else None,
        kind="device" if device else "personal",
        name=label,
        token_sha256=sha256_hex(token),
        prefix=token[:10],
    )
    session.add(row)
    session.commit()
    return NewToken(row=row, token=token)


def first_organisation(session: Session, user: User) -> Organisation:
    """Return the user's first organisation (by id)."""
    org = session.scalar(
        select(Organisation)
        .join(Membership, Membership.organisation_id == Organisation.id)
        .where(Membership.user_id == user.id)
        .order_by(Organisation.id)
        .limit(1)
    )
    if org is None:
        raise AccountError(f"--user: {user.username!r} belongs to no organisation")
    return org


def visible_tokens(session: Session, user: User, access: Access | None) -> list[ApiToken]:
    """Return the tokens a user may see and revoke, newest first, revoked ones included.

    That is the user's personal tokens, and the device tokens of ``access``'s organisation
    when the user owns it.
    """
    query = select(ApiToken).where(ApiToken.user_id == user.id, ApiToken.kind == "personal")
    tokens = list(session.scalars(query))
    if access is not None and access.at_least("owner"):
        tokens += list(
            session.scalars(
                select(ApiToken).where(
                    ApiToken.kind == "device",
                    ApiToken.organisation_id == access.organisation_id,
                )
            )
        )
    return sorted(tokens, key=lambda t: (t.created_at, t.id), reverse=True)


def revoke_token(session: Session, user: User, access: Access | None, token_id: int) -> None:
    """Revoke a token the user may see (:func:`visible_tokens`); it stops working at once.

    Raises
    ------
    NotFoundError
        If the user may not see such a token.
    """
    begin_write(session)
    for token in visible_tokens(session, user, access):
        if token.id == token_id:
            if token.revoked_at is None:
                token.revoked_at = utc_now()
                session.commit()
            return
    raise NotFoundError("token", token_id)


# --- Sign-in ---------------------------------------------------------------------------------


def _check_throttle(session: Session, username: str, address: str) -> None:
    now = utc_now()
    since = now - THROTTLE_WINDOW
    for column, value, limit, what in (
        (LoginAttempt.username, username, ACCOUNT_FAILURE_LIMIT, "this account"),
        (LoginAttempt.address, address, ADDRESS_FAILURE_LIMIT, "this address"),
    ):
        count, oldest = session.execute(
            select(func.count(), func.min(LoginAttempt.at)).where(
                column == value, LoginAttempt.at > since, LoginAttempt.succeeded.is_(False)
            )
        ).one()
        if count >= limit:
            oldest_at = oldest if oldest.tzinfo else oldest.replace(tzinfo=dt.UTC)
            retry = int((oldest_at + THROTTLE_WINDOW - now).total_seconds()) + 1
            raise ThrottledError(what, max(retry, 1))


def _record_failure(session: Session, username: str, address: str) -> None:
    session.add(LoginAttempt(username=username[:NAME_MAX_LENGTH], address=address[:64]))
    session.execute(delete(LoginAttempt).where(LoginAttempt.at < utc_now() - 8 * THROTTLE_WINDOW))


def authenticate_password(session: Session, username: str, password: str, address: str) -> User:
    """Check a username and password, throttled per account and per address.

    Raises
    ------
    ThrottledError
        After :data:`ACCOUNT_FAILURE_LIMIT` failures of the account or
        :data:`ADDRESS_FAILURE_LIMIT` of the address within :data:`THROTTLE_WINDOW`.
    SignInError
        If either is wrong (the same answer, and about the same time, for both).
    """
    # No stored name has a NUL (check_username); PostgreSQL could not even compare one.
    name = username.replace("\x00", "").strip()[:NAME_MAX_LENGTH]
    _check_throttle(session, name, address)
    user = session.scalar(select(User).where(User.username == name))
    # The password is checked (argon2, tens of ms) with no transaction open, and what sign-in
    # changes is written in a transaction of its own (app.db.write): on SQLite a read
    # transaction cannot become a write one once another client (a tractor's fixes) has
    # written, and says "database is locked" at once.
    end_reads(session)
    ok = verify_password(
        user.password_hash if user else _DUMMY_HASH, password[:PASSWORD_MAX_LENGTH]
    )
    if user is None or not ok:
        write(session, lambda s: _record_failure(s, name, address))
        raise SignInError()
    user_id = user.id
    new_hash = hash_password(password) if _hasher.check_needs_rehash(user.password_hash) else None

    def succeed(s: Session) -> None:
        s.execute(
            delete(LoginAttempt).where(
                LoginAttempt.username == name, LoginAttempt.succeeded.is_(False)
            )
        )
        if new_hash is not None:
            s.execute(update(User).where(User.id == user_id).values(password_hash=new_hash))

    write(session, succeed)
    return user


@dataclass(frozen=True, slots=True)
class NewLoginSession:
    """A sign-in just made: its row and the cookie value (never stored)."""

    row: LoginSession
    cookie: str


def start_login_session(session: Session, user: User) -> NewLoginSession:
    """Open a signed-in session for ``user`` and commit; return it with its cookie value."""
    cookie, csrf_token, user_id = new_secret(), new_secret(), user.id

    def work(s: Session) -> LoginSession:
        row = LoginSession(
            token_sha256=sha256_hex(cookie),
            user_id=user_id,
            organisation_id=None,
            csrf_token=csrf_token,
            expires_at=utc_now() + session_lifetime(),
        )
        s.add(row)
        s.execute(delete(LoginSession).where(LoginSession.expires_at < utc_now()))
        s.flush()
        return row

    return NewLoginSession(row=write(session, work), cookie=cookie)


def end_login_session(session: Session, row: LoginSession) -> None:
    """Sign out: delete the session row (the cookie stops working at once) and commit."""
    begin_write(session)
    session.delete(row)
    session.commit()


def choose_organisation(session: Session, row: LoginSession, organisation_id: int) -> None:
    """Make ``organisation_id`` the one a signed-in page acts in (a member's only)."""
    begin_write(session)
    member = session.scalar(
        select(Membership).where(
            Membership.user_id == row.user_id, Membership.organisation_id == organisation_id
        )
    )
    if member is None:
        raise NotFoundError("organisation", organisation_id)
    row.organisation_id = organisation_id
    session.commit()


def _refuse_a_second_first_account(session: Session) -> None:
    if user_count(session) > 0:
        raise ConflictError(
            "sign-up: this server has accounts already; ask an owner for one "
            "(tillpath users create)"
        )


def sign_up_first(session: Session, username: str, password: str, organisation: str) -> User:
    """Create the first account of an empty server (owner of ``organisation``).

    The organisation is the default one when the database was migrated with plans already in
    it; they then belong to this first owner. "No user yet" is checked again in the write
    transaction that adds the user, which concurrent sign-ups go through one at a time
    (:func:`app.db.serialise_writes`), so only one of them becomes the owner.

    Raises
    ------
    ConflictError
        If there is a user already: accounts then come from an owner (``tillpath users
        create``).
    """
    # Checked first without the lock, so that a server with accounts answers at once, whatever
    # the input, and spends no Argon2 on the request.
    _refuse_a_second_first_account(session)
    end_reads(session)
    name = check_username(username)
    password_hash = _hash_in_advance(password)
    begin_write(session)
    serialise_writes(session, FIRST_ACCOUNT_LOCK_KEY)
    _refuse_a_second_first_account(session)
    # No user at all (checked again above, under the lock): the hash made before it is needed.
    user = _user_named(session, name)
    return _store_user(session, name, user, password_hash, organisation=organisation, role="owner")
