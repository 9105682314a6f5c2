"""The field registry (product.md §12): store a field once, plan it many times.

A plan made with ``field_id`` plans the registry's field; a plan made from a drawn boundary
reuses the organisation's field with the same boundary (same canonical GeoJSON), or adds one.
Deleting a field asks what becomes of its plans: ``keep`` (they keep their own copy of the
boundary in ``request`` and lose the link) or ``delete`` (they go, with their simulations and
runs).
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

from sqlalchemy import delete, func, select, update
from sqlalchemy.orm import Session

import planner
from app.auth import Access, owned, read_owned
from app.db import begin_write, end_reads
from app.field_schemas import FieldCreate, FieldList, FieldRead, FieldUpdate, PlansOnDelete
from app.models import PLAN_NAME_MAX_LENGTH, Field, Plan, utc_now
from app.schemas import PlanCreate
from app.services import polygon_to_geojson
from planner.validation import validate_field


def boundary_sha256(boundary: dict[str, Any]) -> str:
    """Return the SHA-256 of a boundary's canonical JSON (sorted keys, no spaces).

    Examples
    --------
    >>> a = {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 0]]]}
    >>> boundary_sha256(a) == boundary_sha256(dict(reversed(list(a.items()))))
    True
    """
    text = json.dumps(boundary, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def _gate(value: Any, name: str) -> list[float] | None:
    return None if value is None else list(planner.parse_position(value, input_name=name))


def _boundary(
    document: dict[str, Any],
) -> tuple[dict[str, Any], tuple[float, float] | None, tuple[float, float] | None]:
    """Parse and validate a boundary; return its Polygon GeoJSON and the file's gates."""
    spec = planner.parse_field_geojson(document)
    validate_field(spec.field_lonlat)
    # Stored as parsed (as a plan's request stores it), so that a plan drawn on the same
    # boundary finds this field by its hash.
    return polygon_to_geojson(spec.field_lonlat), spec.start_lonlat, spec.finish_lonlat


def field_view(field: Field, plan_count: int = 0) -> FieldRead:
    """Return ``field`` as its schema."""
    read = FieldRead.model_validate(field)
    read.plan_count = plan_count
    return read


def _plan_counts(session: Session, access: Access, ids: list[int]) -> dict[int, int]:
    if not ids:
        return {}
    rows = session.execute(
        owned(Plan, access)
        .with_only_columns(Plan.field_id, func.count())
        .where(Plan.field_id.in_(ids))
        .group_by(Plan.field_id)
    ).all()
    return {int(fid): int(n) for fid, n in rows if fid is not None}


def list_fields(session: Session, access: Access, *, limit: int, offset: int) -> FieldList:
    """Return a page of the organisation's fields, newest first."""
    query = owned(Field, access)
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = list(
        session.scalars(
            query.order_by(Field.created_at.desc(), Field.id.desc()).limit(limit).offset(offset)
        )
    )
    counts = _plan_counts(session, access, [f.id for f in rows])
    return FieldList(items=[field_view(f, counts.get(f.id, 0)) for f in rows], total=total)


def read_field(session: Session, field_id: int, access: Access) -> Field:
    """Return field ``field_id`` of the organisation (404 otherwise)."""
    return read_owned(session, Field, field_id, access, kind="field")


def read_field_view(session: Session, field_id: int, access: Access) -> FieldRead:
    """Return field ``field_id`` with its plan count."""
    field = read_field(session, field_id, access)
    return field_view(field, _plan_counts(session, access, [field.id]).get(field.id, 0))


def create_field(session: Session, body: FieldCreate, access: Access) -> Field:
    """Validate and store a field of the organisation (committed)."""
    boundary, start, finish = _boundary(body.boundary)  # checked before the write lock is held
    begin_write(session)
    field = Field(
        organisation_id=access.organisation_id,
        name=body.name.strip() or "field",
        boundary=boundary,
        boundary_sha256=boundary_sha256(boundary),
        start=_gate(body.start, "start") or _gate(start, "start"),
        finish=_gate(body.finish, "finish") or _gate(finish, "finish"),
        notes=body.notes,
    )
    session.add(field)
    session.commit()
    return field


