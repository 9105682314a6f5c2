"""Import a file of many fields into the registry in one go (product.md §4, §12).

The file is read by the same reader as ``tillpath plan`` and the page (:mod:`planner.io`);
every field is validated before anything is stored, so a file with one bad field stores
nothing and the error names that field. A field whose boundary the organisation already has
(same canonical GeoJSON, as :mod:`app.fields` matches drawn plans) is reused, not copied.
"""

from __future__ import annotations

from typing import Final

from pydantic import BaseModel
from pydantic import Field as SchemaField
from sqlalchemy.orm import Session

from app.auth import Access, owned
from app.db import end_reads
from app.field_schemas import FieldRead
from app.fields import boundary_sha256, field_view
from app.models import PLAN_NAME_MAX_LENGTH, Field
from app.services import polygon_to_geojson
from planner import InvalidFieldError, PlannerError
from planner.fields import FieldSpec
from planner.validation import validate_field

#: Most fields one import may hold (the 223 shared real fields fit many times over).
MAX_IMPORT_FIELDS: Final = 5_000


class FieldImportRead(BaseModel):
    """Answer of ``POST /api/fields/import``: the file's fields as stored, in file order."""

    fields: list[FieldRead]
    created: int = SchemaField(description="Fields added to the registry.")
    reused: int = SchemaField(description="Fields whose boundary the registry already had.")


def import_fields(
    session: Session, specs: list[FieldSpec], access: Access, *, filename: str
) -> FieldImportRead:
    """Store every field of a file for the organisation (committed), in file order.

    Parameters
    ----------
    specs : list of FieldSpec
        What :func:`planner.io.read_fields` read from the file.
    filename : str
        Named in errors and in the default names (``<file> 3``).

    Returns
    -------
    FieldImportRead
        The file's fields as stored: new ones, and existing ones with the same boundary.

    Raises
    ------
    InvalidFieldError
        If the file holds too many fields or one of them cannot be planned; nothing is stored.
    """
    if len(specs) > MAX_IMPORT_FIELDS:
        raise InvalidFieldError(
            filename, f"holds {len(specs)} fields; import at most {MAX_IMPORT_FIELDS} at once"
        )
    rows: list[tuple[str, dict[str, object], FieldSpec]] = []
    for index, spec in enumerate(specs):
        label = spec.name or spec.feature_id or f"{filename} {index}"
        try:
            validate_field(spec.field_lonlat)
        except PlannerError as exc:
            raise InvalidFieldError(
                filename, f"field {index} ({label}): {exc.problem}; nothing was imported"
            ) from None
        rows.append((label[:PLAN_NAME_MAX_LENGTH], polygon_to_geojson(spec.field_lonlat), spec))

    digests = [boundary_sha256(boundary) for _, boundary, _ in rows]
    existing = {
        field.boundary_sha256: field
        for field in session.scalars(owned(Field, access).where(Field.boundary_sha256.in_(digests)))
    }
    end_reads(session)
    stored: list[Field] = []
    created = 0
    for (name, boundary, spec), digest in zip(rows, digests, strict=True):
        field = existing.get(digest)
        if field is None:
            field = Field(
                organisation_id=access.organisation_id,
                name=name,
                boundary=boundary,
                boundary_sha256=digest,
                start=list(spec.start_lonlat) if spec.start_lonlat else None,
                finish=list(spec.finish_lonlat) if spec.finish_lonlat else None,
                notes=f"Imported from {filename}"[:200],
            )
            session.add(field)
            existing[digest] = field
            created += 1
        stored.append(field)
    session.commit()
    return FieldImportRead(
        fields=[field_view(f) for f in stored], created=created, reused=len(stored) - created
    )
