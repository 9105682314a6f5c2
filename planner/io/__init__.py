"""Reading field files: every import format into :class:`planner.fields.FieldSpec` (pure).

``read_fields(data, filename=…)`` is the one reader the page, the API and the CLI share;
``select_field`` picks one field of many (``--feature``); :mod:`planner.io.safety` holds the
archive and XML checks.
"""

from planner.io.readers import (
    FIELD_FILE_SUFFIXES,
    FIELD_FORMATS,
    detect_field_format,
    field_choices,
    fields_to_geojson,
    read_fields,
    select_field,
)
from planner.io.safety import DEFAULT_LIMITS, ArchiveLimits, check_xml, unzip_checked

__all__ = [
    "DEFAULT_LIMITS",
    "FIELD_FILE_SUFFIXES",
    "FIELD_FORMATS",
    "ArchiveLimits",
    "check_xml",
    "detect_field_format",
    "field_choices",
    "fields_to_geojson",
    "read_fields",
    "select_field",
    "unzip_checked",
]
