"""``tillpath simulate``: drive a plan with the simulated tractor (product.md §7, §10).

FIELD is a GeoJSON field file (planned first, with its start, finish and interval) or PLAN a
plan GeoJSON written by ``tillpath plan``. Metrics go to stdout as JSON. With ``--runs N``
the run is repeated over seeds ``seed … seed+N-1`` (Monte Carlo) and each metric is
summarised by its median and spread; ``--plot`` and ``--gpx`` then show the run whose
cross-track RMS is the median one.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from app.cli.common import (
    fail,
    plan_field_document,
    plan_field_spec,
    read_field_file,
    read_json_file,
    write_output,
)

if TYPE_CHECKING:
    from rich.progress import Progress

    from navigation import SimulationLog
    from planner import CoveragePlan

#: Scalar metrics summarised over Monte Carlo runs.
SUMMARY_METRICS = (
    "time_s",
    "distance_m",
    "cross_track_max_m",
    "cross_track_rms_m",
    "cross_track_p95_m",
    "turn_cross_track_max_m",
    "turn_cross_track_rms_m",
    "waypoint_error_max_m",
    "waypoint_error_mean_m",
    "line_waypoint_error_max_m",
    "waypoint_error_estimate_max_m",
    "waypoint_error_estimate_mean_m",
    "line_waypoint_error_estimate_max_m",
    "coverage_ratio",
    "on_line_share",
    "filter_rms_m",
    "gps_rms_m",
    "nees_mean",
    "nis_mean",
    "compass_bias_estimate_deg",
    "stretch_count",
)
MAX_RUNS = 10_000
#: A single run with this many waypoints or more gets a progress bar.
LONG_RUN_WAYPOINTS = 40


def _is_plan(document: Any) -> bool:
    """Tell whether ``document`` is a plan written by tillpath (it has waypoint features)."""
    if not isinstance(document, dict) or document.get("type") != "FeatureCollection":
        return False
    features = document.get("features")
    return isinstance(features, list) and any(
        isinstance(f, dict) and (f.get("properties") or {}).get("kind") == "waypoint"
        for f in features
    )


def load_plan(path: Path, *, interval: float | None) -> tuple[CoveragePlan, str]:
    """Read FIELD (and plan it) or PLAN; return the plan and a name for it.

    FIELD may be any import format (KML, KMZ, zipped Shapefile, GeoPackage) of one field.
    """
    from planner import PlannerError

    if path.suffix.lower() in (".kml", ".kmz", ".zip", ".gpkg"):
        spec = read_field_file(path, feature=None, what="FIELD|PLAN")
        return plan_field_spec(spec, interval_m=interval), spec.name or path.stem
    document = read_json_file(path, what="FIELD|PLAN")
    try:
        if _is_plan(document):
            from planner.export.geojson import plan_from_geojson

            name = str(
                document.get("name") or (document.get("properties") or {}).get("name") or path.stem
            )
            return plan_from_geojson(document), name
    except PlannerError as exc:
        fail(str(exc))
    return plan_field_document(document, interval_m=interval, name_fallback=path.stem)


def _value(metrics: dict[str, Any], name: str) -> float | None:
    if name == "stretch_count":
        return float(len(metrics["stretches"]))
    value = metrics.get(name)
    return None if value is None else float(value)


def summarise(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Summarise each metric over runs: median and spread (5th/95th percentile, min, max).

    The filter's consistency over the batch comes first: the mean over runs of each run's
    mean NEES (and NIS) with its 95 % χ² bounds (:mod:`navigation.consistency`).
    """
    import numpy as np

    from navigation.consistency import batch_consistency

    out: dict[str, Any] = {
        "completed_share": sum(1 for r in runs if r["completed"]) / len(runs),
    }
    for stat in ("nees", "nis"):
        means = [r[f"{stat}_mean"] for r in runs if r.get(f"{stat}_mean") is not None]
        dofs = [r[f"{stat}_dof"] for r in runs if r.get(f"{stat}_dof")]
        if means and dofs:
            out[f"{stat}_consistency"] = batch_consistency(means, dof=int(np.median(dofs)))
    for name in SUMMARY_METRICS:
        values = [v for r in runs if (v := _value(r, name)) is not None]
        if not values:
            out[name] = None
            continue
        arr = np.asarray(values)
        out[name] = {
            "median": round(float(np.median(arr)), 4),
            "p5": round(float(np.percentile(arr, 5)), 4),
            "p95": round(float(np.percentile(arr, 95)), 4),
            "min": round(float(arr.min()), 4),
            "max": round(float(arr.max()), 4),
            "n": len(values),
        }
    return out


