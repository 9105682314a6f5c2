"""Helpers shared by the command-line modules."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import typer

if TYPE_CHECKING:
    from planner import CoveragePlan, FieldSpec

#: Exit status for bad input (as argparse and click use for usage errors).
EXIT_BAD_INPUT = 2


def fail(message: str) -> NoReturn:
    """Print ``error: message`` on stderr and exit with status 2."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(EXIT_BAD_INPUT)


def read_json_file(path: Path, *, what: str) -> Any:
    """Read and parse a JSON file, failing with a clear message naming ``what``."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        fail(f"{what}: cannot read {path}: {exc.strerror or exc}")
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        fail(f"{what}: {path} is not valid JSON (line {exc.lineno}, column {exc.colno})")


def write_output(text: str | bytes, output: Path | None) -> None:
    """Write ``text`` (or binary ``bytes``) to ``output``, or to stdout when it is None."""
    if isinstance(text, bytes):
        if output is None:
            sys.stdout.buffer.write(text)
            sys.stdout.flush()
            return
        try:
            output.write_bytes(text)
        except OSError as exc:
            fail(f"-o: cannot write {output}: {exc.strerror or exc}")
        return
    if output is None:
        sys.stdout.write(text)
        if not text.endswith("\n"):
            sys.stdout.write("\n")
        return
    try:
        output.write_text(text, encoding="utf-8")
    except OSError as exc:
        fail(f"-o: cannot write {output}: {exc.strerror or exc}")


def read_field_file(path: Path, *, feature: str | None, what: str = "FIELD") -> FieldSpec:
    """Read one field of a field file of any import format (``--feature`` picks one of many).

    Fails with status 2, naming the file, when it cannot be read; when it holds several fields
    and none (or no known one) is chosen, the message lists them all.
    """
    from planner import PlannerError
    from planner.errors import FieldChoiceError
    from planner.io import read_fields, select_field

    try:
        data = path.read_bytes()
    except OSError as exc:
        fail(f"{what}: cannot read {path}: {exc.strerror or exc}")
    try:
        return select_field(read_fields(data, filename=str(path)), feature, filename=str(path))
    except FieldChoiceError as exc:
        rows = "\n".join(
            f"  {index:>4}  {ident or '-':<28} {name or '-':<28} {area / 10_000:10.2f} ha"
            for index, ident, name, area in exc.choices
        )
        fail(
            f"{what}: {exc}. Give --feature ID|NAME|INDEX, one of:\n"
            f"  {'index':>4}  {'id':<28} {'name':<28} {'area':>13}\n{rows}"
        )
    except PlannerError as exc:
        fail(f"{what}: {exc}")


def plan_field_spec(
    spec: FieldSpec,
    *,
    interval_m: float | None,
    start_lonlat: tuple[float, float] | None = None,
    finish_lonlat: tuple[float, float] | None = None,
    **options: Any,
) -> CoveragePlan:
    """Plan one field as the commands do; the flags win over the file; bad input exits 2."""
    from planner import PlannerError, plan_coverage

    interval = interval_m if interval_m is not None else spec.interval_m
    if interval is None:
        fail("interval_m: give --interval (the field file has no interval_m property)")
    try:
        return plan_coverage(
            spec.field_lonlat,
            interval_m=interval,
            start_lonlat=start_lonlat or spec.start_lonlat,
            finish_lonlat=finish_lonlat or spec.finish_lonlat,
            **options,
        )
    except PlannerError as exc:
        fail(str(exc))


def plan_field_document(
    document: Any,
    *,
    interval_m: float | None,
    name_fallback: str,
    start_lonlat: tuple[float, float] | None = None,
    finish_lonlat: tuple[float, float] | None = None,
    **options: Any,
) -> tuple[CoveragePlan, str]:
    """Plan a GeoJSON field document as the commands do; bad input fails with status 2.

    The flags win over the file: ``interval_m``, ``start_lonlat`` and ``finish_lonlat`` fall
    back to the file's ``interval_m`` property and its start/finish Points.

    Returns
    -------
    plan : CoveragePlan
    name : str
        The field's name, or ``name_fallback``.
    """
    from planner import PlannerError, parse_field_geojson, plan_coverage

    try:
        spec = parse_field_geojson(document)
        interval = interval_m if interval_m is not None else spec.interval_m
        if interval is None:
            fail("interval_m: give --interval (the field file has no interval_m property)")
        plan = plan_coverage(
            spec.field_lonlat,
            interval_m=interval,
            start_lonlat=start_lonlat or spec.start_lonlat,
            finish_lonlat=finish_lonlat or spec.finish_lonlat,
            **options,
        )
    except PlannerError as exc:
        fail(str(exc))
    return plan, spec.name or name_fallback
