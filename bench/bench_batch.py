"""``tillpath plan-batch``: the 223 real fields on 1 and 2 workers, and memory on 100,000 fields.

Speed-up: the five real field files are merged into one GeoPackage and planned at 4 m by
:func:`app.cli.batch.run_batch` on a local Dask cluster of 1, then 2, worker processes (the
cluster is started, its workers' kernels loaded, before the clock starts). Budget
(product.md §11): ≥ 1.7 × with 2 workers.

Memory: ``tillpath plan-batch`` (a real process, 2 workers) on generated GeoPackages of 10,000
and 100,000 small fields; the peak resident memory of the command and its worker processes
together is sampled every 0.1 s. Flat memory: the peak for 100,000 close to that for 10,000.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import psutil
import pyogrio.raw
import shapely

from app.cli.batch import FIELDS_PER_TASK, run_batch
from app.jobs.engine import start_local_cluster
from app.testing import tillpath_command
from bench.common import small_quadrilaterals

if TYPE_CHECKING:
    from distributed import LocalCluster

ROOT = Path(__file__).resolve().parent.parent
FIELDS = ROOT.parent / "shared" / "fields"
BUDGET_SPEEDUP = 1.7
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


def started_cluster(workers: int, *, kernels_loaded: bool) -> LocalCluster:
    """Start a local cluster of ``workers``; with ``kernels_loaded``, wait until each worker
    has loaded the planner's compiled kernels too.

    ``tillpath plan-batch`` pays the load on every run (``numba`` and the disk cache, about
    0.5 s of a core per worker, :mod:`app.jobs.kernels_plugin`), so the budget's figure keeps
    it inside the clock; the figure without it shows how planning itself scales.
    """
    from distributed import Client

    from planner.warm_up import warm_up

    cluster = start_local_cluster(workers)
    if kernels_loaded:
        with Client(cluster.scheduler_address, set_as_default=False) as client:
            client.wait_for_workers(workers)
            client.run(warm_up)
    return cluster


def timed_batch(
    fields: Path, out: Path, workers: int, *, kernels_loaded: bool = False
) -> tuple[float, int, int]:
    """Seconds ``run_batch`` takes on a started cluster of ``workers``, rows, failures."""
    cluster = started_cluster(workers, kernels_loaded=kernels_loaded)
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


def peak_rss(fields: Path, out: Path) -> tuple[float, float, float]:
    """Run ``tillpath plan-batch``; return (seconds, peak MiB of the tree, peak MiB of main)."""
    command = [*tillpath_command(), "plan-batch", str(fields), "-o", str(out)]
    command += ["--interval", "10", "--workers", "2", "--fields-per-task", "64"]
    started = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    main = psutil.Process(process.pid)
    peak_tree = peak_main = 0
    while process.poll() is None:
        try:
            tree = [main, *main.children(recursive=True)]
            rss = [p.memory_info().rss for p in tree]
            peak_tree = max(peak_tree, sum(rss))
            peak_main = max(peak_main, rss[0])
        except psutil.Error:
            pass
        time.sleep(0.1)
    if process.returncode != 0:
        raise RuntimeError(f"plan-batch failed with {process.returncode}")
    return time.perf_counter() - started, peak_tree / 2**20, peak_main / 2**20


def run() -> str:
    """Measure and return the Markdown section."""
    with tempfile.TemporaryDirectory(prefix="tillpath-bench-") as tmp:
        real = Path(tmp) / "real.gpkg"
        count = real_fields(real)
        one, rows1, failed1 = timed_batch(real, Path(tmp) / "one.gpkg", 1)
        two, rows2, failed2 = timed_batch(real, Path(tmp) / "two.gpkg", 2)
        one_loaded, _, _ = timed_batch(real, Path(tmp) / "one-l.gpkg", 1, kernels_loaded=True)
        two_loaded, _, _ = timed_batch(real, Path(tmp) / "two-l.gpkg", 2, kernels_loaded=True)
        memory = []
        for size in MEMORY_SIZES:
            generated = Path(tmp) / f"gen{size}.gpkg"
            generated_fields(generated, size)
            memory.append((size, *peak_rss(generated, Path(tmp) / f"out{size}.gpkg")))
    speedup = one / two
    verdict = "within" if speedup >= BUDGET_SPEEDUP else "UNDER"
    memory_rows = [
        f"| {size:,} | {seconds:.0f} | {size / seconds:.0f} | {tree:.0f} | {main:.0f} |"
        for size, seconds, tree, main in memory
    ]
    return "\n".join(
        [
            "## `tillpath plan-batch`\n",
            f"The {count} real fields of `../shared/fields` in one GeoPackage, at 4 m, on a "
            "local Dask cluster (started before the clock; its workers load the planner's "
            "kernels inside it, as every `plan-batch` run does), "
            f"{FIELDS_PER_TASK} fields per task (the command's default):",
            "",
            "| workers | seconds | fields/s | fields/s per worker | failed |",
            "| ---: | ---: | ---: | ---: | ---: |",
            f"| 1 | {one:.2f} | {rows1 / one:.1f} | {rows1 / one:.1f} | {failed1} |",
            f"| 2 | {two:.2f} | {rows2 / two:.1f} | {rows2 / two / 2:.1f} | {failed2} |",
            "",
            f"Budget: 2 workers vs 1 ≥ {BUDGET_SPEEDUP:g} ×: {speedup:.2f} ×, {verdict} budget.",
            "",
            "The same with the workers' kernels loaded before the clock (how planning itself "
            f"scales; not the budget's figure): 1 worker {one_loaded:.2f} s, 2 workers "
            f"{two_loaded:.2f} s, {one_loaded / two_loaded:.2f} ×.",
            "",
            "Memory of `tillpath plan-batch FIELDS -o OUT.gpkg --interval 10 --workers 2` on "
            "generated fields (random quadrilaterals of 0.1–0.6 ha), peak resident memory "
            "sampled every 0.1 s (whole run, cluster start included):",
            "",
            "| fields | seconds | fields/s | peak MiB, command + workers | peak MiB, command |",
            "| ---: | ---: | ---: | ---: | ---: |",
            *memory_rows,
            "",
        ]
    )


if __name__ == "__main__":
    print(run())
