"""The access matrix: every route × every kind of caller, on SQLite and PostgreSQL.

The routes come from the app itself (``create_app().routes``), so a route added without a row
in :data:`RULES` fails ``test_route_access``. Each row says which access rule the route
declares (it must match what the route's dependencies say), how to call it for organisation
``default``'s objects, and what an allowed call answers. The expected status of every other
caller follows from the rule:

- no credentials: 401 (public routes: the allowed answer);
- a device token: 403 except on the ``fixes`` routes (open a live run, post fixes);
- a role weaker than the rule's: 403;
- another organisation's owner: 404 for anything of ``default`` (as if it did not exist), the
  allowed answer for collections, which must then hold nothing of ``default``.

Nothing of ``default`` (its plan's, field's and run's names, its counts) may appear in any
answer to a caller outside it.
"""

from __future__ import annotations

import datetime as dt
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import pytest
from fastapi.routing import iter_route_contexts
from sqlalchemy.orm import Session
from starlette.routing import Mount
from starlette.testclient import TestClient

from app import services
from app.auth import Access, declared_rules
from app.jobs import store
from app.jobs.simulations import simulation_params
from app.main import create_app
from app.models import Plan
from app.schemas import SimulationCreate
from tests.app.conftest import TEST_PASSWORD, ClientFactory, Workspace

CALLERS: tuple[str | None, ...] = (None, "device", "viewer", "planner", "owner", "other")
ROLE_RANK = {"viewer": 0, "planner": 1, "owner": 2}

SECRET_PLAN = "ALPHA-SECRET-PLAN"
SECRET_FIELD = "ALPHA-SECRET-FIELD"
SECRET_RUN = "ALPHA-SECRET-RUN"
SECRETS = (SECRET_PLAN, SECRET_FIELD, SECRET_RUN)


@dataclass
class Objects:
    """Organisation ``default``'s objects, and how to make fresh ones for destructive calls."""

    owner: TestClient
    body: dict[str, Any]
    workspace: Workspace
    session: Session
    field_id: int = 0
    plan_id: int = 0
    simulation_id: int = 0
    run_id: int = 0
    made_members: list[str] = field(default_factory=list)
    job_id: int = 0

    def new_job(self) -> int:
        """A queued job of ``default`` (this app runs no job engine: it stays queued)."""
        owner = self.workspace.users["owner"]
        access = Access(self.workspace.organisation_id, "owner", owner.id, "token")
        params = simulation_params(self.plan_id, SimulationCreate(), dt.date(2026, 12, 1))
        return store.create_job(self.session, access, "simulation", params).id

    def new_field(self) -> int:
        response = self.owner.post(
            "/api/fields",
            json={"name": SECRET_FIELD, "boundary": self.body["field"], "notes": "north gate"},
        )
        assert response.status_code == 201, response.text
        return int(response.json()["id"])

    def new_plan(self) -> int:
        response = self.owner.post("/api/plans", json={**self.body, "field": None, **self._on()})
        assert response.status_code == 201, response.text
        return int(response.json()["id"])

    def _on(self) -> dict[str, Any]:
        return {"field_id": self.field_id, "name": SECRET_PLAN}

    def new_member(self) -> int:
        username = f"member{len(self.made_members)}"
        response = self.owner.post(
            "/api/members",
            json={"username": username, "role": "viewer", "password": "a long password"},
        )
        assert response.status_code == 201, response.text
        self.made_members.append(username)
        return int(response.json()["user_id"])

    def new_token(self) -> int:
        response = self.owner.post("/api/tokens", json={"name": "to revoke"})
        assert response.status_code == 201, response.text
        return int(response.json()["id"])


Call = tuple[str, str, dict[str, Any]]


@dataclass(frozen=True)
class Rule:
    """How a route is guarded, called and answered.

    Attributes
    ----------
    needs : str
        ``public``, ``user``, ``viewer``, ``planner``, ``owner`` or ``fixes``.
    call : callable
        ``Objects -> (method, url, request kwargs)``; called once per caller, so a destructive
        call makes its own object.
    ok : int
        The status of an allowed call.
    item : bool
        The URL names an object of ``default`` (another organisation gets 404).
    overrides : dict
        Expected status per caller where the rule's default does not hold.
    """

    needs: str
    call: Callable[[Objects], Call]
    ok: int = 200
    item: bool = False
    overrides: dict[str | None, int] = field(default_factory=dict)


