"""Coverage and path length per real field, this tree against another checkout (R5 review).

``python -m bench.compare_trees OTHER_TREE [VEHICLE ...]`` plans the 223 real fields at 4 m
(:mod:`bench.bench_fields`) in this tree and, in a child process with its own venv, in
``OTHER_TREE`` (e.g. ``/work/main``), each importing its own ``planner``; then lists per field
the coverage ratio [%], path length [m] and heading of both, and flags where this tree covers
more than 0.2 pp less (R5). ``--json`` prints this tree's figures only (the child's mode).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

DEFAULT_VEHICLES = ("hand_tractor", "small_tractor")


def figures(vehicles: list[str]) -> dict[str, list[float]]:
    """``"vehicle field_id" -> [coverage ratio, path length m, heading deg]`` in this tree."""
    from bench.bench_fields import DATASETS, INTERVAL_M, load
    from planner import plan_coverage

    out: dict[str, list[float]] = {}
    for vehicle in vehicles:
        for name in DATASETS:
            for field_id, field in load(name):
                try:
                    plan = plan_coverage(field, interval_m=INTERVAL_M, vehicle=vehicle)
                except ValueError:
                    continue
                out[f"{vehicle} {field_id}"] = [
                    plan.stats.coverage_ratio,
                    plan.stats.path_length_m,
                    plan.stats.angle_deg,
                ]
    return out


def main() -> None:
    args = sys.argv[1:]
    if args and args[0] == "--json":
        print(json.dumps(figures(args[1:] or list(DEFAULT_VEHICLES))))
        return
    other = Path(args[0]).resolve()
    vehicles = args[1:] or list(DEFAULT_VEHICLES)
    child = subprocess.run(
        [
            str(other / ".venv" / "bin" / "python"),
            "-c",
            # This script, run with the other tree's venv and from its root (its planner).
            "import runpy, sys; sys.argv = sys.argv[1:]; "
            "runpy.run_path(sys.argv[0], run_name='__main__')",
            __file__,
            "--json",
            *vehicles,
        ],
        cwd=other,
        capture_output=True,
        text=True,
        check=True,
    )
    theirs = json.loads(child.stdout)
    ours = figures(vehicles)
    worse = 0
    gains_pp: dict[str, list[float]] = {}
    longer_pct: dict[str, list[float]] = {}
    print(
        f"{'vehicle field':40s} {'other %':>9s} {'this %':>9s} {'d pp':>7s} "
        f"{'other m':>9s} {'this m':>9s} {'d %':>7s} {'other°':>8s} {'this°':>8s}"
    )
    for key in sorted(set(ours) | set(theirs)):
        if key not in ours or key not in theirs:
            print(f"{key:40s} planned in one tree only")
            continue
        (c0, p0, h0), (c1, p1, h1) = theirs[key], ours[key]
        d_pp = (c1 - c0) * 100.0
        flag = "  << R5" if d_pp < -0.2 else ""
        worse += d_pp < -0.2
        vehicle = key.split(" ", 1)[0]
        gains_pp.setdefault(vehicle, []).append(d_pp)
        longer_pct.setdefault(vehicle, []).append((p1 / p0 - 1) * 100.0)
        print(
            f"{key:40s} {c0 * 100:9.4f} {c1 * 100:9.4f} {d_pp:+7.3f} {p0:9.1f} {p1:9.1f} "
            f"{(p1 / p0 - 1) * 100:+7.2f} {h0:8.2f} {h1:8.2f}{flag}"
        )
    print(f"{len(ours)} plans; this tree more than 0.2 pp below the other on {worse}")
    for vehicle, gains in gains_pp.items():
        longer = longer_pct[vehicle]
        print(
            f"{vehicle}: coverage {sum(gains) / len(gains):+.3f} pp on average "
            f"(more than 0.2 pp higher on {sum(g > 0.2 for g in gains)}, lower on "
            f"{sum(g < -0.2 for g in gains)}; from {min(gains):+.2f} to {max(gains):+.2f} pp); "
            f"path {sum(longer) / len(longer):+.2f} % on average"
        )


if __name__ == "__main__":
    main()
