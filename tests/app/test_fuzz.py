"""Whatever a client sends to the planning endpoints, the answer is 200 or a 4xx, never a 500."""

from __future__ import annotations

import json
import math
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from starlette.testclient import TestClient

RING = [
    [115.298, -8.6265],
    [115.29813989, -8.62649238],
    [115.29814712, -8.62631751],
    [115.29800448, -8.62632237],
    [115.298, -8.6265],
]

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**20), max_value=10**20),
    st.sampled_from([0, -1, 0.2, 4, 50, 180, 1e308]),
)
junk = st.recursive(
    st.one_of(st.none(), st.booleans(), numbers, st.text(max_size=8)),
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=6), children, max_size=4)
    ),
    max_leaves=12,
)


@st.composite
def fields(draw: st.DrawFn) -> Any:
    """Mostly the paper field with its corners moved (up to ~10 m), sometimes damaged."""
    ring = [
        [lon + draw(st.floats(-1e-4, 1e-4)), lat + draw(st.floats(-1e-4, 1e-4))]
        for lon, lat in RING[:-1]
    ]
    ring.append(list(ring[0]))
    for _ in range(draw(st.integers(0, 2)) if draw(st.integers(0, 3)) == 0 else 0):
        i = draw(st.integers(0, len(ring) - 1))
        ring[i][draw(st.integers(0, 1))] = draw(st.one_of(numbers, junk))
    if draw(st.integers(0, 5)) == 0:
        ring = ring[: draw(st.integers(0, len(ring)))]
    kind = draw(st.sampled_from(["Polygon"] * 6 + ["MultiPolygon", "Point", "LineString"]))
    geometry = {"type": kind, "coordinates": [[ring]] if kind == "MultiPolygon" else [ring]}
    shape = draw(st.integers(0, 9))
    if shape == 0:
        return draw(junk)
    if shape <= 3:
        return {"type": "Feature", "properties": draw(junk), "geometry": geometry}
    return geometry


near = st.tuples(st.floats(-2e-3, 2e-3), st.floats(-2e-3, 2e-3)).map(
    lambda d: [RING[0][0] + d[0], RING[0][1] + d[1]]
)
VALUES: dict[str, st.SearchStrategy[Any]] = {
    "name": st.one_of(st.none(), st.text(max_size=30), numbers),
    "interval_m": st.one_of(st.floats(0.1, 60), numbers, junk),
    "start": st.one_of(st.none(), near, st.lists(numbers, max_size=3), junk),
    "finish": st.one_of(st.none(), near, st.lists(st.floats(-200, 200), max_size=3)),
    "angle_deg": st.one_of(st.none(), st.floats(-10, 200), numbers, junk),
    "objective": st.one_of(st.sampled_from(["shortest_path", "fewest_lines"]), junk),
    "headland_passes": st.one_of(st.integers(-2, 7), numbers, junk),
    "speed_mps": st.one_of(st.floats(0, 12), numbers),
}


@st.composite
def bodies(draw: st.DrawFn) -> dict[str, Any]:
    """A valid request with a few inputs replaced by plausible or junk values."""
    body: dict[str, Any] = {"field": draw(fields()), "interval_m": draw(st.floats(0.5, 20))}
    for key in draw(st.lists(st.sampled_from(sorted(VALUES)), max_size=3, unique=True)):
        body[key] = draw(VALUES[key])
    if draw(st.integers(0, 20)) == 0:
        del body[draw(st.sampled_from(["field", "interval_m"]))]
    return body


@settings(
    max_examples=150,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(body=bodies())
def test_preview_never_fails_with_500(client: TestClient, body: dict[str, Any]):
    text = json.dumps(body, allow_nan=True)  # NaN/Infinity literals, as Python clients send
    response = client.post(
        "/api/plans/preview", content=text, headers={"content-type": "application/json"}
    )
    assert response.status_code in (200, 422), response.text
    payload = response.json()
    if response.status_code == 422:
        assert isinstance(payload["detail"], str) and ": " in payload["detail"]
    else:
        stats = payload["stats"]
        assert stats["line_count"] >= 1
        assert all(math.isfinite(v) for v in stats.values() if isinstance(v, float))
