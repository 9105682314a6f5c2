"""The field registry: ``/api/fields`` and plans that reference their field (product.md §12)."""

from __future__ import annotations

from typing import Any

from starlette.testclient import TestClient


def boundary_of(paper_geojson: dict[str, Any]) -> dict[str, Any]:
    return paper_geojson["features"][0]["geometry"]


def new_field(client: TestClient, paper_geojson: dict[str, Any], **extra: Any) -> dict[str, Any]:
    body = {"name": "Sawah Ketewel", "boundary": paper_geojson, **extra}
    response = client.post("/api/fields", json=body)
    assert response.status_code == 201, response.text
    assert response.headers["location"] == f"/api/fields/{response.json()['id']}"
    return dict(response.json())


def test_create_field_takes_gates_from_the_file_and_lists_it(
    client: TestClient, paper_geojson: dict[str, Any]
):
    field = new_field(client, paper_geojson, notes="gate by the inlet")
    assert field["boundary"]["type"] == "Polygon"
    assert field["start"] == [115.29797264, -8.62652248]  # the file's start Point
    assert field["finish"] is not None and field["notes"] == "gate by the inlet"
    listing = client.get("/api/fields").json()
    assert listing["total"] == 1 and listing["items"][0]["id"] == field["id"]
    assert client.get(f"/api/fields/{field['id']}").json()["plan_count"] == 0


def test_plan_from_a_field_uses_its_boundary_gates_and_name(
    client: TestClient, paper_geojson: dict[str, Any]
):
    field = new_field(client, paper_geojson)
    plan = client.post("/api/plans", json={"field_id": field["id"], "interval_m": 4})
    assert plan.status_code == 201, plan.text
    body = plan.json()
    assert body["field_id"] == field["id"] and body["name"] == "Sawah Ketewel"
    assert body["request"]["field"] == field["boundary"]
    assert body["request"]["start"] == field["start"]
    assert client.get(f"/api/fields/{field['id']}").json()["plan_count"] == 1
    listed = client.get(f"/api/plans?field_id={field['id']}").json()
    assert [p["id"] for p in listed["items"]] == [body["id"]]


def test_drawn_boundary_creates_a_field_once_and_reuses_it(
    client: TestClient, paper_body: dict[str, Any]
):
    first = client.post("/api/plans", json=paper_body).json()
    second = client.post("/api/plans", json={**paper_body, "interval_m": 3}).json()
    assert first["field_id"] is not None and first["field_id"] == second["field_id"]
    fields = client.get("/api/fields").json()
    assert fields["total"] == 1
    assert fields["items"][0]["name"] == "Sawah Ketewel"
    assert fields["items"][0]["plan_count"] == 2
    # A preview stores nothing, not even a field.
    client.post("/api/plans/preview", json={**paper_body, "interval_m": 5})
    assert client.get("/api/fields").json()["total"] == 1


def test_field_and_field_id_together_or_neither_is_422(
    client: TestClient, paper_body: dict[str, Any], paper_geojson: dict[str, Any]
):
    field = new_field(client, paper_geojson)
    both = client.post("/api/plans", json={**paper_body, "field_id": field["id"]})
    assert both.status_code == 422 and both.json()["detail"].startswith("field_id:")
    neither = client.post("/api/plans", json={"interval_m": 4})
    assert neither.status_code == 422 and neither.json()["detail"].startswith("field:")
    unknown = client.post("/api/plans", json={"field_id": 999999, "interval_m": 4})
    assert unknown.status_code == 404 and unknown.json()["detail"] == "field 999999 not found"


def test_patch_changes_only_what_is_given(client: TestClient, paper_geojson: dict[str, Any]):
    field = new_field(client, paper_geojson)
    changed = client.patch(f"/api/fields/{field['id']}", json={"name": "North", "finish": None})
    assert changed.status_code == 200
    body = changed.json()
    assert body["name"] == "North" and body["finish"] is None
    assert body["start"] == field["start"] and body["boundary"] == field["boundary"]
    assert body["updated_at"] >= field["updated_at"]


