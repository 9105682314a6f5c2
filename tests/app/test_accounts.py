"""Accounts, sessions, CSRF, tokens, throttling and organisations (product.md §12)."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import pytest
from fastapi import FastAPI
from sqlalchemy import delete, func, select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app import accounts, members
from app.auth_models import LoginAttempt, Membership, Organisation, User
from app.errors import AccountError
from app.models import Plan
from tests.app.conftest import TEST_PASSWORD, ClientFactory, Workspace, add_user


def sign_in(app: FastAPI, username: str, password: str = TEST_PASSWORD) -> tuple[TestClient, str]:
    """A browser-like client signed in with the session cookie; returns it and the CSRF token."""
    browser = TestClient(app)
    response = browser.post("/api/auth/login", json={"username": username, "password": password})
    assert response.status_code == 200, response.text
    return browser, response.json()["csrf_token"]


def plan_count(session: Session) -> int:
    return session.scalar(select(func.count()).select_from(Plan)) or 0


def test_login_sets_an_httponly_samesite_cookie_and_answers_who(app: FastAPI, workspace: Workspace):
    browser = TestClient(app)
    response = browser.post(
        "/api/auth/login", json={"username": "planner", "password": TEST_PASSWORD}
    )
    assert response.status_code == 200
    cookie = response.headers["set-cookie"]
    assert cookie.startswith("tillpath_session=")
    assert "HttpOnly" in cookie and "SameSite=lax" in cookie and "Path=/" in cookie
    me = response.json()
    assert me["user"]["username"] == "planner"
    assert me["organisation"] == {
        "id": workspace.organisation_id,
        "name": "default",
        "role": "planner",
    }
    assert me["via"] == "session" and len(me["csrf_token"]) >= 32
    again = browser.get("/api/me").json()
    assert again["csrf_token"] == me["csrf_token"]


def test_login_says_nothing_about_which_of_name_or_password_was_wrong(
    app: FastAPI, workspace: Workspace
):
    browser = TestClient(app)
    wrong_password = browser.post("/api/auth/login", json={"username": "owner", "password": "nope"})
    unknown_user = browser.post(
        "/api/auth/login", json={"username": "nobody", "password": TEST_PASSWORD}
    )
    assert wrong_password.status_code == unknown_user.status_code == 401
    assert (
        wrong_password.json() == unknown_user.json() == {"detail": "username or password is wrong"}
    )
    assert "set-cookie" not in wrong_password.headers


@pytest.mark.slow
def test_twenty_wrong_passwords_throttle_the_account_only(app: FastAPI, workspace: Workspace):
    browser = TestClient(app)
    for _ in range(accounts.ACCOUNT_FAILURE_LIMIT):
        bad = browser.post("/api/auth/login", json={"username": "owner", "password": "guess"})
        assert bad.status_code == 401
    # Now even the right password is refused for a while, with Retry-After.
    throttled = browser.post(
        "/api/auth/login", json={"username": "owner", "password": TEST_PASSWORD}
    )
    assert throttled.status_code == 429
    assert "too many failed sign-ins for this account" in throttled.json()["detail"]
    assert 0 < int(throttled.headers["retry-after"]) <= 15 * 60 + 1
    # Another account signs in as usual from the same address.
    other = browser.post("/api/auth/login", json={"username": "viewer", "password": TEST_PASSWORD})
    assert other.status_code == 200


def test_failures_from_one_address_throttle_it(
    app: FastAPI, workspace: Workspace, session: Session
):
    # A hundred failures of as many names from the test client's address (recorded as a
    # failed login records them; hashing a hundred passwords would take a minute here).
    browser = TestClient(app)
    assert (
        browser.post("/api/auth/login", json={"username": "u", "password": "x"}).status_code == 401
    )
    address = session.scalars(select(LoginAttempt.address)).one()
    session.add_all(
        LoginAttempt(username=f"u{i}", address=address)
        for i in range(accounts.ADDRESS_FAILURE_LIMIT - 1)
    )
    session.commit()
    throttled = browser.post(
        "/api/auth/login", json={"username": "viewer", "password": TEST_PASSWORD}
    )
    assert throttled.status_code == 429
    assert "this address" in throttled.json()["detail"]


def test_cookie_writes_need_the_csrf_token(
    app: FastAPI, workspace: Workspace, session: Session, paper_body: dict[str, Any]
):
    browser, csrf = sign_in(app, "planner")
    before = plan_count(session)
    missing = browser.post("/api/plans", json=paper_body)
    wrong = browser.post("/api/plans", json=paper_body, headers={"X-CSRF-Token": "x" * 43})
    assert missing.status_code == wrong.status_code == 403
    assert "X-CSRF-Token" in missing.json()["detail"]
    assert plan_count(session) == before
    made = browser.post("/api/plans", json=paper_body, headers={"X-CSRF-Token": csrf})
    assert made.status_code == 201
    assert browser.get(f"/api/plans/{made.json()['id']}").status_code == 200  # reads need none


def test_cross_site_form_post_with_the_session_cookie_is_refused(
    app: FastAPI, workspace: Workspace, session: Session
):
    browser, _csrf = sign_in(app, "owner")
    plan = browser.get("/api/plans").json()
    before = plan_count(session)
    # What a page on another site can make a browser send: a form post, cookie attached.
    for method, url, data in [
        ("POST", "/api/plans", {"field": "x", "interval_m": "4"}),
        ("POST", "/api/tokens", {"name": "stolen"}),
        ("POST", "/api/auth/logout", {}),
    ]:
        response = browser.request(
            method,
            url,
            data=data,
            headers={"Origin": "https://evil.example", "Referer": "https://evil.example/"},
        )
        assert response.status_code == 403, (url, response.text)
    assert plan_count(session) == before
    assert browser.get("/api/plans").json() == plan
    assert browser.get("/api/me").status_code == 200  # still signed in: logout was refused


def test_logout_ends_the_session_at_once(app: FastAPI, workspace: Workspace):
    browser, csrf = sign_in(app, "viewer")
    cookie = browser.cookies.get("tillpath_session")
    assert browser.post("/api/auth/logout", headers={"X-CSRF-Token": csrf}).status_code == 204
    replay = TestClient(app, cookies={"tillpath_session": cookie or ""})
    assert replay.get("/api/me").status_code == 401


def test_personal_token_is_shown_once_stored_hashed_and_revocable(
    client: TestClient, app: FastAPI, session: Session
):
    made = client.post("/api/tokens", json={"name": "script"})
    assert made.status_code == 201
    token = made.json()["token"]
    assert token.startswith("tp_") and len(token) >= 40
    listed = client.get("/api/tokens").json()["items"]
    assert all("token" not in item for item in listed)
    assert token not in str(listed)
    stored = session.execute(select(accounts.ApiToken.token_sha256)).scalars().all()
    assert token not in stored and accounts.sha256_hex(token) in stored

    script = TestClient(app, headers={"Authorization": f"Bearer {token}"})
    assert script.get("/api/plans").status_code == 200
    assert client.delete(f"/api/tokens/{made.json()['id']}").status_code == 204
    assert script.get("/api/plans").status_code == 401  # at once, not after a cache expires
    revoked = next(t for t in client.get("/api/tokens").json()["items"] if t["name"] == "script")
    assert revoked["revoked_at"] is not None and revoked["last_used_at"] is not None


def test_bad_or_malformed_credentials_are_401(app: FastAPI, workspace: Workspace):
    for headers in (
        {"Authorization": "Bearer tp_not-a-token"},
        {"Authorization": "Basic dXNlcjpwYXNz"},
        {"Cookie": "tillpath_session=forged"},
    ):
        response = TestClient(app, headers=headers).get("/api/plans")
        assert response.status_code == 401, headers
        assert response.headers["www-authenticate"] == "Bearer"


def test_device_token_posts_fixes_and_nothing_else(
    client: TestClient, device_client: TestClient, paper_body: dict[str, Any]
):
    plan = client.post("/api/plans", json=paper_body).json()
    opened = device_client.post(f"/api/plans/{plan['id']}/runs", json={})
    assert opened.status_code == 201  # the logger may open a live run
    run_id = opened.json()["id"]
    fixes = [{"t": 1795318455 + i, "lat": -8.62652, "lon": 115.29797} for i in range(3)]
    posted = device_client.post(f"/api/runs/{run_id}/fixes", json=fixes)
    assert posted.status_code == 200 and posted.json()["stored"] == 3
    for method, url in [
        ("GET", f"/api/plans/{plan['id']}"),
        ("GET", "/api/plans"),
        ("DELETE", f"/api/plans/{plan['id']}"),
        ("GET", f"/api/runs/{run_id}"),
        ("GET", f"/api/runs/{run_id}/export/gpx"),
        ("GET", "/api/fields"),
        ("POST", "/api/tokens"),
        ("GET", "/api/me"),
    ]:
        response = device_client.request(method, url)
        assert response.status_code == 403, (method, url, response.text)
        assert "device token" in response.json()["detail"]
    upload = device_client.post(
        f"/api/plans/{plan['id']}/runs", files={"file": ("t.csv", b"time,lat,lon\n", "text/csv")}
    )
    assert upload.status_code == 403
    assert client.get(f"/api/plans/{plan['id']}").status_code == 200  # nothing was deleted


def test_device_token_of_another_organisation_sees_nothing(
    client: TestClient,
    client_as: ClientFactory,
    session: Session,
    workspace: Workspace,
    paper_body: dict[str, Any],
):
    plan = client.post("/api/plans", json=paper_body).json()
    run = client.post(f"/api/plans/{plan['id']}/runs", json={}).json()
    other_device = accounts.create_token(
        session,
        workspace.users["other"],
        name="their tractor",
        device=True,
        organisation_id=workspace.other_organisation_id,
    ).token
    intruder = TestClient(client.app, headers={"Authorization": f"Bearer {other_device}"})
    fix = [{"t": 1795318455, "lat": -8.7, "lon": 115.3}]
    assert intruder.post(f"/api/runs/{run['id']}/fixes", json=fix).status_code == 404
    assert intruder.post(f"/api/plans/{plan['id']}/runs", json={}).status_code == 404
    assert client.get(f"/api/runs/{run['id']}").json()["fix_count"] == 0


def test_only_owners_make_device_tokens(planner_client: TestClient, client: TestClient):
    refused = planner_client.post("/api/tokens", json={"name": "t", "device": True})
    assert refused.status_code == 403 and "owner role" in refused.json()["detail"]
    made = client.post("/api/tokens", json={"name": "tractor 2", "device": True})
    assert made.status_code == 201 and made.json()["kind"] == "device"
    # The owner sees the organisation's device tokens, with when they were last used.
    listed = client.get("/api/tokens").json()["items"]
    assert any(t["name"] == "tractor 2" and t["kind"] == "device" for t in listed)


def test_first_account_sign_up_only_on_an_empty_server(app: FastAPI, session: Session):
    browser = TestClient(app)
    assert browser.get("/api/auth/setup").json() == {"needs_first_account": True}
    made = browser.post(
        "/api/auth/signup",
        json={"username": "first", "password": "a long password", "organisation": "Subak Ketewel"},
    )
    assert made.status_code == 201, made.text
    assert made.json()["organisation"]["role"] == "owner"
    assert browser.get("/api/me").json()["user"]["username"] == "first"
    second = TestClient(app).post(
        "/api/auth/signup", json={"username": "second", "password": "a long password"}
    )
    assert second.status_code == 409
    assert browser.get("/api/auth/setup").json() == {"needs_first_account": False}
    assert session.scalar(select(func.count()).select_from(User)) == 1


def test_sign_up_refuses_a_bad_name_or_short_password(app: FastAPI):
    browser = TestClient(app)
    bad_name = browser.post("/api/auth/signup", json={"username": "<b>", "password": "long enough"})
    assert bad_name.status_code == 422 and bad_name.json()["detail"].startswith("username:")
    short = browser.post("/api/auth/signup", json={"username": "ok", "password": "short"})
    assert short.status_code == 422 and short.json()["detail"].startswith("password:")


def test_a_member_of_two_organisations_switches_between_them(
    app: FastAPI, session: Session, workspace: Workspace, paper_body: dict[str, Any]
):
    add_user(
        session,
        "technician",
        {workspace.organisation_id: "planner", workspace.other_organisation_id: "viewer"},
    )
    token = accounts.create_token(
        session, session.scalars(select(User).where(User.username == "technician")).one(), name="t"
    ).token
    script = TestClient(app, headers={"Authorization": f"Bearer {token}"})
    made = script.post("/api/plans", json=paper_body)
    assert made.status_code == 201  # the first organisation by default
    other = {"X-Organisation": str(workspace.other_organisation_id)}
    assert script.get(f"/api/plans/{made.json()['id']}", headers=other).status_code == 404
    refused = script.post("/api/plans", json=paper_body, headers=other)
    assert refused.status_code == 403 and "planner role" in refused.json()["detail"]
    assert script.get("/api/plans", headers={"X-Organisation": "999999"}).status_code == 404
    assert script.get("/api/plans", headers={"X-Organisation": "x"}).status_code == 422

    browser, csrf = sign_in(app, "technician")
    switched = browser.put(
        "/api/me/organisation",
        json={"organisation_id": workspace.other_organisation_id},
        headers={"X-CSRF-Token": csrf},
    )
    assert switched.status_code == 200
    assert switched.json()["organisation"]["name"] == "other"
    assert browser.get("/api/plans").json()["total"] == 0
    assert len(switched.json()["organisations"]) == 2


def test_create_user_adds_membership_and_keeps_password(session: Session):
    user = accounts.create_user(session, "made", "first password", organisation="coop")
    again = accounts.create_user(session, "made", "ignored", organisation="farm", role="viewer")
    assert again.id == user.id
    assert accounts.verify_password(again.password_hash, "first password")
    assert again.password_hash.startswith("$argon2id$")
    roles = {
        o.name: m.role
        for m, o in session.execute(
            select(Membership, Organisation).join(Organisation).where(Membership.user_id == user.id)
        )
    }
    assert roles == {"coop": "owner", "farm": "viewer"}


def test_a_cross_site_form_cannot_sign_a_browser_in(app: FastAPI, workspace: Workspace):
    # Login CSRF: a form can send text/plain or urlencoded bodies, never application/json.
    browser = TestClient(app)
    body = json.dumps({"username": "owner", "password": TEST_PASSWORD})
    for content_type in ("text/plain", "application/x-www-form-urlencoded"):
        response = browser.post(
            "/api/auth/login", content=body, headers={"Content-Type": content_type}
        )
        assert response.status_code == 422, (content_type, response.text)
        assert "set-cookie" not in response.headers


def test_member_ids_beyond_32_bits_are_404(client: TestClient):
    # Found by schemathesis: such an id reached the database and failed there (500).
    huge = 1264658853214972534587392
    assert client.patch(f"/api/members/{huge}", json={"role": "viewer"}).status_code == 404
    assert client.delete(f"/api/members/{huge}").status_code == 404
    assert client.delete(f"/api/tokens/{huge}").status_code == 404


@pytest.fixture
def hashes(session: Session, monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The passwords :func:`app.accounts.hash_password` is called with, from now on.

    A spy, not a stand-in: the real hash is made. Each call also checks that no transaction
    of ``session`` is open, so that Argon2 never runs under SQLite's write lock.
    """
    calls: list[str] = []
    real = accounts.hash_password

    def spy(password: str) -> str:
        assert not session.in_transaction(), "Argon2 ran inside a transaction"
        calls.append(password)
        return real(password)

    monkeypatch.setattr(accounts, "hash_password", spy)
    return calls


