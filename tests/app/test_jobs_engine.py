"""The job engine's local cluster settings (``app.jobs.engine``)."""

from __future__ import annotations

import pytest

from app.jobs.engine import QUIET_CLUSTER


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

    from app.jobs.engine import start_local_cluster

    with start_local_cluster(1) as cluster, Client(cluster, set_as_default=False) as client:
        (loaded,) = client.run(_loaded_in_worker).values()
    assert loaded[0] and loaded[1] >= 1
