"""``/api/health``: whether the app is up and can reach its database."""

from __future__ import annotations

from fastapi import APIRouter, Depends, Response, status
from sqlalchemy import text
from sqlalchemy.exc import SQLAlchemyError

from app.auth import public
from app.db import SessionDep
from app.errors import RETRY_AFTER_S
from app.schemas import Health

router = APIRouter(tags=["health"], dependencies=[Depends(public)])


@router.get("/health", response_model=Health, responses={503: {"model": Health}})
def read_health(session: SessionDep, response: Response) -> Health:
    """Answer ``ok`` if a query reaches the database, else 503 with ``database: error``."""
    try:
        session.execute(text("SELECT 1")).scalar_one()
    except SQLAlchemyError:
        response.status_code = status.HTTP_503_SERVICE_UNAVAILABLE
        response.headers["Retry-After"] = str(RETRY_AFTER_S)
        return Health(status="error", database="error")
    return Health(status="ok", database="ok")
