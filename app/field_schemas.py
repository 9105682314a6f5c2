"""Schemas of the field registry (``/api/fields``, product.md §12)."""

from __future__ import annotations

import datetime as dt
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from app.models import PLAN_NAME_MAX_LENGTH
from app.schemas import PAPER_FIELD_EXAMPLE, PAPER_START_EXAMPLE, Position, StoredText

#: Longest notes of a field [characters].
NOTES_MAX_LENGTH = 10_000

#: What ``DELETE /api/fields/{id}`` does to the field's plans.
PlansOnDelete = Literal["keep", "delete"]

_BOUNDARY = (
    "GeoJSON Polygon, Feature or one-polygon FeatureCollection, WGS84 [lon, lat]; holes are "
    "obstacles. Points with role start/finish in a FeatureCollection become the gates when "
    "`start`/`finish` are absent."
)


class FieldCreate(BaseModel):
    """Body of ``POST /api/fields``."""

    model_config = ConfigDict(
        extra="forbid",
        allow_inf_nan=False,
        json_schema_extra={
            "examples": [
                {
                    "name": "Ketewel",
                    "boundary": PAPER_FIELD_EXAMPLE,
                    "start": PAPER_START_EXAMPLE,
                    "notes": "Sawah of Pak Wayan; the gate is by the irrigation inlet.",
                }
            ]
        },
    )

    name: StoredText = Field(
        min_length=1, max_length=PLAN_NAME_MAX_LENGTH, description="Field name."
    )
    boundary: dict[str, Any] = Field(description=_BOUNDARY)
    start: Position | None = Field(default=None, description="[lon, lat] gate to enter.")
    finish: Position | None = Field(default=None, description="[lon, lat] gate to leave.")
    notes: StoredText = Field(default="", max_length=NOTES_MAX_LENGTH, description="Free text.")


class FieldUpdate(BaseModel):
    """Body of ``PATCH /api/fields/{id}``: only what is given changes (null clears a gate)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    name: StoredText | None = Field(default=None, min_length=1, max_length=PLAN_NAME_MAX_LENGTH)
    boundary: dict[str, Any] | None = Field(default=None, description=_BOUNDARY)
    start: Position | None = None
    finish: Position | None = None
    notes: StoredText | None = Field(default=None, max_length=NOTES_MAX_LENGTH)


class FieldRead(BaseModel):
    """A field of the registry."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    name: str
    boundary: dict[str, Any] = Field(description="GeoJSON Polygon, WGS84.")
    start: Position | None
    finish: Position | None
    notes: str
    created_at: dt.datetime
    updated_at: dt.datetime
    plan_count: int = Field(default=0, description="Stored plans of this field.")


class FieldList(BaseModel):
    """The organisation's fields, newest first."""

    items: list[FieldRead]
    total: int
