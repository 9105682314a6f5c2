"""``tillpath plan-batch``: every field of a file planned on Dask, a bad field a row of its own."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import uuid
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import psutil
import pyarrow as pa
import pyarrow.parquet as pq
import pyogrio.raw
import pytest
import shapely
from pyproj import Transformer

from app.cli.batch import run_batch
from app.cli.batch_read import BatchInputError, iter_field_chunks, open_fields
from app.kernels_plugin import NAME
from tests.conftest import FIELDS_DIR

TILLPATH = [sys.executable, "-c", "from app.cli import main; main()"]
#: A bow tie: self-intersecting, so the planner refuses it with a message.
BOW_TIE = shapely.Polygon([(30.0, -2.0), (30.001, -2.001), (30.001, -2.0), (30.0, -2.001)])


def rwanda_fields(n: int) -> list[dict[str, Any]]:
    collection = json.loads((FIELDS_DIR / "rwanda_2021.geojson").read_text())
    features: list[dict[str, Any]] = collection["features"][:n]
    return features


def write_gpkg(path: Path, geometries: list[Any], ids: list[str], names: list[Any]) -> None:
    pyogrio.raw.write(
        str(path),
        geometry=np.array([None if g is None else shapely.to_wkb(g) for g in geometries]),
        field_data=[np.array(ids, dtype=object), np.array(names, dtype=object)],
        fields=["id", "name"],
        driver="GPKG",
        geometry_type="Polygon",
        crs="EPSG:4326",
    )


def read_layer(path: Path, layer: str) -> tuple[list[Any], dict[str, list[Any]]]:
    meta, _fids, geometry, data = pyogrio.raw.read(str(path), layer=layer)
    return list(geometry), {
        name: list(column) for name, column in zip(meta["fields"], data, strict=False)
    }


def test_one_invalid_field_is_reported_and_the_rest_are_planned(tmp_path: Path) -> None:
    features = rwanda_fields(5)
    geometries: list[Any] = [shapely.geometry.shape(f["geometry"]) for f in features]
    geometries.insert(2, BOW_TIE)
    ids = [str(f["properties"]["id"]) for f in features]
    ids.insert(2, "bow-tie")
    names = [f"field {i}" for i in range(6)]
    fields = tmp_path / "fields.gpkg"
    write_gpkg(fields, geometries, ids, names)
    out = tmp_path / "out.gpkg"
    result = subprocess.run(
        [*TILLPATH, "plan-batch", str(fields), "-o", str(out), "--interval", "4", "--workers", "1"],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert result.returncode == 0, result.stderr
    assert "6 fields, 5 planned, 1 failed" in result.stderr
    _geoms, rows = read_layer(out, "fields")
    by_id = dict(zip(rows["field_id"], range(6), strict=False))
    assert sorted(rows["field_id"]) == sorted(ids)
    bad = by_id["bow-tie"]
    assert "self-intersect" in rows["error"][bad]
    assert np.isnan(rows["path_length_m"][bad])
    for ident in ids:
        if ident == "bow-tie":
            continue
        i = by_id[ident]
        assert rows["error"][i] is None
        assert rows["line_count"][i] >= 1
        assert 0.5 < rows["coverage_ratio"][i] <= 1.0
        expected = next(f for f in features if str(f["properties"]["id"]) == ident)
        area = expected["properties"]["area_m2"]
        assert abs(rows["area_m2"][i] - area) / area < 0.01
    paths, path_rows = read_layer(out, "paths")
    assert sorted(path_rows["field_id"]) == sorted(i for i in ids if i != "bow-tie")
    for wkb, length in zip(paths, path_rows["path_length_m"], strict=False):
        line = shapely.from_wkb(wkb)
        assert line.geom_type == "LineString" and len(line.coords) >= 2
        assert length > 0


def test_geoparquet_in_utm_and_a_zipped_shapefile_read_as_wgs84(tmp_path: Path) -> None:
    features = rwanda_fields(3)
    lonlat = [shapely.geometry.shape(f["geometry"]) for f in features]
    to_utm = Transformer.from_crs(4326, 32736, always_xy=True)
    utm = [
        shapely.transform(g, lambda xy: np.column_stack(to_utm.transform(xy[:, 0], xy[:, 1])))
        for g in lonlat
    ]
    crs = json.loads(Transformer.from_crs(32736, 32736).source_crs.to_json())  # PROJJSON
    geo = {
        "version": "1.1.0",
        "primary_column": "geometry",
        "columns": {"geometry": {"encoding": "WKB", "geometry_types": ["Polygon"], "crs": crs}},
    }
    table = pa.table(
        {"id": ["a", "b", "c"], "geometry": [shapely.to_wkb(g) for g in utm]}
    ).replace_schema_metadata({"geo": json.dumps(geo)})
    parquet = tmp_path / "fields.parquet"
    pq.write_table(table, parquet)

    shp_dir = tmp_path / "shp"
    shp_dir.mkdir()
    write_gpkg(tmp_path / "tmp.gpkg", lonlat, ["a", "b", "c"], ["x", "y", "z"])
    subprocess.run(
        [
            "ogr2ogr",
            "-f",
            "ESRI Shapefile",
            str(shp_dir / "fields.shp"),
            str(tmp_path / "tmp.gpkg"),
        ],
        check=True,
    )
    zipped = tmp_path / "fields.zip"
    with zipfile.ZipFile(zipped, "w") as archive:
        for part in shp_dir.iterdir():
            archive.write(part, part.name)

    for path in (parquet, zipped):
        source = open_fields(path)
        assert source.count == 3
        chunks = list(iter_field_chunks(source, 2))
        assert [len(c) for c in chunks] == [2, 1]
        records = [r for c in chunks for r in c]
        assert [r.ident for r in records] == ["a", "b", "c"]
        for record, expected in zip(records, lonlat, strict=False):
            assert record.wkb is not None
            got = shapely.from_wkb(record.wkb)
            assert got.symmetric_difference(expected).area < 1e-6 * expected.area


def test_run_batch_streams_many_fields_on_a_cluster(tmp_path: Path, dask_scheduler: str) -> None:
    # More fields than one read chunk and one write buffer, planned on the session's cluster.
    squares = [shapely.box(10 + i * 1e-3, 50, 10 + i * 1e-3 + 4e-4, 50.0004) for i in range(2500)]
    fields = tmp_path / "squares.gpkg"
    write_gpkg(fields, squares, [f"s{i}" for i in range(2500)], [None] * 2500)
    out = tmp_path / "out.gpkg"
    rows, failed, _seconds = run_batch(
        fields,
        out,
        options={"interval_m": 10.0},
        scheduler=dask_scheduler,
        workers=1,
        per_task=64,
        show_progress=False,
    )
    assert (rows, failed) == (2500, 0)
    _geoms, data = read_layer(out, "fields")
    assert sorted(data["field_index"]) == list(range(2500))
    assert all(n >= 1 for n in data["line_count"])
    # Dask's profiler is off in the workers: it kept an hour of call trees, ~10 MiB a worker
    # per 1,000 fields, so a long batch's memory grew with its length.
    from distributed import Client

    with Client(dask_scheduler, set_as_default=False) as client:
        profiles = client.run(
            lambda dask_worker: (len(dask_worker.profile_history), dask_worker.profile_recent)
        )
        for history, recent in profiles.values():
            assert history == 0 and recent["count"] == 0, (history, recent["count"])
        # The planner's kernels are loaded once per worker (a plugin), not by each task.
        plugins = client.run(lambda dask_worker: list(dask_worker.plugins))
    assert all(NAME in names for names in plugins.values()), plugins


def test_unreadable_input_and_bad_output_are_errors_with_status_2(tmp_path: Path) -> None:
    with pytest.raises(BatchInputError, match="does not exist"):
        open_fields(tmp_path / "missing.gpkg")
    text = tmp_path / "fields.txt"
    text.write_text("not fields")
    with pytest.raises(BatchInputError, match="not a known format"):
        open_fields(text)
    result = subprocess.run(
        [*TILLPATH, "plan-batch", str(text), "-o", str(tmp_path / "out.csv")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2
    assert result.stderr.startswith("error: -o: the output is a GeoPackage")
    result = subprocess.run(
        [*TILLPATH, "plan-batch", str(text), "-o", str(tmp_path / "out.gpkg")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2
    assert result.stderr.startswith("error: FIELDS: fields.txt is not a known format")


def _marked(marker: str) -> list[str]:
    """Command lines of the live processes whose environment has ``marker``."""
    found = []
    for process in psutil.process_iter():
        try:
            if process.environ().get("TILLPATH_TEST_MARKER") == marker:
                found.append(" ".join(process.cmdline()))
        except psutil.Error:
            continue
    return found


def test_a_file_that_cannot_be_read_leaves_no_fork_server_behind(tmp_path: Path) -> None:
    """The fork server starts before the file is opened (it loads the planner meanwhile): a
    file found unreadable then still ends the command at once, with no process left loading
    the planner after it (the resource tracker goes with the command; it may take a moment).

    Output to files, not pipes: a process left behind holds the command's stderr, and reading
    a pipe to its end would wait for that process too.
    """
    fields = tmp_path / "fields.gpkg"
    fields.write_bytes(b"not a GeoPackage")
    marker = uuid.uuid4().hex
    with (tmp_path / "stderr.txt").open("w+") as stderr:
        returncode = subprocess.run(
            [*TILLPATH, "plan-batch", str(fields), "-o", str(tmp_path / "out.gpkg")],
            stdout=subprocess.DEVNULL,
            stderr=stderr,
            timeout=60,
            env={**os.environ, "TILLPATH_TEST_MARKER": marker},
        ).returncode
        left_at_exit = _marked(marker)
        stderr.seek(0)
        message = stderr.read()
    assert returncode == 2
    assert message.startswith("error: FIELDS: cannot read"), message
    assert not [c for c in left_at_exit if "forkserver" in c], left_at_exit
    deadline = time.monotonic() + 2.0
    while (left := _marked(marker)) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not left
    assert not (tmp_path / "out.gpkg").exists()


_RUN_ONE_FIELD = """
import sys
from pathlib import Path
from app.cli.batch import run_batch
rows = run_batch(Path(sys.argv[1]), Path(sys.argv[2]), options={"interval_m": 4.0},
                 scheduler=None, workers=1, per_task=8, show_progress=False)[:2]
print(rows, sorted(m for m in sys.modules if m.startswith(("app.jobs", "app.main", "app.db"))))
"""


def test_plan_batch_on_its_own_cluster_does_not_import_the_web_app(tmp_path: Path) -> None:
    """The local cluster's helpers live outside ``app.jobs``, whose package brings the web app
    and its database stack (about 2 s before the cluster could start)."""
    feature = rwanda_fields(1)[0]
    fields = tmp_path / "fields.gpkg"
    write_gpkg(fields, [shapely.geometry.shape(feature["geometry"])], ["a"], ["one"])
    result = subprocess.run(
        [sys.executable, "-c", _RUN_ONE_FIELD, str(fields), str(tmp_path / "out.gpkg")],
        capture_output=True,
        text=True,
        timeout=180,
        check=True,
    )
    assert result.stdout.split("\n")[0] == "(1, 0) []", result.stdout