def get(url: str) -> Callable[[Objects], Call]:
    return lambda o: ("GET", url.format(o=o), {})


FIX_BATCH = [
    {"t": "2026-11-22T03:14:15Z", "lat": -8.62652, "lon": 115.29797},
    {"t": "2026-11-22T03:14:16Z", "lat": -8.62651, "lon": 115.29798},
]

RULES: dict[tuple[str, str], Rule] = {
    # Pages and the API description: public.
    ("GET", "/"): Rule("public", get("/")),
    ("GET", "/docs"): Rule("public", get("/docs")),
    ("GET", "/openapi.json"): Rule("public", get("/openapi.json")),
    ("GET", "/api/health"): Rule("public", get("/api/health")),
    # The page's translations, manifest and service worker (issue 13): public, like the page.
    ("GET", "/i18n/{lang}.json"): Rule("public", get("/i18n/id.json")),
    ("GET", "/manifest.webmanifest"): Rule("public", get("/manifest.webmanifest")),
    ("GET", "/sw.js"): Rule("public", get("/sw.js")),
    # Accounts.
    ("GET", "/api/auth/setup"): Rule("public", get("/api/auth/setup")),
    ("POST", "/api/auth/signup"): Rule(
        "public",
        lambda o: ("POST", "/api/auth/signup", {"json": {"username": "x", "password": "p" * 8}}),
        ok=409,  # the server has accounts already
    ),
    ("POST", "/api/auth/login"): Rule(
        "public",
        lambda o: (
            "POST",
            "/api/auth/login",
            {"json": {"username": "viewer", "password": TEST_PASSWORD}},
        ),
    ),
    ("POST", "/api/auth/logout"): Rule("user", lambda o: ("POST", "/api/auth/logout", {}), ok=204),
    ("GET", "/api/me"): Rule("user", get("/api/me")),
    ("PUT", "/api/me/organisation"): Rule(
        "user",
        lambda o: (
            "PUT",
            "/api/me/organisation",
            {"json": {"organisation_id": o.workspace.organisation_id}},
        ),
        ok=409,  # a token chooses its organisation with X-Organisation, not a session setting
    ),
    ("GET", "/api/tokens"): Rule("user", get("/api/tokens")),
    ("POST", "/api/tokens"): Rule(
        "user", lambda o: ("POST", "/api/tokens", {"json": {"name": "script"}}), ok=201
    ),
    ("DELETE", "/api/tokens/{token_id}"): Rule(
        "user",
        lambda o: ("DELETE", f"/api/tokens/{o.new_token()}", {}),
        ok=204,
        # Only the token's user (or an owner, for device tokens) sees it.
        overrides={"viewer": 404, "planner": 404, "other": 404},
    ),
    # Members: owners only.
    ("GET", "/api/members"): Rule("owner", get("/api/members")),
    ("POST", "/api/members"): Rule(
        "owner",
        lambda o: ("POST", "/api/members", {"json": {"username": "viewer", "role": "viewer"}}),
        ok=201,
        # The other organisation's owner adds the user to their own organisation: allowed.
    ),
    ("PATCH", "/api/members/{user_id}"): Rule(
        "owner",
        lambda o: (
            "PATCH",
            f"/api/members/{o.workspace.users['viewer'].id}",
            {"json": {"role": "viewer"}},
        ),
        item=True,
    ),
    ("DELETE", "/api/members/{user_id}"): Rule(
        "owner",
        lambda o: ("DELETE", f"/api/members/{o.new_member()}", {}),
        ok=204,
        item=True,
    ),
    # The field registry.
    ("GET", "/api/fields"): Rule("viewer", get("/api/fields")),
    # Vehicle presets (issue 9): figures only, for any member.
    ("GET", "/api/vehicles"): Rule("viewer", get("/api/vehicles")),
    ("POST", "/api/fields"): Rule(
        "planner",
        lambda o: (
            "POST",
            "/api/fields",
            {"json": {"name": "new field", "boundary": o.body["field"]}},
        ),
        ok=201,
    ),
    ("GET", "/api/fields/{field_id}"): Rule("viewer", get("/api/fields/{o.field_id}"), item=True),
    ("PATCH", "/api/fields/{field_id}"): Rule(
        "planner",
        lambda o: ("PATCH", f"/api/fields/{o.field_id}", {"json": {"notes": "by the river"}}),
        item=True,
    ),
    ("DELETE", "/api/fields/{field_id}"): Rule(
        "planner",
        lambda o: ("DELETE", f"/api/fields/{o.new_field()}?plans=keep", {}),
        ok=204,
        item=True,
    ),
    # Plans.
    ("POST", "/api/plans/preview"): Rule(
        "viewer", lambda o: ("POST", "/api/plans/preview", {"json": o.body})
    ),
    ("POST", "/api/plans"): Rule(
        "planner", lambda o: ("POST", "/api/plans", {"json": o.body}), ok=201
    ),
    ("GET", "/api/plans"): Rule("viewer", get("/api/plans")),
    ("GET", "/api/plans/{plan_id}"): Rule("viewer", get("/api/plans/{o.plan_id}"), item=True),
    ("DELETE", "/api/plans/{plan_id}"): Rule(
        "planner", lambda o: ("DELETE", f"/api/plans/{o.new_plan()}", {}), ok=204, item=True
    ),
    ("GET", "/api/plans/{plan_id}/export/{format}"): Rule(
        "viewer", get("/api/plans/{o.plan_id}/export/gpx"), item=True
    ),
    # Simulations: background jobs. This app runs on in-memory SQLite, which worker processes
    # cannot open, so it has no job engine: an allowed call gets as far as the engine (503).
    # tests/app/test_jobs_api.py runs them on a real cluster (202).
    ("POST", "/api/plans/{plan_id}/simulations"): Rule(
        "planner",
        lambda o: ("POST", f"/api/plans/{o.plan_id}/simulations", {"json": {"seed": 1}}),
        ok=503,
        item=True,
    ),
    ("GET", "/api/jobs/{job_id}"): Rule("viewer", get("/api/jobs/{o.job_id}"), item=True),
    ("DELETE", "/api/jobs/{job_id}"): Rule(
        "planner", lambda o: ("DELETE", f"/api/jobs/{o.new_job()}", {}), item=True
    ),
    ("GET", "/api/simulations/{simulation_id}"): Rule(
        "viewer", get("/api/simulations/{o.simulation_id}"), item=True
    ),
    ("GET", "/api/simulations/{simulation_id}/export/gpx"): Rule(
        "viewer", get("/api/simulations/{o.simulation_id}/export/gpx"), item=True
    ),
    # Runs: a device token may open a live run and post fixes.
    ("POST", "/api/plans/{plan_id}/runs"): Rule(
        "fixes", lambda o: ("POST", f"/api/plans/{o.plan_id}/runs", {}), ok=201, item=True
    ),
    ("GET", "/api/plans/{plan_id}/simulations"): Rule(
        "viewer", get("/api/plans/{o.plan_id}/simulations"), item=True
    ),
    ("GET", "/api/plans/{plan_id}/runs"): Rule(
        "viewer", get("/api/plans/{o.plan_id}/runs"), item=True
    ),
    ("GET", "/api/runs/{run_id}"): Rule("viewer", get("/api/runs/{o.run_id}"), item=True),
    ("POST", "/api/runs/{run_id}/fixes"): Rule(
        "fixes", lambda o: ("POST", f"/api/runs/{o.run_id}/fixes", {"json": FIX_BATCH}), item=True
    ),
    ("POST", "/api/runs/{run_id}/follow-up"): Rule(
        "planner",
        lambda o: ("POST", f"/api/runs/{o.run_id}/follow-up", {}),
        ok=201,  # two fixes leave most of the field to plan
        item=True,
    ),
    ("GET", "/api/runs/{run_id}/export/gpx"): Rule(
        "viewer", get("/api/runs/{o.run_id}/export/gpx"), item=True
    ),
    # Field files and KML exports (issue 12).
    ("POST", "/api/fields/parse"): Rule(
        "viewer",
        lambda o: (
            "POST",
            "/api/fields/parse",
            {"files": {"file": ("field.geojson", json.dumps(o.body["field"]).encode())}},
        ),
    ),
    ("POST", "/api/fields/import"): Rule(
        "planner",
        lambda o: (
            "POST",
            "/api/fields/import",
            {"files": {"file": ("field.geojson", json.dumps(o.body["field"]).encode())}},
        ),
        ok=201,
    ),
    ("GET", "/api/simulations/{simulation_id}/export/kml"): Rule(
        "viewer", get("/api/simulations/{o.simulation_id}/export/kml"), item=True
    ),
    ("GET", "/api/runs/{run_id}/export/kml"): Rule(
        "viewer", get("/api/runs/{o.run_id}/export/kml"), item=True
    ),
}


