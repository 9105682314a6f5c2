"""``tillpath plan``: plan a field file and write the plan (product.md §10)."""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from app.cli.common import fail, plan_field_spec, read_field_file, read_json_file, write_output


class OutputFormat(StrEnum):
    """Formats ``tillpath plan`` writes."""

    geojson = "geojson"
    gpx = "gpx"
    csv = "csv"
    json = "json"
    kml = "kml"
    waypoints = "waypoints"
    plan = "plan"
    gpkg = "gpkg"


class PatternChoice(StrEnum):
    """How the path covers the field (product.md §3)."""

    boustrophedon = "boustrophedon"
    snake = "snake"
    spiral = "spiral"


def parse_vehicle(text: str | None) -> str | dict[str, object] | None:
    """Return a preset name as is, or the fields of a JSON vehicle file (``{"preset": …, …}``)."""
    if text is None:
        return None
    path = Path(text)
    if text.endswith(".json") or path.is_file():
        document = read_json_file(path, what="--vehicle")
        if not isinstance(document, dict):
            fail(f"--vehicle: {path} must hold a JSON object of vehicle fields")
        return document
    return text


class ObjectiveChoice(StrEnum):
    """What the heading and order search minimises."""

    shortest_path = "shortest_path"
    fewest_lines = "fewest_lines"


def parse_lonlat(text: str | None, *, option: str) -> tuple[float, float] | None:
    """Parse ``LON,LAT`` from the command line, failing with a clear message."""
    if text is None:
        return None
    parts = text.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        return float(parts[0]), float(parts[1])
    except ValueError:
        fail(f"{option}: expected LON,LAT in degrees (e.g. 115.2980,-8.6265), got {text!r}")


def plan_command(
    field: Annotated[
        Path,
        typer.Argument(
            metavar="FIELD",
            help="Field file: GeoJSON, KML, KMZ, zipped Shapefile or GeoPackage.",
        ),
    ],
    feature: Annotated[
        str | None,
        typer.Option(
            "--feature",
            metavar="ID|NAME|INDEX",
            help="Which field of a file of many: its id, its name or its 0-based index.",
        ),
    ] = None,
    interval: Annotated[
        float | None,
        typer.Option(
            "--interval",
            help="Distance between tillage lines, in metres; default: the file's interval_m.",
        ),
    ] = None,
    start: Annotated[
        str | None, typer.Option("--start", metavar="LON,LAT", help="Where the tractor enters.")
    ] = None,
    finish: Annotated[
        str | None, typer.Option("--finish", metavar="LON,LAT", help="Where it must end.")
    ] = None,
    angle: Annotated[
        float | None,
        typer.Option(
            "--angle",
            help="Line heading in degrees clockwise from true north, 0–180; default: searched.",
        ),
    ] = None,
    objective: Annotated[
        ObjectiveChoice, typer.Option("--objective", help="What to minimise.")
    ] = ObjectiveChoice.shortest_path,
    headland: Annotated[
        int, typer.Option("--headland", help="Headland passes around the inside, 0–5.")
    ] = 0,
    vehicle: Annotated[
        str | None,
        typer.Option(
            "--vehicle",
            metavar="PRESET|FILE.json",
            help=(
                "The machine: hand_tractor (default), paper_g1000, small_tractor, rover, or a "
                'JSON file such as {"preset": "small_tractor", "min_turn_radius_m": 4}.'
            ),
        ),
    ] = None,
    implement_width: Annotated[
        float | None,
        typer.Option(
            "--implement-width",
            metavar="M",
            help="Working width of the implement in metres; default: the interval.",
        ),
    ] = None,
    pattern: Annotated[
        PatternChoice,
        typer.Option(
            "--pattern",
            help="Lines back and forth, skipping lines (snake), or rounds inward (spiral).",
        ),
    ] = PatternChoice.boustrophedon,
    speed: Annotated[
        float | None,
        typer.Option("--speed", metavar="V", help="Working speed in m/s; default 0.56."),
    ] = None,
    output_format: Annotated[
        OutputFormat, typer.Option("--format", help="Output format.")
    ] = OutputFormat.geojson,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Write here instead of stdout.")
    ] = None,
) -> None:
    """Plan the back-and-forth path over FIELD; figures go to stderr, the plan to stdout or -o."""
    from planner import export

    spec = read_field_file(field, feature=feature)
    start_lonlat = parse_lonlat(start, option="--start")
    finish_lonlat = parse_lonlat(finish, option="--finish")
    plan = plan_field_spec(
        spec,
        interval_m=interval,
        start_lonlat=start_lonlat,
        finish_lonlat=finish_lonlat,
        angle_deg=angle,
        objective=objective.value,
        headland_passes=headland,
        vehicle=parse_vehicle(vehicle),
        implement_width_m=implement_width,
        pattern=pattern.value,
        **({} if speed is None else {"speed_mps": speed}),
    )
    name = spec.name or field.stem
    text: str | bytes
    if output_format is OutputFormat.geojson:
        text = json.dumps(export.plan_to_geojson(plan, name=name), indent=1)
    elif output_format is OutputFormat.gpx:
        text = export.plan_to_gpx(plan, name=name)
    elif output_format is OutputFormat.csv:
        text = export.plan_to_csv(plan)
    elif output_format is OutputFormat.kml:
        text = export.plan_to_kml(plan, name=name)
    elif output_format is OutputFormat.waypoints:
        text = export.plan_to_qgc_wpl(plan)
    elif output_format is OutputFormat.plan:
        text = json.dumps(export.plan_to_qgc_plan(plan), indent=1)
    elif output_format is OutputFormat.gpkg:
        if output is None:
            fail("--format gpkg: a GeoPackage is a database file; give -o FILE.gpkg")
        text = export.plan_to_gpkg(plan, name=name)
    else:
        text = json.dumps(export.plan_to_waypoints_json(plan), indent=1)
    write_output(text, output)
    s = plan.stats
    typer.echo(
        f"{name}: {s.line_count} lines, {s.waypoint_count} waypoints, "
        f"area {s.area_m2:,.1f} m², path {s.path_length_m:,.1f} m "
        f"(lines {s.working_length_m:,.1f}, turns {s.turn_length_m:,.1f}, "
        f"transit {s.transit_length_m:,.1f}), heading {s.angle_deg:.1f}°, "
        f"coverage {s.coverage_ratio:.1%} with a {plan.implement_width_m or plan.interval_m:g} m "
        f"implement, vehicle {plan.vehicle.preset if plan.vehicle else '?'}, "
        f"about {s.estimated_time_s / 60:.1f} min, "
        f"planned in {s.planning_ms:.1f} ms",
        err=True,
    )


def register(cli: typer.Typer) -> None:
    """Add ``plan`` to ``cli``."""
    cli.command("plan")(plan_command)
