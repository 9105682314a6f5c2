"""``GET /api/health`` really asks the database."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from fastapi import FastAPI
from sqlalchemy import create_engine
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app.db import get_session


def test_health_reports_ok_with_database(client: TestClient):
    response = client.get("/api/health")
    assert response.status_code == 200
    assert response.json() == {"status": "ok", "database": "ok"}


def test_health_reports_503_when_database_is_unreachable(app: FastAPI, tmp_path: Path):
    missing = tmp_path / "no" / "such" / "dir" / "tillpath.db"  # SQLite cannot create it
    engine = create_engine(f"sqlite:///{missing}")

    def broken_session() -> Iterator[Session]:
        with Session(engine) as session:
            yield session

    app.dependency_overrides[get_session] = broken_session
    try:
        with TestClient(app) as client:
            response = client.get("/api/health")
    finally:
        engine.dispose()
    assert response.status_code == 503
    assert response.json() == {"status": "error", "database": "error"}
