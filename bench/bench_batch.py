"""``tillpath plan-batch``: the 223 real fields on 1 and 2 workers, and memory on 100,000 fields.

Speed-up: the five real field files are merged into one GeoPackage and planned at 4 m by
:func:`app.cli.batch.run_batch` on a local Dask cluster of 1, then 2, worker processes,
alternated :data:`REPEAT` times, medians compared. Budget (product.md §11): ≥ 1.7 × with 2
workers. The budget's figure is on the local cluster as ``plan-batch`` starts it, started
before the clock: its workers are forked from a process that has loaded the planner and its
kernels (:mod:`app.preload`), once per process that starts clusters. Two more figures say what that
leaves out: spawned workers, which load the planner on their first task inside the clock (as
workers that ``dask worker`` starts on other machines do on a batch's first run), and the whole
command as a user types it, cluster start included.

Memory: ``tillpath plan-batch`` (a real process, 2 workers) on generated GeoPackages of 10,000
and 100,000 small fields; the peak memory of the command and its processes (scheduler and
nannies in the command; the forkserver and the workers) is sampled every 0.1 s, as the sum of
resident sets (RSS, which counts pages shared by forked processes once per process) and as the
sum of proportional sets (PSS, which shares them out). Flat memory: the peak for 100,000 close to
that for 10,000.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import psutil
import pyogrio.raw
import shapely

from app.cli.batch import FIELDS_PER_TASK, run_batch
from app.local_cluster import start_local_cluster
from app.testing import tillpath_command
from bench.common import small_quadrilaterals

ROOT = Path(__file__).resolve().parent.parent
FIELDS = ROOT.parent / "shared" / "fields"
BUDGET_SPEEDUP = 1.7
#: Alternations of the 1- and 2-worker runs: one run on a shared 2-core machine can be 10 % off.
REPEAT = 3
#: Field counts of the memory runs; ``TILLPATH_BENCH_MEMORY_SIZES=10000`` (comma-separated,
#: empty for none) runs fewer, for a partial run (the 100,000-field run takes ~20 minutes).
MEMORY_SIZES = tuple(
    int(n)
    for n in os.environ.get("TILLPATH_BENCH_MEMORY_SIZES", "10000,100000").split(",")
    if n.strip()
)


def write_gpkg(path: Path, geometries: list[bytes], ids: list[str]) -> None:
    pyogrio.raw.write(
        str(path),
        geometry=np.array(geometries, dtype=object),
        field_data=[np.array(ids, dtype=object)],
        fields=["id"],
        driver="GPKG",
        geometry_type="Polygon",
        crs="EPSG:4326",
    )


def real_fields(path: Path) -> int:
    geometries, ids = [], []
    for name in sorted(FIELDS.glob("*.geojson")):
        for feature in json.loads(name.read_text())["features"]:
            if feature["geometry"]["type"] in ("Polygon", "MultiPolygon"):
                geometries.append(shapely.to_wkb(shapely.geometry.shape(feature["geometry"])))
                ids.append(f"{name.stem}/{feature['properties'].get('id', len(ids))}")
    write_gpkg(path, geometries, ids)
    return len(ids)


def generated_fields(path: Path, count: int) -> None:
    """``count`` random quadrilaterals of 0.1–0.6 ha on a grid (plans of a few lines each)."""
    geometries = [shapely.to_wkb(q) for q in small_quadrilaterals(count)]
    write_gpkg(path, geometries, [f"g{i}" for i in range(count)])


def timed_batch(fields: Path, out: Path, workers: int, *, forked: bool) -> tuple[float, int, int]:
    """Seconds ``run_batch`` takes on a started cluster of ``workers``, rows, failures.

    :func:`start_local_cluster` returns once its workers have registered with the scheduler;
    ``forked=False`` spawns them instead (they load the planner on their first task).
    """
    cluster = start_local_cluster(workers, forked=forked)
    try:
        started = time.perf_counter()
        rows, failed, _ = run_batch(
            fields,
            out,
            options={"interval_m": 4.0},
            scheduler=cluster.scheduler_address,
            workers=workers,
            per_task=FIELDS_PER_TASK,
            show_progress=False,
        )
        return time.perf_counter() - started, rows, failed
    finally:
        cluster.close()


def timed_command(fields: Path, out: Path, workers: int) -> float:
    """Seconds of the whole ``tillpath plan-batch`` command, as a user runs it."""
    command = [*tillpath_command(), "plan-batch", str(fields), "-o", str(out)]
    command += ["--interval", "4", "--workers", str(workers)]
    started = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - started


def alternated(measure: Callable[[int, int], float]) -> tuple[float, float]:
    """Median seconds of ``measure(workers, run)`` for 1 and 2 workers, alternated."""
    one, two = [], []
    for run in range(REPEAT):
        one.append(measure(1, run))
        two.append(measure(2, run))
    return statistics.median(one), statistics.median(two)


def peak_memory(fields: Path, out: Path) -> tuple[float, float, float, float]:
    """Run ``tillpath plan-batch``; return (seconds, peak MiB of the tree as RSS and as PSS,
    peak MiB of the command's RSS)."""
    command = [*tillpath_command(), "plan-batch", str(fields), "-o", str(out)]
    command += ["--interval", "10", "--workers", "2", "--fields-per-task", "64"]
    started = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    main = psutil.Process(process.pid)
    peak_rss = peak_pss = peak_main = 0
    while process.poll() is None:
        try:
            tree = [main, *main.children(recursive=True)]
            memory = [p.memory_full_info() for p in tree]
            peak_rss = max(peak_rss, sum(m.rss for m in memory))
            peak_pss = max(peak_pss, sum(m.pss for m in memory))
            peak_main = max(peak_main, memory[0].rss)
        except psutil.Error:
            pass
        time.sleep(0.1)
    if process.returncode != 0:
        raise RuntimeError(f"plan-batch failed with {process.returncode}")
    return time.perf_counter() - started, peak_rss / 2**20, peak_pss / 2**20, peak_main / 2**20


def run() -> str:
    """Measure and return the Markdown section."""
    with tempfile.TemporaryDirectory(prefix="tillpath-bench-") as tmp:
        real = Path(tmp) / "real.gpkg"
        count = real_fields(real)
        rows: dict[int, tuple[int, int]] = {}

        def forked(workers: int, run: int) -> float:
            seconds, planned, failed = timed_batch(
                real, Path(tmp) / f"f{workers}-{run}.gpkg", workers, forked=True
            )
            rows[workers] = (planned, failed)
            return seconds

        def spawned(workers: int, run: int) -> float:
            out = Path(tmp) / f"s{workers}-{run}.gpkg"
            return timed_batch(real, out, workers, forked=False)[0]

        def whole(workers: int, run: int) -> float:
            return timed_command(real, Path(tmp) / f"c{workers}-{run}.gpkg", workers)

        one, two = alternated(forked)
        one_spawned, two_spawned = alternated(spawned)
        one_command, two_command = alternated(whole)
        memory = []
        for size in MEMORY_SIZES:
            generated = Path(tmp) / f"gen{size}.gpkg"
            generated_fields(generated, size)
            memory.append((size, *peak_memory(generated, Path(tmp) / f"out{size}.gpkg")))
    speedup = one / two
    verdict = "within" if speedup >= BUDGET_SPEEDUP else "UNDER"
    (rows1, failed1), (rows2, failed2) = rows[1], rows[2]
    memory_rows = [
        f"| {size:,} | {seconds:.0f} | {size / seconds:.0f} | {rss:.0f} | {pss:.0f} | {main:.0f} |"
        for size, seconds, rss, pss, main in memory
    ]
    return "\n".join(
        [
            "## `tillpath plan-batch`\n",
            f"The {count} real fields of `../shared/fields` in one GeoPackage, at 4 m, "
            f"{FIELDS_PER_TASK} fields per task (the command's default), on a local Dask "
            "cluster as `plan-batch` starts it, started before the clock (its workers forked "
            "from a process that has loaded the planner and its kernels once, for every cluster "
            "this process starts); "
            f"1 and 2 workers alternated {REPEAT} times, medians:",
            "",
            "| workers | seconds | fields/s | fields/s per worker | failed |",
            "| ---: | ---: | ---: | ---: | ---: |",
            f"| 1 | {one:.2f} | {rows1 / one:.1f} | {rows1 / one:.1f} | {failed1} |",
            f"| 2 | {two:.2f} | {rows2 / two:.1f} | {rows2 / two / 2:.1f} | {failed2} |",
            "",
            f"Budget: 2 workers vs 1 ≥ {BUDGET_SPEEDUP:g} ×: {speedup:.2f} ×, {verdict} budget.",
            "",
            "What the budget's figure leaves out (no budget; same alternation and medians):",
            "",
            f"- Spawned workers, which load the planner and its kernels on their first task, "
            f"inside the clock (as workers started by `dask worker` do on a batch's first "
            f"run): 1 worker {one_spawned:.2f} s, 2 workers {two_spawned:.2f} s, "
            f"{one_spawned / two_spawned:.2f} ×.",
            f"- The whole command, `tillpath plan-batch FIELDS -o OUT.gpkg --interval 4 "
            f"--workers N`, interpreter, cluster start and the planner's load included: "
            f"1 worker {one_command:.2f} s, 2 workers {two_command:.2f} s, "
            f"{one_command / two_command:.2f} ×.",
            "",
            "Memory of `tillpath plan-batch FIELDS -o OUT.gpkg --interval 10 --workers 2` on "
            "generated fields (random quadrilaterals of 0.1–0.6 ha), peak sampled every 0.1 s "
            "(whole run, cluster start included). RSS counts the pages the forked workers "
            "share with their forkserver once per process; PSS shares them out:",
            "",
            "| fields | seconds | fields/s | peak MiB, tree RSS | peak MiB, tree PSS "
            "| peak MiB, command RSS |",
            "| ---: | ---: | ---: | ---: | ---: | ---: |",
            *memory_rows,
            "",
        ]
    )


if __name__ == "__main__":
    print(run())
