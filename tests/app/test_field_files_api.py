"""``POST /api/fields/parse``: any import format in, every field out; hostile files are a 422."""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path
from typing import Any

import shapely
from starlette.testclient import TestClient

from app.dependencies import request_settings
from app.settings import Settings
from tests.conftest import FIELDS_DIR, PAPER_FIELD
from tests.planner.field_files import google_earth_kmz_bytes, shared_polygon
from tests.planner.test_io_safety import BILLION_LAUGHS


def parse(client: TestClient, name: str, data: bytes) -> Any:
    return client.post("/api/fields/parse", files={"file": (name, data)})


def test_a_thirty_field_file_answers_thirty_fields_with_id_name_and_area(
    client: TestClient,
) -> None:
    response = parse(
        client, "rwanda_2021.geojson", (FIELDS_DIR / "rwanda_2021.geojson").read_bytes()
    )
    assert response.status_code == 200, response.text
    features = response.json()["features"]
    assert len(features) == 30
    assert [f["properties"]["index"] for f in features] == list(range(30))
    assert features[3]["properties"]["id"] == "rwanda_2021-3"
    assert features[3]["properties"]["area_m2"] > 0


def test_paper_field_answers_the_field_and_its_start_and_finish(client: TestClient) -> None:
    response = parse(client, "paper.geojson", PAPER_FIELD.read_bytes())
    features = response.json()["features"]
    assert [f["geometry"]["type"] for f in features] == ["Polygon", "Point", "Point"]
    assert [f["properties"].get("role") for f in features[1:]] == ["start", "finish"]
    assert features[0]["properties"]["interval_m"] == 4.0


def test_a_google_earth_kmz_answers_its_field_and_plans(client: TestClient, tmp_path: Path) -> None:
    response = parse(client, "sawah.kmz", google_earth_kmz_bytes(tmp_path, shared_polygon("paper")))
    assert response.status_code == 200, response.text
    (field,) = response.json()["features"]
    plan = client.post("/api/plans/preview", json={"field": field, "interval_m": 4})
    original = client.post(
        "/api/plans/preview",
        json={"field": json.loads(shapely.to_geojson(shared_polygon("paper"))), "interval_m": 4},
    )
    assert plan.status_code == 200 and original.status_code == 200
    assert plan.json()["stats"]["line_count"] == original.json()["stats"]["line_count"]


def test_hostile_and_unreadable_files_are_a_422_naming_the_file(client: TestClient) -> None:
    bomb = io.BytesIO()
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("field.shp", bytes(20_000_000))
    for name, data, words in [
        ("bomb.zip", bomb.getvalue(), "zip bomb"),
        ("lol.kml", BILLION_LAUGHS, "DTD, entity declarations"),
        ("photo.jpg", b"\xff\xd8\xff\xe0\x00\x10JFIF\x00" + bytes(64), "binary data"),
        ("broken.geojson", b'{"type": ', "not valid JSON"),
    ]:
        response = parse(client, name, data)
        assert response.status_code == 422, (name, response.text)
        assert (
            response.json()["detail"].startswith(f"{name}: ") and words in response.json()["detail"]
        )


def test_an_upload_over_the_limit_is_a_413(app: Any, client: TestClient) -> None:
    app.dependency_overrides[request_settings] = lambda: Settings(max_upload_bytes=1000)
    try:
        response = parse(client, "big.geojson", json.dumps({"pad": "x" * 2000}).encode())
    finally:
        del app.dependency_overrides[request_settings]
    assert response.status_code == 413