def _round_floats(value: Any) -> Any:
    if isinstance(value, float):
        return round(value, 4) if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _round_floats(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_round_floats(v) for v in value]
    return value


def simulate_command(
    source: Annotated[
        Path,
        typer.Argument(
            metavar="FIELD|PLAN",
            help="GeoJSON field file (planned with its start, finish and interval_m) "
            "or a plan GeoJSON written by `tillpath plan`.",
        ),
    ],
    seed: Annotated[int, typer.Option("--seed", help="Random seed (first seed with --runs).")] = 0,
    gps: Annotated[
        str, typer.Option("--gps", metavar="m8n|rtk", help="GPS receiver preset.")
    ] = "m8n",
    guidance: Annotated[
        str,
        typer.Option(
            "--guidance",
            metavar="waypoint|line",
            help="waypoint (the paper's law) or line (pure pursuit along the plan).",
        ),
    ] = "waypoint",
    runs: Annotated[
        int, typer.Option("--runs", help="Monte Carlo runs over consecutive seeds.")
    ] = 1,
    plot: Annotated[
        Path | None, typer.Option("--plot", metavar="FILE.png", help="Write a PNG of the run.")
    ] = None,
    gpx: Annotated[
        Path | None,
        typer.Option("--gpx", metavar="FILE", help="Write the plan and the tracks as GPX."),
    ] = None,
    interval: Annotated[
        float | None,
        typer.Option("--interval", help="Line interval in metres, for a FIELD without interval_m."),
    ] = None,
    gps_from: Annotated[
        Path | None,
        typer.Option(
            "--gps-from",
            metavar="LOG",
            help="Fit the GPS model (CEP, correlation time, rate) from a static log "
            "(GPX, CSV or NMEA of a receiver standing still) instead of --gps.",
        ),
    ] = None,
    date: Annotated[
        str | None,
        typer.Option(
            "--date",
            metavar="YYYY-MM-DD",
            help="Date of the run, for the magnetic declination (2020–2029); default today.",
        ),
    ] = None,
) -> None:
    """Simulate the tractor driving FIELD|PLAN; print the metrics as JSON."""
    import numpy as np

    from navigation import (
        GPS_PRESETS,
        GUIDANCE_MODES,
        GuidanceParams,
        NavigationError,
        SimulationConfig,
        simulate,
    )

    if gps not in GPS_PRESETS:
        fail(f"--gps: unknown preset {gps!r}; choose one of {', '.join(GPS_PRESETS)}")
    if guidance not in GUIDANCE_MODES:
        fail(f"--guidance: unknown mode {guidance!r}; choose one of {', '.join(GUIDANCE_MODES)}")
    if seed < 0:
        fail(f"--seed: must be ≥ 0, got {seed}")
    if not (1 <= runs <= MAX_RUNS):
        fail(f"--runs: must be between 1 and {MAX_RUNS}, got {runs}")
    if plot is not None and plot.suffix.lower() != ".png":
        fail(f"--plot: the plot is a PNG; name the file *.png, got {plot.name!r}")
    plan, name = load_plan(source, interval=interval)
    run_date = dt.datetime.now(dt.UTC).date()
    if date is not None:
        try:
            run_date = dt.date.fromisoformat(date)
        except ValueError:
            fail(f"--date: expected YYYY-MM-DD, got {date!r}")
    gps_model: Any = gps
    if gps_from is not None:
        gps_model = fit_static_log(gps_from)
    config = SimulationConfig(
        gps=gps_model,
        guidance=GuidanceParams(mode=guidance),
        date=run_date,
    )
    seeds = list(range(seed, seed + runs))
    logs: dict[int, SimulationLog] = {}
    results: list[dict[str, Any]] = []
    keep_logs = plot is not None or gpx is not None
    try:
        if runs == 1 and len(plan.waypoints) < LONG_RUN_WAYPOINTS:
            log = simulate(plan, config, np.random.default_rng(seed))
            logs[seed] = log
            results.append(log.metrics.as_dict())
        elif runs == 1:
            # A long single run: a progress bar over the waypoints reached.
            with _progress() as progress:
                task = progress.add_task("driving", total=len(plan.waypoints) - 1)

                def advance(reached: int, total: int) -> None:
                    progress.update(task, completed=reached - 1)

                log = simulate(plan, config, np.random.default_rng(seed), on_waypoint=advance)
            logs[seed] = log
            results.append(log.metrics.as_dict())
        else:
            with _progress() as progress:
                task = progress.add_task("simulating", total=runs)
                for s in seeds:
                    log = simulate(plan, config, np.random.default_rng(s))
                    if s == seed:
                        logs[s] = log
                    results.append(log.metrics.as_dict())
                    progress.advance(task)
    except NavigationError as exc:
        fail(str(exc))

    scenario = {
        "name": name,
        "gps": gps if gps_from is None else _gps_dict(gps_model),
        "vehicle": getattr(logs[seed].config.vehicle, "preset", None),
        "guidance": guidance,
        "interval_m": plan.interval_m,
        "waypoints": len(plan.waypoints),
        "planned_path_length_m": round(plan.stats.path_length_m, 3),
        "planned_time_s": round(plan.stats.estimated_time_s, 1),
        "declination_deg": round(logs[seed].declination_deg, 3),
        "date": config.date.isoformat(),
    }
    shown_seed = seed
    if runs > 1:
        rms = [
            r["cross_track_rms_m"] if r["cross_track_rms_m"] is not None else math.inf
            for r in results
        ]
        shown_seed = seeds[int(np.argsort(rms)[len(rms) // 2])]
        output: dict[str, Any] = {
            "scenario": scenario,
            "runs": runs,
            "seeds": [seeds[0], seeds[-1]],
            "summary": summarise(results),
        }
        if keep_logs:
            output["shown_seed"] = shown_seed
    else:
        output = {"scenario": scenario, "seed": seed, "metrics": results[0]}
    write_output(json.dumps(_round_floats(output), indent=1), None)

    if keep_logs:
        # Runs are reproducible per seed: re-run the one to show rather than keep them all.
        log = logs.get(shown_seed) or simulate(plan, config, np.random.default_rng(shown_seed))
        if plot is not None:
            from navigation.plot import plot_simulation

            title = None
            if runs > 1:
                title = (
                    f"{guidance} guidance, {gps} GPS, seed {shown_seed} "
                    f"(median cross-track RMS of {runs} runs)"
                )
            _write_bytes(plot, plot_simulation(log, title=title), option="--plot")
        if gpx is not None:
            from navigation.export import simulation_to_gpx

            _write_bytes(
                gpx,
                simulation_to_gpx(log, name=f"{name} simulation seed {shown_seed}").encode(),
                option="--gpx",
            )


def fit_static_log(path: Path) -> Any:
    """Read a static log (any track format) and fit the GPS model to it (``--gps-from``)."""
    import numpy as np

    from app.track_fixes import TrackFormatError
    from app.tracks import parse_track
    from navigation import NavigationError
    from navigation.gps_fit import fit_gps_params
    from planner.projection import local_frame

    try:
        data = path.read_bytes()
    except OSError as exc:
        fail(f"--gps-from: cannot read {path}: {exc.strerror or exc}")
    try:
        track = parse_track(data)
    except TrackFormatError as exc:
        fail(f"--gps-from: {exc}")
    lon = np.array([f.lon for f in track.fixes])
    lat = np.array([f.lat for f in track.fixes])
    t = np.array([f.t for f in track.fixes], dtype=float) / 1e6
    frame = local_frame(float(np.mean(lon)), float(np.mean(lat)))
    x, y = frame.to_local_xy(lon, lat)
    try:
        return fit_gps_params(t - t[0], x, y, name=f"fitted:{path.name}")
    except NavigationError as exc:
        fail(f"--gps-from: {exc}")


def _gps_dict(model: Any) -> dict[str, Any]:
    return {
        "name": model.name,
        "cep_m": round(model.cep_m, 4),
        "rate_hz": round(model.rate_hz, 3),
        "correlated_sigma_m": round(model.correlated_sigma_m, 4),
        "correlation_time_s": round(model.correlation_time_s, 2),
        "white_sigma_m": round(model.white_sigma_m, 4),
    }


def _progress() -> Progress:
    """Build a progress bar on stderr that disappears when done."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeRemainingColumn

    return Progress(
        "[progress.description]{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        transient=True,
    )


def _write_bytes(path: Path, content: bytes, *, option: str) -> None:
    try:
        path.write_bytes(content)
    except OSError as exc:
        fail(f"{option}: cannot write {path}: {exc.strerror or exc}")


def register(cli: typer.Typer) -> None:
    """Add ``simulate`` to ``cli``."""
    cli.command("simulate")(simulate_command)
