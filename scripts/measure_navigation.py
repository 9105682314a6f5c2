"""Measure every navigation figure quoted in docs/simulation.md and the README.

    .venv/bin/python scripts/measure_navigation.py [--seeds 50] [-o figures.json]
    .venv/bin/python scripts/measure_navigation.py --speed
    .venv/bin/python scripts/measure_navigation.py --run-cost
    .venv/bin/python scripts/measure_navigation.py --spiral --seeds 10

Seeded Monte Carlo over seeds 0 … N-1 (one process, no parallelism: the machine is shared),
on the paper's field (``../shared/fields/paper_ketewel.geojson``) with its start and finish,
dated 2021-02-01 (the paper's trial; WMM2020), driven by the default vehicle
(``hand_tractor``). Prints a JSON document of medians with 5–95 % ranges.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from navigation import GuidanceParams, SimulationConfig, score_track, simulate
from navigation.consistency import batch_consistency
from navigation.route import build_route, point_segment
from navigation.types import FilterParams, GpsParams
from planner import parse_field_geojson, plan_coverage
from planner.projection import field_frame
from planner.types import CoveragePlan, PathSegment, Waypoint

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # for bench.bench_runs's track (``--run-cost``)
PAPER_FIELD = ROOT.parent / "shared" / "fields" / "paper_ketewel.geojson"
RWANDA_FIELDS = ROOT.parent / "shared" / "fields" / "rwanda_2021.geojson"
#: Real fields driven as spirals by ``--spiral``: two non-convex fields of rwanda_2021, 0.66 and
#: 0.88 ha (each run simulates about an hour of driving).
SPIRAL_FIELDS = ("rwanda_2021-11", "rwanda_2021-1")
DATE = dt.date(2021, 2, 1)
#: Heading of the paper's tillage rows on its field [deg].
PAPER_ROWS_DEG = 1.0


def paper_plan(interval_m: float) -> CoveragePlan:
    """Plan the paper field at ``interval_m`` with its start and finish, along the paper's rows.

    The heading is fixed at 1° (the paper's rows, four lines at 4 m): the coverage-first search
    of R5 now adds a fifth line 0.2 m from the fourth, which is not the scenario the paper ran.
    """
    spec = parse_field_geojson(json.loads(PAPER_FIELD.read_text(encoding="utf-8")))
    return plan_coverage(
        spec.field_lonlat,
        interval_m=interval_m,
        start_lonlat=spec.start_lonlat,
        finish_lonlat=spec.finish_lonlat,
        angle_deg=PAPER_ROWS_DEG,
    )


def pulled_back(plan: CoveragePlan, pull_m: float) -> CoveragePlan:
    """Apply the paper's Algorithm 1: every line end moved ``pull_m`` inward along its line.

    The paper's route τ = [p_s, p_0 … p_n, p_f] holds the line ends only, so the plan's turn
    points are dropped: kept, they stayed at the lines' old ends and sent the tractor there
    and back (a 94.8 m route instead of 69.6 m once the planner sampled its turns).
    """
    frame = field_frame(plan.field_lonlat)
    wps = list(plan.waypoints)
    out: list[Waypoint] = []
    for i, w in enumerate(wps):
        if w.role == "turn":
            continue
        w = dataclasses.replace(w, seq=len(out))
        if w.role in ("line_start", "line_end"):
            other = wps[i + 1] if w.role == "line_start" else wps[i - 1]
            x, y = frame.to_local_xy([w.lon, other.lon], [w.lat, other.lat])
            dx, dy = x[1] - x[0], y[1] - y[0]
            d = math.hypot(dx, dy)
            s = min(pull_m, 0.45 * d) / d
            lon, lat = frame.to_lonlat_xy([x[0] + s * dx], [y[0] + s * dy])
            w = dataclasses.replace(w, lon=float(lon[0]), lat=float(lat[0]))
        out.append(w)
    segments = []
    for a, b in zip(out[:-1], out[1:], strict=True):
        is_line = a.role == "line_start" and b.role == "line_end" and a.line == b.line
        kind = (
            "line"
            if is_line
            else ("transit" if a.role == "start" or b.role == "finish" else "turn")
        )
        segments.append(
            PathSegment(kind, a.line if is_line else None, ((a.lon, a.lat), (b.lon, b.lat)))  # type: ignore[arg-type]
        )
    return dataclasses.replace(plan, waypoints=tuple(out), segments=tuple(segments))


def route_length_m(plan: CoveragePlan) -> float:
    """Return the plan's path length [m]."""
    route = build_route(plan)
    return float(route.lengths_m.sum())


def nearest_line_rms(plan: CoveragePlan, log: Any) -> float | None:
    """Return the old metric: each on-line fix against whichever tillage line is nearest."""
    route = build_route(plan, log.frame)
    lines = route.is_line
    d, _ = point_segment(
        log.true_x_m[:, None],
        log.true_y_m[:, None],
        route.ax[None, lines],
        route.ay[None, lines],
        route.bx[None, lines],
        route.by[None, lines],
    )
    nearest = d.min(axis=1)
    # The same fixes the new metric counts as on a line.
    from navigation.metrics import cross_track_errors
    from navigation.route import match_by_leg

    piece = match_by_leg(route, log.true_x_m, log.true_y_m, log.target)
    on = ~np.isnan(cross_track_errors(route, log.true_x_m, log.true_y_m, piece)[0])
    return float(np.sqrt(np.mean(nearest[on] ** 2))) if on.any() else None


def summary(values: list[float | None]) -> dict[str, float] | None:
    """Return median and 5–95 % range."""
    arr = np.array([v for v in values if v is not None], dtype=float)
    if not len(arr):
        return None
    return {
        "median": round(float(np.median(arr)), 3),
        "p5": round(float(np.percentile(arr, 5)), 3),
        "p95": round(float(np.percentile(arr, 95)), 3),
        "n": len(arr),
    }


FIGURES = (
    "time_s",
    "distance_m",
    "cross_track_rms_m",
    "cross_track_p95_m",
    "cross_track_max_m",
    "turn_cross_track_rms_m",
    "turn_cross_track_max_m",
    "line_waypoint_error_max_m",
    "line_waypoint_error_estimate_max_m",
    "waypoint_error_max_m",
    "waypoint_error_estimate_max_m",
    "waypoint_error_estimate_mean_m",
    "coverage_ratio",
    "filter_rms_m",
    "gps_rms_m",
    "compass_bias_estimate_deg",
)


def batch(
    plan: CoveragePlan, seeds: range, config: SimulationConfig, *, extras: bool = False
) -> dict[str, Any]:
    """Simulate ``plan`` over ``seeds`` and summarise the figures."""
    runs = []
    extra: dict[str, list[float | None]] = {
        "nearest_line_rms_m": [],
        "receiver_coverage": [],
        "receiver_xte_rms_m": [],
    }
    for s in seeds:
        log = simulate(plan, config, np.random.default_rng(s))
        runs.append(log.metrics)
        if extras:
            extra["nearest_line_rms_m"].append(nearest_line_rms(plan, log))
            # What a logger on the tractor records is the receiver's fixes: scored as a run.
            lon, lat = log.lonlat("gps")
            as_run = score_track(plan, log.gps_time_s, lon, lat)
            extra["receiver_coverage"].append(as_run.coverage_ratio)
            extra["receiver_xte_rms_m"].append(as_run.cross_track_rms_m)
    out: dict[str, Any] = {
        "runs": len(runs),
        "completed_share": sum(m.completed for m in runs) / len(runs),
        "nees": batch_consistency([m.nees_mean for m in runs if m.nees_mean is not None], dof=2),
        "nis_mean": summary([m.nis_mean for m in runs]),
        "nis_dof": runs[0].nis_dof,
    }
    for name in FIGURES:
        out[name] = summary([getattr(m, name) for m in runs])
    for name, values in extra.items():
        if values:
            out[name] = summary(values)
    out["_per_seed_xte_rms"] = [m.cross_track_rms_m for m in runs]
    return out


def speed() -> dict[str, Any]:
    """Time 9 seeded runs per guidance mode on the paper field: wall clock and CPU."""
    plan = paper_plan(4.0)
    out: dict[str, Any] = {}
    for mode in ("waypoint", "line"):
        rows = []
        for s in range(9):
            wall0, cpu0 = time.perf_counter(), time.process_time()
            config = SimulationConfig(date=DATE, guidance=GuidanceParams(mode=mode))
            log = simulate(plan, config, np.random.default_rng(s))
            rows.append(
                (log.metrics.time_s, time.perf_counter() - wall0, time.process_time() - cpu0)
            )
        sim, wall, cpu = (np.array(c) for c in zip(*rows, strict=True))
        out[mode] = {
            "simulated_s": float(np.median(sim)),
            "cpu_s": round(float(np.median(cpu)), 4),
            "x_real_time_cpu": round(float(np.median(sim / cpu))),
            "x_real_time_wall": round(float(np.median(sim / wall))),
        }
    return out


def spiral(seeds: range) -> dict[str, Any]:
    """Drive spirals at 4 m with RTK against their plans: distance, coverage and time.

    The paper's field (with its start and finish) and :data:`SPIRAL_FIELDS`, for the default
    ``hand_tractor``, in both guidance modes: RTK, so that the receiver's wander does not hide
    how the rounds, their corner loops and the joins are driven.
    """
    spec = parse_field_geojson(json.loads(PAPER_FIELD.read_text(encoding="utf-8")))
    plans = {
        "paper_ketewel": plan_coverage(
            spec.field_lonlat,
            interval_m=4.0,
            start_lonlat=spec.start_lonlat,
            finish_lonlat=spec.finish_lonlat,
            pattern="spiral",
        )
    }
    collection = json.loads(RWANDA_FIELDS.read_text(encoding="utf-8"))
    for feature in collection["features"]:
        if feature["properties"]["id"] in SPIRAL_FIELDS:
            field = parse_field_geojson({**feature, "properties": {}}).field_lonlat
            plans[feature["properties"]["id"]] = plan_coverage(
                field, interval_m=4.0, pattern="spiral"
            )
    out: dict[str, Any] = {}
    for name, plan in plans.items():
        stats = plan.stats
        case: dict[str, Any] = {
            "planned": {
                "path_length_m": stats.path_length_m,
                "estimated_time_s": stats.estimated_time_s,
                "coverage_pct": round(100.0 * stats.coverage_ratio, 3),
            }
        }
        for mode in ("waypoint", "line"):
            config = SimulationConfig(date=DATE, gps="rtk", guidance=GuidanceParams(mode=mode))
            runs = [simulate(plan, config, np.random.default_rng(s)).metrics for s in seeds]
            case[mode] = {
                "completed_share": sum(m.completed for m in runs) / len(runs),
                "distance_m": summary([m.distance_m for m in runs]),
                # In per cent: the plan's and the run's differ by tenths of a point.
                "coverage_pct": summary([100.0 * m.coverage_ratio for m in runs]),
                "time_s": summary([m.time_s for m in runs]),
            }
        out[name] = case
        print(f"done {name}", file=sys.stderr)
    return out


def run_cost() -> dict[str, float]:
    """CPU time to score a 6-hour 10 Hz log and trace its missed ground (bench_runs' track)."""
    from app.schemas import PlanCreate
    from app.services import coverage_plan_from_row, plan_field
    from bench.bench_runs import field_geojson, six_hour_track
    from navigation.coverage import missed_ground
    from navigation.route import match_monotone

    row = plan_field(PlanCreate(field=field_geojson(), interval_m=1.0))
    plan = coverage_plan_from_row(row)
    fixes = six_hour_track(row)
    lon = np.array([f.lon for f in fixes])
    lat = np.array([f.lat for f in fixes])
    frame = field_frame(plan.field_lonlat)
    x, y = (np.asarray(v) for v in frame.to_local_xy(lon, lat))
    out: dict[str, float] = {"fixes": float(len(fixes))}
    c = time.process_time()
    match_monotone(build_route(plan, frame), x, y)
    out["match_cpu_s"] = round(time.process_time() - c, 3)
    c = time.process_time()
    score_track(plan, np.arange(len(x)) * 0.1, lon, lat)
    out["score_cpu_s"] = round(time.process_time() - c, 3)
    c = time.process_time()
    missed_ground(frame, plan, x, y)
    out["missed_ground_cpu_s"] = round(time.process_time() - c, 3)
    return out


def main() -> int:
    """Measure and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=50)
    parser.add_argument("--speed", action="store_true", help="only time the simulator")
    parser.add_argument("--run-cost", action="store_true", help="only time scoring a 6 h log")
    parser.add_argument(
        "--spiral", action="store_true", help="only the spirals driven with RTK against plan"
    )
    parser.add_argument("-o", "--output", type=Path)
    args = parser.parse_args()
    if args.speed:
        print(json.dumps(speed(), indent=1))
        return 0
    if args.run_cost:
        print(json.dumps(run_cost(), indent=1))
        return 0
    if args.spiral:
        text = json.dumps(spiral(range(args.seeds)), indent=1)
        if args.output:
            args.output.write_text(text + "\n")
        print(text)
        return 0
    seeds = range(args.seeds)
    started = time.process_time()
    plan4 = paper_plan(4.0)
    base = SimulationConfig(date=DATE)
    result: dict[str, Any] = {
        "seeds": [0, args.seeds - 1],
        "date": DATE.isoformat(),
        "paper_4m": {"route_length_m": round(route_length_m(plan4), 2), "cases": {}},
    }
    cases = result["paper_4m"]["cases"]
    for gps in ("m8n", "rtk"):
        for mode in ("waypoint", "line"):
            config = dataclasses.replace(base, gps=gps, guidance=GuidanceParams(mode=mode))
            cases[f"{gps}-{mode}"] = batch(plan4, seeds, config, extras=gps == "m8n")
            print(f"done {gps}-{mode}", file=sys.stderr)
    a = np.array(cases["m8n-line"].pop("_per_seed_xte_rms"), dtype=float)
    b = np.array(cases["m8n-waypoint"].pop("_per_seed_xte_rms"), dtype=float)
    for case in cases.values():
        case.pop("_per_seed_xte_rms", None)
    diff = a - b
    result["paper_4m"]["m8n_line_minus_waypoint_xte_rms_m"] = {
        "mean": round(float(diff.mean()), 4),
        "std": round(float(diff.std(ddof=1)), 4),
        "ci95": round(float(1.96 * diff.std(ddof=1) / math.sqrt(len(diff))), 4),
        "n": len(diff),
    }
    # The filter that treats the receiver's wander as white noise (before this issue).
    white = dataclasses.replace(base, gps="m8n", kalman=FilterParams(augmented=False))
    runs = [simulate(plan4, white, np.random.default_rng(s)).metrics for s in seeds]
    result["paper_4m"]["white_noise_filter_m8n_nees"] = batch_consistency(
        [m.nees_mean for m in runs if m.nees_mean is not None], dof=2
    )
    # The correlation time is an assumption: how much it moves coverage.
    result["paper_4m"]["m8n_tau_sensitivity"] = {}
    for tau in (30.0, 60.0, 120.0):
        from navigation.sensors import gps_params

        m8n = gps_params("m8n")
        model = GpsParams(
            f"m8n-tau{tau:g}",
            rate_hz=m8n.rate_hz,
            correlated_sigma_m=m8n.correlated_sigma_m,
            correlation_time_s=tau,
            white_sigma_m=m8n.white_sigma_m,
        )
        runs = [
            simulate(plan4, dataclasses.replace(base, gps=model), np.random.default_rng(s)).metrics
            for s in seeds
        ]
        result["paper_4m"]["m8n_tau_sensitivity"][f"{tau:g}"] = {
            "coverage_ratio": summary([m.coverage_ratio for m in runs]),
            "cross_track_rms_m": summary([m.cross_track_rms_m for m in runs]),
        }
    print("done tau", file=sys.stderr)
    # The paper's Algorithm 1 pulls every line end in by d_x: the route the 132 s trial drove.
    pulled = pulled_back(plan4, 4.0)
    result["paper_4m_pulled_back"] = {
        "route_length_m": round(route_length_m(pulled), 2),
        "m8n-waypoint": batch(pulled, seeds, dataclasses.replace(base, gps="m8n")),
    }
    result["paper_4m_pulled_back"]["m8n-waypoint"].pop("_per_seed_xte_rms")
    print("done pull-back", file=sys.stderr)
    plan1 = paper_plan(1.0)
    one = batch(plan1, seeds, dataclasses.replace(base, gps="m8n"), extras=True)
    one.pop("_per_seed_xte_rms")
    result["paper_1m"] = {"route_length_m": round(route_length_m(plan1), 2), "m8n-waypoint": one}
    result["cpu_s"] = round(time.process_time() - started, 1)
    text = json.dumps(result, indent=1)
    if args.output:
        args.output.write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
