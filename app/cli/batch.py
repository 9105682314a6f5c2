"""``tillpath plan-batch``: plan every field of a file on Dask (product.md §10, §13).

The file is read in chunks (:mod:`app.cli.batch_read`), each chunk split into small tasks
(:func:`app.cli.batch_tasks.plan_records`) that run on a local cluster of worker processes or
on the cluster ``--scheduler`` names; at most a few tasks per worker are in flight, and the
rows are written to the GeoPackage as they come back, so memory stays flat however many
fields the file holds. OUT has two layers: ``fields`` (one row of figures per field, with the
error of a field that could not be planned) and ``paths`` (the driven path of each planned
field).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Final

import typer

from app.cli.common import fail
from app.cli.plan import ObjectiveChoice

if TYPE_CHECKING:
    from app.cli.batch_read import FieldRecord
    from app.cli.batch_tasks import FieldResult

#: Fields read from the file at a time.
READ_CHUNK: Final = 1000
#: Rows buffered before they are appended to OUT.
WRITE_EVERY: Final = 1000
#: Tasks in flight per worker (enough to keep each busy while results are written).
IN_FLIGHT_PER_WORKER: Final = 4
#: Fields per Dask task by default: enough that the scheduler's own work per task (in this
#: process, on the cores that plan) stays small beside the planning; on the 223 real fields,
#: 2 workers against 1 gave 1.54-1.59x with 4 and 1.68-1.74x with 8 (bench.bench_batch).
FIELDS_PER_TASK: Final = 8

FIELD_COLUMNS: Final = (
    "field_index",
    "field_id",
    "name",
    "area_m2",
    "line_count",
    "path_length_m",
    "coverage_ratio",
    "estimated_time_s",
    "planning_ms",
    "error",
)


class GeoPackageWriter:
    """Append ``plan-batch`` rows to the ``fields`` and ``paths`` layers of a GeoPackage."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._rows: list[FieldResult] = []
        self._started = {"fields": False, "paths": False}
        self.written = 0
        self.failed = 0

    def add(self, rows: list[FieldResult]) -> None:
        """Buffer ``rows``; write when :data:`WRITE_EVERY` are waiting."""
        self._rows.extend(rows)
        self.failed += sum(1 for r in rows if r.error is not None)
        if len(self._rows) >= WRITE_EVERY:
            self.flush()

    def _append(self, layer: str, geometry: list[bytes | None], columns: dict[str, Any]) -> None:
        import numpy as np
        import pyogrio.raw

        pyogrio.raw.write(
            str(self.path),
            geometry=np.array(geometry, dtype=object),
            field_data=list(columns.values()),
            fields=list(columns),
            layer=layer,
            driver="GPKG",
            geometry_type="Polygon" if layer == "fields" else "LineString",
            crs="EPSG:4326",
            append=self._started[layer],
            promote_to_multi=False,
            # GeoPackage 1.2: what older GDALs (Debian's ogrinfo, QGIS LTR) read without warning.
            dataset_options={"VERSION": "1.2"},
        )
        self._started[layer] = True

    def flush(self) -> None:
        """Write the buffered rows."""
        import numpy as np

        rows, self._rows = self._rows, []
        if not rows:
            return

        def floats(name: str, of: list[FieldResult]) -> Any:
            return np.array(
                [np.nan if getattr(r, name) is None else float(getattr(r, name)) for r in of]
            )

        self._append(
            "fields",
            [r.field_wkb for r in rows],
            {
                "field_index": np.array([r.index for r in rows], dtype=np.int64),
                "field_id": np.array([r.ident for r in rows], dtype=object),
                "name": np.array([r.name for r in rows], dtype=object),
                "area_m2": floats("area_m2", rows),
                "line_count": floats("line_count", rows),
                "path_length_m": floats("path_length_m", rows),
                "coverage_ratio": floats("coverage_ratio", rows),
                "estimated_time_s": floats("estimated_time_s", rows),
                "planning_ms": floats("planning_ms", rows),
                "error": np.array([r.error for r in rows], dtype=object),
            },
        )
        planned = [r for r in rows if r.path_wkb is not None]
        if planned:
            self._append(
                "paths",
                [r.path_wkb for r in planned],
                {
                    "field_index": np.array([r.index for r in planned], dtype=np.int64),
                    "field_id": np.array([r.ident for r in planned], dtype=object),
                    "name": np.array([r.name for r in planned], dtype=object),
                    "path_length_m": floats("path_length_m", planned),
                },
            )
        self.written += len(rows)


def _tasks(chunks: Iterator[list[FieldRecord]], per_task: int) -> Iterator[list[FieldRecord]]:
    for chunk in chunks:
        for start in range(0, len(chunk), per_task):
            yield chunk[start : start + per_task]


