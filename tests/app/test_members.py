"""An organisation's members: owners add, change and remove them; the last owner stays."""

from __future__ import annotations

import pytest
from fastapi import FastAPI
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app import members
from app.errors import ConflictError, status_for
from tests.app.conftest import Workspace
from tests.app.test_accounts import sign_in


def test_owners_manage_members_and_keep_an_owner(
    client: TestClient, app: FastAPI, workspace: Workspace
):
    made = client.post(
        "/api/members",
        json={"username": "newcomer", "role": "planner", "password": "a long password"},
    )
    assert made.status_code == 201 and made.json()["role"] == "planner"
    names = {m["username"]: m["role"] for m in client.get("/api/members").json()["items"]}
    assert names == {
        "newcomer": "planner",
        "owner": "owner",
        "planner": "planner",
        "viewer": "viewer",
    }
    newcomer, _csrf = sign_in(app, "newcomer", "a long password")
    assert newcomer.get("/api/plans").status_code == 200
    unknown = client.post("/api/members", json={"username": "ghost", "role": "viewer"})
    assert unknown.status_code == 422 and "give a password" in unknown.json()["detail"]

    owner_id = workspace.users["owner"].id
    last = client.patch(f"/api/members/{owner_id}", json={"role": "viewer"})
    assert last.status_code == 409 and "no owner left" in last.json()["detail"]
    assert client.delete(f"/api/members/{owner_id}").status_code == 409
    user_id = made.json()["user_id"]
    assert client.delete(f"/api/members/{user_id}").status_code == 204
    assert newcomer.get("/api/plans").status_code == 403  # belongs to no organisation now


def test_adding_a_member_that_conflicts_twice_is_a_409_on_the_username(
    session: Session, workspace: Workspace, monkeypatch: pytest.MonkeyPatch
):
    # A first conflict is retried (tests.app.test_accounts_concurrency); a second one is told.
    tries: list[str] = []

    def conflict(_session: Session, _org: int, name: str, *_rest: object) -> None:
        tries.append(name)
        raise IntegrityError("INSERT INTO users", {}, Exception("duplicate key"))

    monkeypatch.setattr(members, "_store_member", conflict)
    with pytest.raises(ConflictError, match="^username: the request conflicts") as refused:
        members.add_member(session, workspace.organisation_id, "newcomer", "viewer", "long enough")
    assert tries == ["newcomer", "newcomer"] and status_for(refused.value) == 409
    assert not session.in_transaction()
