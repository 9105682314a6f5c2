"""Helpers shared by the command-line modules."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import typer

if TYPE_CHECKING:
    from planner import CoveragePlan

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


def write_output(text: str, output: Path | None) -> None:
    """Write ``text`` to ``output``, or to stdout when ``output`` is None."""
    if output is None:
        sys.stdout.write(text)
        if not text.endswith("\n"):
            sys.stdout.write("\n")
        return
    try:
        output.write_text(text, encoding="utf-8")
    except OSError as exc:
        fail(f"-o: cannot write {output}: {exc.strerror or exc}")


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