def run_batch(
    fields: Path,
    output: Path,
    *,
    options: dict[str, Any],
    scheduler: str | None,
    workers: int,
    per_task: int,
    layer: str | None = None,
    show_progress: bool = True,
) -> tuple[int, int, float]:
    """Plan every field of ``fields`` into ``output``; return (rows, failed, seconds).

    Raises
    ------
    BatchInputError
        If ``fields`` cannot be read at all.
    """
    from app.forkserver import start_fork_server, stop_fork_server

    started = time.perf_counter()
    # The fork server loads Dask and the planner (about 1.4 s) while this process imports
    # Dask, reads the file's header and starts the scheduler, instead of after them.
    server = None if scheduler else start_fork_server()
    try:
        from app.cli.batch_read import open_fields

        source = open_fields(fields, layer=layer)
        output.unlink(missing_ok=True)
        writer = GeoPackageWriter(output)
    except BaseException:
        stop_fork_server(server)  # it would load the planner on after this command has exited
        raise
    from distributed import Client, as_completed

    from app.cli.batch_read import iter_field_chunks
    from app.cli.batch_tasks import plan_records
    from app.kernels_plugin import KernelWarmUp
    from app.local_cluster import start_local_cluster

    # The scheduler runs in this process: its INFO lines would drown the progress bar.
    logging.getLogger("distributed").setLevel(logging.WARNING)
    # A cluster that fails to start leaves the fork server to finish its preload and exit
    # (about 1.4 s): its workers may already be forked from it, so it is not killed.
    cluster = None if scheduler else start_local_cluster(workers)
    client = Client(scheduler or cluster, set_as_default=False)
    try:
        client.register_plugin(KernelWarmUp())  # once per worker, not per task
        n_workers = max(1, len(client.scheduler_info(n_workers=-1)["workers"]))
        limit = IN_FLIGHT_PER_WORKER * n_workers
        pending = as_completed(loop=client.loop)
        tasks = _tasks(iter_field_chunks(source, READ_CHUNK), per_task)
        with _progress(show_progress) as progress:
            bar = progress.add_task("planning", total=source.count, failed=0)

            def collect(future: Any) -> None:
                rows: list[FieldResult] = future.result()
                future.release()
                writer.add(rows)
                progress.update(bar, advance=len(rows), failed=writer.failed)

            for task in tasks:
                while pending.count() >= limit:
                    collect(next(pending))
                pending.add(client.submit(plan_records, task, options, pure=False))
            for future in pending:
                collect(future)
        writer.flush()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return writer.written, writer.failed, time.perf_counter() - started


class _NoProgress:
    def __enter__(self) -> _NoProgress:
        return self

    def __exit__(self, *args: object) -> None:
        return None

    def add_task(self, *args: Any, **kwargs: Any) -> int:
        return 0

    def update(self, *args: Any, **kwargs: Any) -> None:
        return None


def _progress(show: bool) -> Any:
    if not show:
        return _NoProgress()
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    return Progress(
        "[progress.description]{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        "[red]{task.fields[failed]} failed",
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        transient=False,
    )


def plan_batch_command(
    fields: Annotated[
        Path,
        typer.Argument(
            metavar="FIELDS",
            help="GeoPackage, GeoJSON, zipped Shapefile or GeoParquet file of field polygons.",
        ),
    ],
    output: Annotated[
        Path, typer.Option("-o", "--output", metavar="OUT.gpkg", help="GeoPackage to write.")
    ],
    interval: Annotated[
        float | None,
        typer.Option("--interval", help="Line interval [m]; default: each field's interval_m."),
    ] = None,
    angle: Annotated[
        float | None,
        typer.Option("--angle", help="Line heading, degrees from true north; default: searched."),
    ] = None,
    objective: Annotated[
        ObjectiveChoice, typer.Option("--objective", help="What to minimise.")
    ] = ObjectiveChoice.shortest_path,
    headland: Annotated[
        int, typer.Option("--headland", help="Headland passes around the inside, 0–5.")
    ] = 0,
    layer: Annotated[
        str | None, typer.Option("--layer", help="Layer of FIELDS to read (default: first).")
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option(
            "--scheduler",
            metavar="ADDRESS",
            envvar="TILLPATH_DASK_SCHEDULER",
            help="Dask scheduler (tcp://host:8786); default: a local cluster.",
        ),
    ] = None,
    workers: Annotated[
        int,
        typer.Option("--workers", min=1, help="Worker processes of the local cluster."),
    ] = max(1, os.cpu_count() or 1),
    per_task: Annotated[
        int, typer.Option("--fields-per-task", min=1, help="Fields planned per Dask task.")
    ] = FIELDS_PER_TASK,
) -> None:
    """Plan every field of FIELDS in parallel; write figures and paths to OUT.gpkg.

    A field that cannot be planned is a row with its error, not the end of the batch.
    """
    from app.cli.batch_read import BatchInputError

    if output.suffix.lower() != ".gpkg":
        fail(f"-o: the output is a GeoPackage; name the file *.gpkg, got {output.name!r}")
    if interval is not None and not interval > 0:
        fail(f"--interval: must be a positive number of metres, got {interval:g}")
    options: dict[str, Any] = {
        "interval_m": interval,
        "angle_deg": angle,
        "objective": objective.value,
        "headland_passes": headland,
    }
    try:
        rows, failed, seconds = run_batch(
            fields,
            output,
            options=options,
            scheduler=scheduler,
            workers=workers,
            per_task=per_task,
            layer=layer,
        )
    except BatchInputError as exc:
        fail(str(exc))
    except OSError as exc:
        fail(f"-o: cannot write {output}: {exc.strerror or exc}")
    rate = rows / seconds if seconds > 0 else 0.0
    typer.echo(
        f"{rows} fields, {rows - failed} planned, {failed} failed, in {seconds:.1f} s "
        f"({rate:.1f} fields/s); wrote {output}",
        err=True,
    )


def register(cli: typer.Typer) -> None:
    """Add ``plan-batch`` to ``cli``."""
    cli.command("plan-batch")(plan_batch_command)