def test_bad_boundary_is_422_naming_it(client: TestClient):
    bow_tie = {"type": "Polygon", "coordinates": [[[0, 0], [1, 1], [1, 0], [0, 1], [0, 0]]]}
    for boundary in (bow_tie, {"type": "Point", "coordinates": [0, 0]}, {}):
        response = client.post("/api/fields", json={"name": "x", "boundary": boundary})
        assert response.status_code == 422, response.text
        assert response.json()["detail"].startswith(("field", "boundary"))
    assert client.get("/api/fields").json()["total"] == 0
    nameless = client.post("/api/fields", json={"name": "", "boundary": bow_tie})
    assert nameless.status_code == 422 and nameless.json()["detail"].startswith("name:")


def test_delete_asks_what_happens_to_the_plans(client: TestClient, paper_body: dict[str, Any]):
    plan = client.post("/api/plans", json=paper_body).json()
    field_id = plan["field_id"]
    unasked = client.delete(f"/api/fields/{field_id}")
    assert unasked.status_code == 422 and unasked.json()["detail"].startswith("plans:")
    assert client.delete(f"/api/fields/{field_id}?plans=keep").status_code == 204
    kept = client.get(f"/api/plans/{plan['id']}")
    assert kept.status_code == 200 and kept.json()["field_id"] is None
    assert kept.json()["request"]["field"] == plan["request"]["field"]  # its own copy
    assert client.get(f"/api/fields/{field_id}").status_code == 404


def test_delete_with_plans_deletes_them_and_their_runs(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = client.post("/api/plans", json=paper_body).json()
    run = client.post(f"/api/plans/{plan['id']}/runs", json={}).json()
    other = client.post(
        "/api/plans",
        json={
            **paper_body,
            "field": {
                "type": "Polygon",
                "coordinates": [
                    [[115.3, -8.6], [115.3003, -8.6], [115.3003, -8.6003], [115.3, -8.6]]
                ],
            },
        },
    ).json()
    assert client.delete(f"/api/fields/{plan['field_id']}?plans=delete").status_code == 204
    assert client.get(f"/api/plans/{plan['id']}").status_code == 404
    assert client.get(f"/api/runs/{run['id']}").status_code == 404
    assert client.get(f"/api/plans/{other['id']}").status_code == 200  # another field's


def test_another_organisation_sees_none_of_the_fields(
    client: TestClient, other_client: TestClient, paper_geojson: dict[str, Any]
):
    field = new_field(client, paper_geojson)
    assert other_client.get("/api/fields").json() == {"items": [], "total": 0}
    for method in ("GET", "PATCH", "DELETE"):
        url = f"/api/fields/{field['id']}" + ("?plans=delete" if method == "DELETE" else "")
        kwargs: dict[str, Any] = {"json": {"name": "mine"}} if method == "PATCH" else {}
        response = other_client.request(method, url, **kwargs)
        assert response.status_code == 404, (method, response.text)
    plan = other_client.post("/api/plans", json={"field_id": field["id"], "interval_m": 4})
    assert plan.status_code == 404
    assert client.get(f"/api/fields/{field['id']}").json()["name"] == "Sawah Ketewel"


def test_names_with_nul_are_422_not_a_database_error(
    client: TestClient, paper_body: dict[str, Any], paper_geojson: dict[str, Any]
):
    # Found by schemathesis on PostgreSQL, whose text cannot hold NUL.
    nul = "a\x00b"
    answers = [
        client.post("/api/fields", json={"name": nul, "boundary": paper_geojson}),
        client.post("/api/fields", json={"name": "ok", "boundary": paper_geojson, "notes": nul}),
        client.post("/api/plans", json={**paper_body, "name": nul}),
        client.post("/api/tokens", json={"name": nul}),
        client.post("/api/auth/login", json={"username": nul, "password": "x"}),
    ]
    assert [a.status_code for a in answers] == [422, 422, 422, 422, 401]
    assert answers[0].json()["detail"] == "name: must not contain NUL characters"
    plan = client.post("/api/plans", json=paper_body).json()
    run = client.post(f"/api/plans/{plan['id']}/runs", data={"name": nul})
    assert run.status_code == 422 and run.json()["detail"].startswith("name:")