def app_routes() -> list[tuple[str, str]]:
    """Every (method, path) the app serves, mounts of static files aside."""
    found = []
    for context in iter_route_contexts(create_app().routes):
        if isinstance(context.original_route, Mount):
            continue
        for method in sorted(set(context.methods or ()) - {"HEAD"}):
            found.append((method, str(context.path)))
    return found


ROUTES = app_routes()


def expected_status(rule: Rule, caller: str | None) -> int:
    """The status ``caller`` must get from a route guarded by ``rule``."""
    if caller in rule.overrides:
        return rule.overrides[caller]
    if rule.needs == "public":
        return rule.ok
    if caller is None:
        return 401
    if rule.needs == "user":
        return 403 if caller == "device" else rule.ok
    if rule.needs == "fixes":
        if caller == "viewer":
            return 403
        if caller == "other" and rule.item:
            return 404
        return rule.ok
    if caller == "device":
        return 403
    role = "owner" if caller == "other" else caller
    if ROLE_RANK[role] < ROLE_RANK[rule.needs]:
        return 403
    if caller == "other" and rule.item:
        return 404
    return rule.ok


@pytest.fixture
def objects(
    client_as: ClientFactory, workspace: Workspace, paper_body: dict[str, Any], session: Session
) -> Objects:
    owner = client_as("owner")
    made = Objects(owner=owner, body=paper_body, workspace=workspace, session=session)
    made.field_id = made.new_field()
    made.plan_id = made.new_plan()
    # A stored simulation, as a simulation job's worker stores it.
    simulation = services.simulate_plan(session.get(Plan, made.plan_id), SimulationCreate())
    session.add(simulation)
    session.commit()
    made.simulation_id = simulation.id
    made.job_id = made.new_job()
    run = owner.post(f"/api/plans/{made.plan_id}/runs", data={"name": SECRET_RUN})
    assert run.status_code == 201, run.text
    made.run_id = run.json()["id"]
    fixes = owner.post(f"/api/runs/{made.run_id}/fixes", json=FIX_BATCH)
    assert fixes.status_code == 200, fixes.text
    return made