def test_an_existing_user_added_with_a_password_costs_no_argon2_and_keeps_theirs(
    session: Session, workspace: Workspace, hashes: list[str]
):
    planner = workspace.users["planner"]
    user, member = members.add_member(
        session, workspace.other_organisation_id, "planner", "viewer", "a new long password"
    )
    again = accounts.create_user(session, "planner", "another long password", organisation="coop")
    assert user.id == again.id == planner.id and member.role == "viewer"
    assert hashes == []
    signed_in = accounts.authenticate_password(session, "planner", TEST_PASSWORD, "192.0.2.1")
    assert signed_in.id == planner.id
    for new in ("a new long password", "another long password"):
        assert not accounts.verify_password(again.password_hash, new)
    # A new user's password is hashed, once.
    members.add_member(session, workspace.organisation_id, "newcomer", "viewer", "long enough")
    assert hashes == ["long enough"]


def test_a_bad_password_refuses_a_new_user_and_is_ignored_for_an_existing_one(
    session: Session, workspace: Workspace, hashes: list[str]
):
    with pytest.raises(AccountError) as expected:
        accounts.check_password("short")
    for make in (
        lambda: accounts.create_user(session, "newcomer", "short", organisation="coop"),
        lambda: members.add_member(
            session, workspace.organisation_id, "newcomer", "viewer", "short"
        ),
    ):
        with pytest.raises(AccountError) as refused:
            make()
        assert str(refused.value) == str(expected.value)
        session.rollback()
        assert session.scalar(select(User).where(User.username == "newcomer")) is None
    _user, member = members.add_member(
        session, workspace.other_organisation_id, "planner", "viewer", "short"
    )
    assert member.role == "viewer"
    kept = accounts.create_user(session, "planner", "short", organisation="coop", role="viewer")
    assert accounts.verify_password(kept.password_hash, TEST_PASSWORD)
    assert hashes == []


