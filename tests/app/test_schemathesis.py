"""Schemathesis over the OpenAPI spec, with a token, against ``tillpath serve``: no 5xx.

Every operation of the spec gets generated requests (its examples, then random ones within
and around the schema); the only check is that the server never answers ≥ 500. The run is
bounded (:data:`MAX_EXAMPLES` per operation) so that CI stays short.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import ExitStack
from typing import Any

import pytest
import requests
import schemathesis
from hypothesis import HealthCheck, given, settings
from schemathesis.checks import not_a_server_error

from app.db import get_engine
from app.main import create_app
from app.testing import ServerUrl, running_server
from tests.databases import DATABASES, scratch_pg_database

#: Generated requests per operation (``TILLPATH_SCHEMATHESIS_EXAMPLES`` overrides it).
MAX_EXAMPLES = int(os.environ.get("TILLPATH_SCHEMATHESIS_EXAMPLES", "12"))


@pytest.fixture(scope="module", params=DATABASES)
def served(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[ServerUrl]:
    """``tillpath serve`` on each database, with a plan, a live run and a fix in it."""
    workdir = tmp_path_factory.mktemp("schemathesis")
    with ExitStack() as stack:
        if request.param == "sqlite":
            db_url = f"sqlite:///{workdir / 't.db'}"
        else:
            db_url = stack.enter_context(scratch_pg_database("tillpath_schemathesis"))
        url = stack.enter_context(
            running_server(db_url, log=workdir / "serve.log", serve_args=["--no-access-log"])
        )
        # A plan, a live run with a fix and a field, so that ids 1 exist for the generator.
        session = requests.Session()
        session.headers.update(url.headers)
        paper = {
            "type": "Polygon",
            "coordinates": [
                [
                    [115.298, -8.6265],
                    [115.29813989, -8.62649238],
                    [115.29814712, -8.62631751],
                    [115.29800448, -8.62632237],
                    [115.298, -8.6265],
                ]
            ],
        }
        assert session.post(f"{url}/api/plans", json={"field": paper, "interval_m": 4}).ok
        assert session.post(f"{url}/api/plans/1/runs", json={}).ok
        fix = [{"t": 1795318455, "lat": -8.6265, "lon": 115.298}]
        assert session.post(f"{url}/api/runs/1/fixes", json=fix).ok
        yield url
    get_engine.cache_clear()


@pytest.fixture(scope="module")
def api_schema(served: ServerUrl) -> Any:
    return schemathesis.openapi.from_url(f"{served}/openapi.json")


def spec_operations() -> list[tuple[str, str]]:
    """(method, path) of every operation of the spec, read in process at collection time."""
    spec = create_app().openapi()
    return [
        (method.upper(), path)
        for path, item in spec["paths"].items()
        for method in item
        if method in {"get", "post", "put", "patch", "delete"}
    ]


OPERATIONS = spec_operations()
#: What the run found, per status class, for the closing note (printed at the end).
SEEN: dict[str, int] = {}


@pytest.mark.parametrize("operation", OPERATIONS, ids=[f"{m} {p}" for m, p in OPERATIONS])
def test_no_response_is_a_server_error(
    operation: tuple[str, str], api_schema: Any, served: ServerUrl
) -> None:
    method, path = operation
    headers = dict(served.headers)
    if (method, path) == ("DELETE", "/api/tokens/{token_id}"):
        # The generator must not revoke the token it runs with (that would leave it 401s).
        headers["Authorization"] = "Bearer tp_a-token-that-does-not-exist"
    strategy = api_schema[path][method].as_strategy()

    @settings(
        max_examples=MAX_EXAMPLES,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        derandomize=True,
        database=None,
    )
    @given(case=strategy)
    def check(case: Any) -> None:
        response = case.call_and_validate(headers=headers, checks=[not_a_server_error])
        key = f"{response.status_code // 100}xx"
        SEEN[key] = SEEN.get(key, 0) + 1
        assert response.status_code < 500

    check()


def test_report_figures() -> None:
    """Not a check: prints how many generated requests got each class of answer."""
    print("schemathesis answers by class:", dict(sorted(SEEN.items())))