def update_field(session: Session, field_id: int, body: FieldUpdate, access: Access) -> Field:
    """Change what ``body`` gives of field ``field_id`` (committed); plans keep their copy."""
    given = body.model_fields_set
    # A new boundary is checked (the planner's validation) before the write lock is held.
    if "boundary" in given and body.boundary is not None:
        boundary, _start, _finish = _boundary(body.boundary)
    begin_write(session)
    field = read_field(session, field_id, access)
    if "name" in given and body.name is not None:
        field.name = body.name.strip() or field.name
    if "boundary" in given and body.boundary is not None:
        field.boundary = boundary
        field.boundary_sha256 = boundary_sha256(boundary)
    if "start" in given:
        field.start = _gate(body.start, "start")
    if "finish" in given:
        field.finish = _gate(body.finish, "finish")
    if "notes" in given and body.notes is not None:
        field.notes = body.notes
    field.updated_at = utc_now()
    session.commit()
    return field


def delete_field(session: Session, field_id: int, access: Access, *, plans: PlansOnDelete) -> int:
    """Delete field ``field_id``; keep or delete its plans. Return how many plans went."""
    begin_write(session)
    field = read_field(session, field_id, access)
    removed = 0
    plan_ids = owned(Plan, access).with_only_columns(Plan.id).where(Plan.field_id == field.id)
    if plans == "delete":
        ids = list(session.scalars(plan_ids))
        removed = len(ids)
        if ids:
            session.execute(delete(Plan).where(Plan.id.in_(ids)))
    else:
        session.execute(
            update(Plan)
            .where(Plan.field_id == field.id, Plan.organisation_id == access.organisation_id)
            .values(field_id=None)
        )
    session.delete(field)
    session.commit()
    return removed


def resolve_plan_body(session: Session, body: PlanCreate, access: Access) -> PlanCreate:
    """Fill a plan request that names ``field_id`` from the registry's field.

    The field's boundary is planned; its gates are the start and finish unless the request
    gives them, and its name the plan's unless the request gives one. A request with a drawn
    ``field`` passes unchanged.

    Raises
    ------
    InvalidParameterError
        If neither ``field`` nor ``field_id`` is given, or both are.
    NotFoundError
        If the field is not the organisation's.
    """
    if body.field_id is None:
        if body.field is None:
            raise planner.InvalidParameterError("field", "is required (or give field_id)")
        return body
    if body.field is not None:
        raise planner.InvalidParameterError("field_id", "give either field or field_id, not both")
    field = read_field(session, body.field_id, access)
    return body.model_copy(
        update={
            "field": field.boundary,
            "start": body.start if body.start is not None else _pair(field.start),
            "finish": body.finish if body.finish is not None else _pair(field.finish),
            "name": body.name if (body.name or "").strip() else field.name,
        }
    )


def _pair(value: list[float] | None) -> tuple[float, float] | None:
    return None if value is None else (float(value[0]), float(value[1]))


def attach_field(session: Session, plan: Plan, body: PlanCreate, access: Access) -> None:
    """Add a new plan with its organisation and its field (reused or added); not committed.

    The plan's INSERT is the write transaction's first statement (the reads before it are
    ended), so that on SQLite the look-up of the field and its INSERT happen under the write
    lock.

    Parameters
    ----------
    plan : Plan
        The planned row, not yet added.
    body : PlanCreate
        The request after :func:`resolve_plan_body`.
    """
    plan.organisation_id = access.organisation_id
    plan.field_id = body.field_id
    end_reads(session)
    session.add(plan)
    session.flush()
    if body.field_id is not None:
        return
    boundary = plan.request["field"]
    digest = boundary_sha256(boundary)
    field = session.scalar(
        owned(Field, access).where(Field.boundary_sha256 == digest).order_by(Field.id).limit(1)
    )
    if field is None:
        name = (plan.name or "").strip() or "Field"
        field = Field(
            organisation_id=access.organisation_id,
            name=name[:PLAN_NAME_MAX_LENGTH],
            boundary=boundary,
            boundary_sha256=digest,
            start=plan.request.get("start"),
            finish=plan.request.get("finish"),
            notes="",
        )
        session.add(field)
        session.flush()
    plan.field_id = field.id
