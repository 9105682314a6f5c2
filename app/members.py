"""An organisation's members: owners add users with a role, change roles and remove them.

The last owner of an organisation stays an owner. Users themselves (names, passwords) are
:mod:`app.accounts`'s.
"""

from __future__ import annotations

from sqlalchemy import func, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from app.accounts import begin_user_write, check_role, check_username, new_user
from app.auth import MAX_ID
from app.auth_models import Membership, User
from app.db import begin_write
from app.errors import AccountError, ConflictError, NotFoundError


def list_members(session: Session, organisation_id: int) -> list[tuple[User, Membership]]:
    """Return the organisation's members with their memberships, by username."""
    rows = session.execute(
        select(User, Membership)
        .join(Membership, Membership.user_id == User.id)
        .where(Membership.organisation_id == organisation_id)
        .order_by(User.username)
    ).all()
    return [(u, m) for u, m in rows]


def _membership(session: Session, organisation_id: int, user_id: int) -> Membership:
    if not 1 <= user_id <= MAX_ID:  # not a 32-bit key: no such member (and no SQL error)
        raise NotFoundError("member", user_id)
    found = session.scalar(
        select(Membership).where(
            Membership.organisation_id == organisation_id, Membership.user_id == user_id
        )
    )
    if found is None:
        raise NotFoundError("member", user_id)
    return found


def _keep_an_owner(session: Session, membership: Membership) -> None:
    if membership.role != "owner":
        return
    owners = session.scalar(
        select(func.count())
        .select_from(Membership)
        .where(Membership.organisation_id == membership.organisation_id, Membership.role == "owner")
    )
    if (owners or 0) <= 1:
        raise ConflictError("role: the organisation would have no owner left; make another first")


def add_member(
    session: Session, organisation_id: int, username: str, role: str, password: str | None
) -> tuple[User, Membership]:
    """Give a user (made if ``password`` is given and none exists) a role in the organisation.

    The password is hashed only for a new user, before the write lock
    (:func:`app.accounts.create_user`). On PostgreSQL a concurrent request (a double-click, a
    client's retry, another owner) may add the same user or membership between this one's
    read and its write; the write is then rolled back and done once more, finding what the
    other made: the answer is the one the requests would get one after another (an existing
    user keeps their password).

    Raises
    ------
    AccountError
        For an unknown user without a password, or a bad name or password.
    ConflictError
        If the write still conflicts on its second try, or the organisation would have no
        owner left.
    """
    check_role(role)
    name = check_username(username)
    for _attempt in range(2):
        user, password_hash = begin_user_write(session, name, password)
        try:
            return _store_member(session, organisation_id, name, user, password_hash, role)
        except IntegrityError:
            session.rollback()
    # The wording of the database's own conflict (app.errors), so it is translated too.
    raise ConflictError(
        "username: the request conflicts with a change made at the same time; retry"
    )


def _store_member(
    session: Session,
    organisation_id: int,
    name: str,
    user: User | None,
    password_hash: str | AccountError | None,
    role: str,
) -> tuple[User, Membership]:
    """Do :func:`add_member`'s writes in the caller's write transaction; commit.

    ``user`` is the user called ``name`` as read in that transaction (None: add it). Raises
    IntegrityError if a concurrent transaction added the same user or membership.
    """
    if user is None:
        user = new_user(session, name, password_hash)
    member = session.scalar(
        select(Membership).where(
            Membership.organisation_id == organisation_id, Membership.user_id == user.id
        )
    )
    if member is None:
        member = Membership(user_id=user.id, organisation_id=organisation_id, role=role)
        session.add(member)
    else:
        if role != "owner":
            _keep_an_owner(session, member)
        member.role = role
    session.commit()
    return user, member


def change_member_role(session: Session, organisation_id: int, user_id: int, role: str) -> None:
    """Change a member's role; the last owner stays an owner."""
    begin_write(session)
    member = _membership(session, organisation_id, user_id)
    if role != "owner":
        _keep_an_owner(session, member)
    member.role = check_role(role)
    session.commit()


def remove_member(session: Session, organisation_id: int, user_id: int) -> None:
    """Take a user out of the organisation; the last owner stays."""
    begin_write(session)
    member = _membership(session, organisation_id, user_id)
    _keep_an_owner(session, member)
    session.delete(member)
    session.commit()
