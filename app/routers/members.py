"""``/api/members``: the owners of an organisation manage who belongs to it (product.md §12)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Response, status

from app import members
from app.auth import Owner
from app.auth_schemas import MemberCreate, MemberList, MemberRead, MemberUpdate
from app.db import SessionDep
from app.schemas import ErrorRead

router = APIRouter(prefix="/members", tags=["accounts"])

_ERRORS: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorRead, "description": "Not a member"},
    409: {
        "model": ErrorRead,
        "description": "No owner would be left, or a concurrent change conflicted",
    },
    422: {"model": ErrorRead, "description": "The input named in `detail` is wrong"},
}


def _read(user: Any, member: Any) -> MemberRead:
    return MemberRead(user_id=user.id, username=user.username, role=member.role)


@router.get("", response_model=MemberList)
def list_members(session: SessionDep, access: Owner) -> MemberList:
    """List the organisation's members and their roles."""
    rows = members.list_members(session, access.organisation_id)
    return MemberList(items=[_read(u, m) for u, m in rows])


@router.post("", response_model=MemberRead, status_code=status.HTTP_201_CREATED, responses=_ERRORS)
def add_member(body: MemberCreate, session: SessionDep, access: Owner) -> MemberRead:
    """Add a user with a role (a new user when `password` is given), or change their role."""
    user, member = members.add_member(
        session, access.organisation_id, body.username, body.role, body.password
    )
    return _read(user, member)


@router.patch("/{user_id}", response_model=MemberRead, responses=_ERRORS)
def change_member(
    user_id: int, body: MemberUpdate, session: SessionDep, access: Owner
) -> MemberRead:
    """Change a member's role (the last owner stays an owner)."""
    members.change_member_role(session, access.organisation_id, user_id, body.role)
    rows = members.list_members(session, access.organisation_id)
    return next(_read(u, m) for u, m in rows if u.id == user_id)


@router.delete(
    "/{user_id}", status_code=status.HTTP_204_NO_CONTENT, response_class=Response, responses=_ERRORS
)
def remove_member(user_id: int, session: SessionDep, access: Owner) -> None:
    """Take a member out of the organisation (their account stays)."""
    members.remove_member(session, access.organisation_id, user_id)
