"""``/api/fields``: the organisation's field registry (product.md §12)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Response, status

from app import fields
from app.auth import Planner, Viewer
from app.db import SessionDep
from app.field_schemas import FieldCreate, FieldList, FieldRead, FieldUpdate, PlansOnDelete
from app.models import Field
from app.schemas import ErrorRead

router = APIRouter(prefix="/fields", tags=["fields"])

_BAD_INPUT: dict[int | str, dict[str, Any]] = {
    422: {"model": ErrorRead, "description": "The input named in `detail` is wrong"}
}
_NOT_FOUND: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorRead, "description": "No such field"}
}


@router.get("", response_model=FieldList, responses=_BAD_INPUT)
def list_fields(
    session: SessionDep,
    access: Viewer,
    limit: Annotated[int, Query(ge=1, le=500, description="Page size.")] = 200,
    offset: Annotated[int, Query(ge=0, le=1_000_000_000, description="Fields to skip.")] = 0,
) -> FieldList:
    """List the organisation's fields, newest first, with their boundaries and plan counts."""
    return fields.list_fields(session, access, limit=limit, offset=offset)


@router.post(
    "", response_model=FieldRead, status_code=status.HTTP_201_CREATED, responses=_BAD_INPUT
)
def create_field(
    body: FieldCreate, session: SessionDep, access: Planner, response: Response
) -> FieldRead:
    """Add a field to the registry; ``Location`` names it."""
    field = fields.create_field(session, body, access)
    response.headers["Location"] = f"/api/fields/{field.id}"
    return fields.field_view(field)


@router.get("/{field_id}", response_model=FieldRead, responses={**_NOT_FOUND, **_BAD_INPUT})
def read_field(field_id: int, session: SessionDep, access: Viewer) -> FieldRead:
    """Return one field with its boundary, gates, notes and plan count."""
    return fields.read_field_view(session, field_id, access)


@router.patch("/{field_id}", response_model=FieldRead, responses={**_NOT_FOUND, **_BAD_INPUT})
def update_field(
    field_id: int, body: FieldUpdate, session: SessionDep, access: Planner
) -> FieldRead:
    """Change a field's name, boundary, gates or notes; its plans keep what they planned."""
    field: Field = fields.update_field(session, field_id, body, access)
    return fields.read_field_view(session, field.id, access)


@router.delete(
    "/{field_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    response_class=Response,
    responses={**_NOT_FOUND, **_BAD_INPUT},
)
def delete_field(
    field_id: int,
    session: SessionDep,
    access: Planner,
    plans: Annotated[
        PlansOnDelete,
        Query(
            description="What becomes of the field's plans: `keep` them (they keep their own "
            "copy of the boundary) or `delete` them with their simulations and runs."
        ),
    ],
) -> None:
    """Delete a field; `plans` must say whether its plans are kept or deleted."""
    fields.delete_field(session, field_id, access, plans=plans)
