"""Bad input gets a clear 4xx naming the input and the problem, never a 500, and stores nothing.

Every case is sent to ``POST /api/plans`` with one plan already stored, and the stored plans
are compared before and after; the same bodies must fail the same way on the preview.
"""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest
from fastapi.exceptions import RequestValidationError
from sqlalchemy import select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient
from starlette.types import Message, Receive, Scope, Send

from app.errors import (
    STATUS_CODES,
    BodySizeLimitMiddleware,
    BodyTooLargeError,
    ConflictError,
    DatabaseBusyError,
    NotFoundError,
    ServerBusyError,
    UnavailableError,
    UploadTooLargeError,
    format_validation_errors,
    status_for,
)
from app.models import Plan
from app.track_fixes import TrackFormatError
from navigation import NavigationError
from planner import InvalidFieldError, InvalidParameterError, PlannerError, PlanTooLargeError

PAPER_RING = [
    [115.298, -8.6265],
    [115.29813989, -8.62649238],
    [115.29814712, -8.62631751],
    [115.29800448, -8.62632237],
    [115.298, -8.6265],
]
PAPER = {"type": "Polygon", "coordinates": [PAPER_RING]}


def box(lon: float, lat: float, dlon: float, dlat: float) -> dict[str, Any]:
    ring = [[lon, lat], [lon + dlon, lat], [lon + dlon, lat + dlat], [lon, lat + dlat], [lon, lat]]
    return {"type": "Polygon", "coordinates": [ring]}


def body(**changes: Any) -> dict[str, Any]:
    return {"field": PAPER, "interval_m": 4, **changes}


def raw(text: str) -> bytes:
    return text.encode()


# A figure eight whose loops differ in size (a symmetric one has no net area at all).
BOWTIE = {
    "type": "Polygon",
    "coordinates": [
        [[115.298, -8.6265], [115.2984, -8.6261], [115.2984, -8.6265], [115.298, -8.6263]]
        + [[115.298, -8.6265]]
    ],
}

#: name -> (JSON body or raw bytes, substrings the detail must contain)
CASES: dict[str, tuple[dict[str, Any] | bytes, tuple[str, ...]]] = {
    # malformed JSON
    "truncated json": (raw('{"field": {"type": "Polygon"'), ("body", "not valid JSON")),
    "not utf-8": (b'{"interval_m": \xff}', ("body", "not valid JSON")),
    "nested too deep": (b"[" * 50_000, ("body", "not valid JSON")),
    "empty body": (b"", ("body", "required")),
    "array body": (raw("[1, 2]"), ("body", "JSON object")),
    # wrong types
    "interval as text": (body(interval_m="four"), ("interval_m", "number")),
    "interval missing": ({"field": PAPER}, ("interval_m", "required")),
    "field missing": ({"interval_m": 4}, ("field", "required")),
    "field as text": (body(field="my field"), ("field", "JSON object")),
    "start not a pair": (body(start=[115.3]), ("start",)),
    "start as text": (body(start="gate"), ("start",)),
    "headland fraction": (body(headland_passes=1.5), ("headland_passes", "whole number")),
    "unknown objective": (body(objective="zigzag"), ("objective", "shortest_path")),
    "unknown input": (body(intervall_m=4), ("intervall_m", "not a known input")),
    "name too long": (body(name="x" * 201), ("name", "too long")),
    "coordinates as text": (
        body(field={"type": "Polygon", "coordinates": [[["a", "b"]] * 4]}),
        ("field", "[lon, lat]"),
    ),
    # not a polygon, or not a plannable one
    "point": (body(field={"type": "Point", "coordinates": [115.3, -8.6]}), ("field", "Polygon")),
    "line string": (
        body(field={"type": "LineString", "coordinates": PAPER_RING}),
        ("field", "Polygon"),
    ),
    "empty polygon": (body(field={"type": "Polygon", "coordinates": []}), ("field",)),
    "self-intersecting": (body(field=BOWTIE), ("field", "self-intersecting")),
    "huge polygon": (body(field=box(115.0, -8.7, 0.5, 0.5)), ("field", "2,000 ha")),
    "tiny polygon": (body(field=box(115.0, -8.7, 1e-6, 1e-6)), ("field", "too small")),
    "sliver 1,300 km long": (body(field=box(115.0, -8.7, 1e-4, 12.0)), ("field", "25 km")),
    "two polygons": (
        body(
            field={
                "type": "FeatureCollection",
                "features": [{"type": "Feature", "properties": {}, "geometry": PAPER}] * 2,
            }
        ),
        ("field", "2 polygons"),
    ),
    "feature properties not an object": (
        body(field={"type": "Feature", "properties": [1], "geometry": PAPER}),
        ("field", "properties"),
    ),
    "collection feature properties not an object": (
        body(
            field={
                "type": "FeatureCollection",
                "features": [{"type": "Feature", "properties": "start", "geometry": PAPER}],
            }
        ),
        ("field", "properties"),
    ),
    # out-of-range parameters
    "interval zero": (body(interval_m=0), ("interval_m", "between 0.2 and 50")),
    "interval negative": (body(interval_m=-4), ("interval_m", "between 0.2 and 50")),
    "interval too wide": (body(interval_m=51), ("interval_m", "between 0.2 and 50")),
    "angle 180": (body(angle_deg=180), ("angle_deg",)),
    "headland 6": (body(headland_passes=6), ("headland_passes",)),
    "speed zero": (body(speed_mps=0), ("speed_mps",)),
    "start far away": (body(start=[116.0, -8.6]), ("start", "5 km")),
    "finish off the globe": (body(finish=[115.3, -95.0]), ("finish",)),
    # NaN and infinity: not JSON, but Python's json module reads them
    "nan coordinate": (
        raw(json.dumps(body()).replace("115.298,", "NaN,", 1)),
        ("field", "not finite"),
    ),
    "infinite coordinate": (
        raw(json.dumps(body()).replace("115.298,", "Infinity,", 1)),
        ("field", "not finite"),
    ),
    "nan interval": (
        raw(json.dumps(body()).replace('"interval_m": 4', '"interval_m": NaN')),
        (
            "interval_m",
            "finite",
        ),
    ),
    "nan start": (
        raw(json.dumps(body(start=[0, 0])).replace("[0, 0]", "[NaN, -8.6]")),
        (
            "start[0]",
            "finite",
        ),
    ),
    "infinite speed": (
        raw(json.dumps(body(speed_mps=1)).replace('"speed_mps": 1', '"speed_mps": -Infinity')),
        ("speed_mps", "finite"),
    ),
    # too much work
    "too many lines": (
        body(field=box(115.0, -8.7, 0.038, 0.038), interval_m=0.2),
        ("interval_m", "20,000"),
    ),
}


