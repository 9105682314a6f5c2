"""The local Dask cluster (``app.local_cluster``): its settings, and workers forked loaded."""

from __future__ import annotations

import pytest

from app.local_cluster import QUIET_CLUSTER


@pytest.mark.parametrize("key", sorted(QUIET_CLUSTER))
def test_quiet_cluster_keys_exist_in_dask_config(key: str) -> None:
    """``dask.config.set`` takes any key: a misspelt one would be set and silently ignored."""
    import dask
    import distributed  # noqa: F401  (loads the distributed.* defaults)

    dask.config.get(key)  # raises KeyError for a key dask does not know


def _loaded_in_worker() -> tuple[bool, int]:
    """In a worker: is the planner imported, and how many compiled kernels are in memory?"""
    import sys

    from planner import fit_kernels

    return "planner.pipeline" in sys.modules, len(fit_kernels._translate.overloads)


def test_the_local_clusters_workers_start_with_the_planner_and_its_kernels_loaded() -> None:
    """Forked from the preloaded forkserver: asked before any task has run on the worker."""
    from distributed import Client

    from app.local_cluster import start_local_cluster

    with start_local_cluster(1) as cluster, Client(cluster, set_as_default=False) as client:
        (loaded,) = client.run(_loaded_in_worker).values()
    assert loaded[0] and loaded[1] >= 1


#: In a fresh interpreter, as ``tillpath serve`` does: the planning budget's fork server starts
#: first, then the local cluster forks its workers from it; each worker prints its environment.
_SERVE_ORDER = """
from distributed import Client
from app import budget
from app.local_cluster import start_local_cluster
budget.warm_up().join()
def environ():
    with open("/proc/self/environ", "rb") as f:
        return sorted(f.read().decode().split("\\0"))
with start_local_cluster(1) as cluster, Client(cluster, set_as_default=False) as client:
    (names,) = client.run(environ).values()
print(" ".join(names))
"""


def test_workers_forked_after_the_budget_started_the_fork_server_get_dasks_environment() -> None:
    """Dask's pre-spawn environment (one BLAS thread, the malloc trim threshold) is in the
    environment the worker's process started with, not only set after it started."""
    import os
    import subprocess
    import sys

    import dask
    import distributed  # noqa: F401  (loads Dask's distributed.* defaults)

    expected = dask.config.get("distributed.nanny.pre-spawn-environ")
    env = {k: v for k, v in os.environ.items() if k not in expected}
    out = subprocess.run(
        [sys.executable, "-c", _SERVE_ORDER], capture_output=True, text=True, env=env, check=True
    )
    started_with = set(out.stdout.split())
    for name, value in expected.items():
        assert f"{name}={value}" in started_with