def _between_read_and_write(
    monkeypatch: pytest.MonkeyPatch, change: Callable[[Session], None]
) -> None:
    """Make ``change`` (committed) happen after the user is first read, before the write."""
    real = accounts.begin_write
    pending = [change]

    def begin_write(session: Session) -> None:
        if pending:
            pending.pop()(session)
            session.commit()
        real(session)

    monkeypatch.setattr(accounts, "begin_write", begin_write)


def test_a_user_deleted_between_the_read_and_the_write_is_made_anew(
    session: Session, workspace: Workspace, hashes: list[str], monkeypatch: pytest.MonkeyPatch
):
    # Read as existing (no hash), gone in the write transaction: the password is hashed then,
    # outside it (the spy checks), and the user is made with it.
    _between_read_and_write(
        monkeypatch, lambda s: s.execute(delete(User).where(User.username == "planner"))
    )
    user, member = members.add_member(
        session, workspace.other_organisation_id, "planner", "viewer", "a new long password"
    )
    assert hashes == ["a new long password"] and member.role == "viewer"
    assert user.id != workspace.users["planner"].id
    assert accounts.verify_password(user.password_hash, "a new long password")


def test_a_user_made_between_the_read_and_the_write_keeps_their_password(
    session: Session, workspace: Workspace, hashes: list[str], monkeypatch: pytest.MonkeyPatch
):
    _between_read_and_write(
        monkeypatch, lambda s: add_user(s, "twin", {workspace.organisation_id: "planner"})
    )
    user = accounts.create_user(session, "twin", "a new long password", organisation="coop")
    assert hashes == ["a new long password"]  # made before the write, then not needed
    assert accounts.verify_password(user.password_hash, TEST_PASSWORD)