def post(client: TestClient, path: str, payload: dict[str, Any] | bytes) -> Any:
    if isinstance(payload, bytes):
        return client.post(path, content=payload, headers={"content-type": "application/json"})
    return client.post(path, json=payload)


def stored(session: Session) -> list[tuple[int, str | None]]:
    return [(p.id, p.name) for p in session.scalars(select(Plan).order_by(Plan.id))]


@pytest.fixture
def existing_plan(client: TestClient) -> dict[str, Any]:
    response = client.post("/api/plans", json=body(name="keep me"))
    assert response.status_code == 201, response.text
    plan: dict[str, Any] = response.json()
    return plan


@pytest.mark.parametrize("case", list(CASES))
def test_bad_plan_request_returns_422_naming_problem_and_stores_nothing(
    case: str, client: TestClient, session: Session, existing_plan: dict[str, Any]
):
    payload, expected = CASES[case]
    before = stored(session)
    listing_before = client.get("/api/plans").json()

    response = post(client, "/api/plans", payload)

    assert response.status_code == 422, response.text
    detail = response.json()["detail"]
    assert isinstance(detail, str)
    for words in expected:
        assert words in detail, detail
    assert "location" not in response.headers
    assert stored(session) == before == [(existing_plan["id"], "keep me")]
    assert client.get("/api/plans").json() == listing_before


@pytest.mark.parametrize("case", list(CASES))
def test_bad_preview_request_returns_422_naming_problem(case: str, client: TestClient):
    payload, expected = CASES[case]
    response = post(client, "/api/plans/preview", payload)
    assert response.status_code == 422, response.text
    detail = response.json()["detail"]
    assert isinstance(detail, str)
    assert all(words in detail for words in expected), detail


def test_validation_detail_is_one_readable_sentence(client: TestClient):
    response = client.post(
        "/api/plans/preview", json={"field": PAPER, "interval_m": "x", "objective": 3}
    )
    assert response.status_code == 422
    assert response.json() == {
        "detail": "interval_m: must be a number; objective: must be 'shortest_path' or "
        "'fewest_lines'"
    }


def test_body_without_json_content_type_returns_422(client: TestClient):
    response = client.post(
        "/api/plans", content=json.dumps(body()), headers={"content-type": "text/plain"}
    )
    assert response.status_code == 422
    assert response.json()["detail"] == (
        "body: must be a JSON object sent as Content-Type: application/json"
    )


def test_body_over_limit_by_content_length_returns_413(
    client: TestClient, session: Session, existing_plan: dict[str, Any]
):
    before = stored(session)
    padded = body(name="big", padding="x" * 300_000)  # over the test app's 256 KiB limit
    response = client.post("/api/plans", json=padded)
    assert response.status_code == 413
    assert response.json() == {
        "detail": "body: the request is larger than the limit of 262144 bytes"
    }
    assert stored(session) == before