def assert_nothing_leaks(caller: str | None, response: Any, where: str) -> None:
    text = response.text
    for secret in SECRETS:
        assert secret not in text, f"{where}: {caller} sees {secret!r}"
    if "json" not in response.headers.get("content-type", ""):
        return
    try:
        data = json.loads(text)
    except ValueError:
        return
    if isinstance(data, dict) and "total" in data and caller == "other":
        assert data["total"] == 0 and data["items"] == [], f"{where}: other sees {data}"


def test_matrix_covers_every_route():
    """Every route has a row, and every row a route (no stale rows)."""
    assert set(RULES) == set(ROUTES), {
        "routes without a rule": sorted(set(ROUTES) - set(RULES)),
        "rules without a route": sorted(set(RULES) - set(ROUTES)),
    }


@pytest.mark.parametrize("route", ROUTES, ids=[f"{m} {p}" for m, p in ROUTES])
def test_route_access(route: tuple[str, str], objects: Objects, client_as: ClientFactory) -> None:
    rule = RULES.get(route)
    assert rule is not None, f"{route}: no access rule in the matrix; declare one in RULES"
    app_route = next(
        c.original_route
        for c in iter_route_contexts(objects.owner.app.routes)  # type: ignore[attr-defined]
        if str(c.path) == route[1] and route[0] in (c.methods or ())
    )
    if route[1].startswith("/api/"):
        assert declared_rules(app_route) == {rule.needs}, (
            f"{route}: the route declares {declared_rules(app_route)}, the matrix {rule.needs}"
        )
    for caller in CALLERS:
        method, url, kwargs = rule.call(objects)
        response = client_as(caller).request(method, url, **kwargs)
        expected = expected_status(rule, caller)
        where = f"{method} {url} as {caller or 'nobody'}"
        assert response.status_code == expected, f"{where}: {response.status_code} {response.text}"
        if caller == "other" or expected in (401, 403, 404):
            assert_nothing_leaks(caller, response, where)
        if expected == 403:
            detail = response.json()["detail"]
            assert "role" in detail or "device token" in detail or "CSRF" in detail, detail
