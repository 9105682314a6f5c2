"""``POST /api/fields/import``: every field of a file into the registry, all or nothing."""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import shapely
from sqlalchemy import func, select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app.models import Field
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import gpkg_bytes

RWANDA = FIELDS_DIR / "rwanda_2021.geojson"


def stored_fields(session: Session) -> int:
    session.expire_all()
    return session.scalar(select(func.count()).select_from(Field)) or 0


def import_file(client: TestClient, name: str, data: bytes):  # type: ignore[no-untyped-def]
    return client.post("/api/fields/import", files={"file": (name, data)})


def test_thirty_fields_import_once_and_plan_from_the_registry(
    client: TestClient, session: Session
) -> None:
    before = stored_fields(session)
    response = import_file(client, "rwanda_2021.geojson", RWANDA.read_bytes())
    assert response.status_code == 201, response.text
    imported = response.json()
    ids = [f["properties"]["id"] for f in json.loads(RWANDA.read_text())["features"]]
    assert (imported["created"], imported["reused"]) == (30, 0)
    assert [f["name"] for f in imported["fields"]] == ids
    assert stored_fields(session) == before + 30
    again = import_file(client, "rwanda_2021.geojson", RWANDA.read_bytes()).json()
    assert (again["created"], again["reused"]) == (0, 30)
    assert [f["id"] for f in again["fields"]] == [f["id"] for f in imported["fields"]]
    assert stored_fields(session) == before + 30, "the same boundaries are reused, not copied"
    plan = client.post(
        "/api/plans", json={"field_id": imported["fields"][3]["id"], "interval_m": 4}
    )
    assert plan.status_code == 201 and plan.json()["name"] == "rwanda_2021-3"


def test_geopackage_in_web_mercator_imports_in_lonlat(client: TestClient, tmp_path: Path) -> None:
    collection = json.loads(RWANDA.read_text())
    polygons = [shapely.from_geojson(json.dumps(f["geometry"])) for f in collection["features"]]
    data = gpkg_bytes(tmp_path, polygons[:5], [f"parcel {i}" for i in range(5)], crs="EPSG:3857")
    response = import_file(client, "parcels.gpkg", data)
    assert response.status_code == 201, response.text
    first = shapely.from_geojson(json.dumps(response.json()["fields"][0]["boundary"]))
    assert first.hausdorff_distance(polygons[0]) < 1e-8


def test_one_bad_field_stores_nothing_and_is_named(client: TestClient, session: Session) -> None:
    collection = json.loads(RWANDA.read_text())
    bow_tie = [[30.37, -1.54], [30.371, -1.541], [30.371, -1.54], [30.37, -1.541], [30.37, -1.54]]
    collection["features"][7]["geometry"]["coordinates"] = [bow_tie]
    before = stored_fields(session)
    response = import_file(client, "rwanda.geojson", json.dumps(collection).encode())
    assert response.status_code == 422
    detail = response.json()["detail"]
    assert detail.startswith("rwanda.geojson: field 7 (rwanda_2021-7): ") and "nothing" in detail
    assert stored_fields(session) == before


def test_zip_bomb_is_refused_and_stores_nothing(client: TestClient, session: Session) -> None:
    bomb = io.BytesIO()
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("fields.shp", bytes(20_000_000))
    before = stored_fields(session)
    response = import_file(client, "fields.zip", bomb.getvalue())
    assert response.status_code == 422 and "zip bomb" in response.json()["detail"]
    assert stored_fields(session) == before