def test_body_just_under_limit_is_read(client: TestClient):
    # Within the limit, the body reaches the app (here: an unknown input, so 422, not 413).
    response = client.post("/api/plans/preview", json=body(padding="x" * 200_000))
    assert response.status_code == 422
    assert response.json()["detail"] == "padding: is not a known input"


def test_unknown_route_returns_404_with_string_detail(client: TestClient):
    response = client.get("/api/nothing")
    assert response.status_code == 404
    assert isinstance(response.json()["detail"], str)


# --- the error table and the body-limit middleware, directly ---------------------------------


def test_error_table_maps_every_planner_error_to_422():
    for cls in (PlannerError, InvalidFieldError, InvalidParameterError, PlanTooLargeError):
        assert status_for(cls("field", "x")) == 422
    assert status_for(NotFoundError("plan", 42)) == 404
    assert str(NotFoundError("plan", 42)) == "plan 42 not found"
    assert status_for(BodyTooLargeError(10)) == 413
    assert status_for(RequestValidationError([])) == 422
    assert status_for(RuntimeError("boom")) == 500
    assert status_for(NavigationError("gps", "x")) == 422
    assert status_for(TrackFormatError("file", "x")) == 422
    assert status_for(UploadTooLargeError(10)) == 413
    assert status_for(ConflictError("run 1: x")) == 409
    assert set(STATUS_CODES.values()) == {401, 404, 409, 413, 422, 429, 503}
    assert status_for(ServerBusyError("simulation")) == 503
    assert status_for(DatabaseBusyError()) == 503
    assert status_for(UnavailableError("jobs: no engine")) == 503


def test_format_validation_errors_names_nested_inputs():
    errors = [
        {"loc": ("body", "start", 1), "type": "finite_number"},
        {"loc": ("query", "limit"), "type": "greater_than_equal", "ctx": {"ge": 1}},
        {"loc": ("body", 17), "type": "json_invalid", "ctx": {"error": "Expecting ','"}},
    ]
    assert format_validation_errors(errors) == (
        "start[1]: must be a finite number; limit: must be at least 1; "
        "body: is not valid JSON (Expecting ',')"
    )


async def _call(
    middleware: BodySizeLimitMiddleware, headers: list[tuple[bytes, bytes]], chunks: list[bytes]
) -> list[Message]:
    messages = iter(
        [
            {"type": "http.request", "body": c, "more_body": i < len(chunks) - 1}
            for i, c in enumerate(chunks)
        ]
    )
    sent: list[Message] = []

    async def receive() -> Message:
        return next(messages, {"type": "http.disconnect"})

    async def send(message: Message) -> None:
        sent.append(message)

    scope: Scope = {"type": "http", "method": "POST", "path": "/", "headers": headers}
    await middleware(scope, receive, send)
    return sent


class RecordingApp:
    """An ASGI app that records the body it was given and answers 200."""

    def __init__(self) -> None:
        self.bodies: list[bytes] = []

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        message = await receive()
        self.bodies.append(message.get("body", b""))
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b"ok"})


def _status(sent: list[Message]) -> int:
    return int(next(m for m in sent if m["type"] == "http.response.start")["status"])


@pytest.fixture
def recording() -> RecordingApp:
    return RecordingApp()


def test_middleware_counts_streamed_chunks_without_content_length(recording: RecordingApp):
    middleware = BodySizeLimitMiddleware(recording, max_body_bytes=10)
    sent = asyncio.run(_call(middleware, [], [b"12345", b"67890", b"1"]))
    assert _status(sent) == 413
    assert recording.bodies == []


def test_middleware_refuses_body_longer_than_its_content_length(recording: RecordingApp):
    middleware = BodySizeLimitMiddleware(recording, max_body_bytes=10)
    sent = asyncio.run(_call(middleware, [(b"content-length", b"5")], [b"123456", b"789012"]))
    assert _status(sent) == 413
    assert recording.bodies == []


def test_middleware_refuses_declared_length_before_reading(recording: RecordingApp):
    middleware = BodySizeLimitMiddleware(recording, max_body_bytes=10)
    sent = asyncio.run(_call(middleware, [(b"content-length", b"11")], []))
    assert _status(sent) == 413
    assert json.loads(sent[1]["body"]) == {
        "detail": "body: the request is larger than the limit of 10 bytes"
    }


def test_middleware_passes_chunked_body_within_limit_whole(recording: RecordingApp):
    middleware = BodySizeLimitMiddleware(recording, max_body_bytes=10)
    sent = asyncio.run(_call(middleware, [], [b"12345", b"67890"]))
    assert _status(sent) == 200
    assert recording.bodies == [b"1234567890"]
