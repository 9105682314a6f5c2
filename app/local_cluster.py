"""The local Dask cluster of ``tillpath plan-batch`` and ``tillpath serve``: quiet, forked workers.

Outside :mod:`app.jobs` on purpose, as :mod:`app.kernels_plugin` is: importing anything in
``app.jobs`` imports the package, which brings the web app and its database stack (about 2 s
of a core), and ``plan-batch`` needs none of it; it waited for that import before it started
its cluster.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Final

if TYPE_CHECKING:
    from distributed import LocalCluster


#: Dask settings of the local cluster. Its periodic work runs on the cores that plan: on a
#: 2-core machine an idle cluster of two workers took 71-86 ms of CPU a second with Dask's
#: defaults, 19-21 ms with these (the scheduler, with its nannies, runs in the web server's
#: or ``plan-batch``'s process). The event-loop health tick (20 ms by default) only times the
#: warnings of a blocked loop; the system monitor (500 ms) feeds a dashboard there is none
#: of; a nanny checks its worker's memory against the limit twice a second, not ten times.
QUIET_CLUSTER: Final[dict[str, object]] = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "200ms",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "500ms",
}


#: The local cluster's workers are forked from the process's fork server, which has loaded
#: Dask and the planner (:mod:`app.forkserver`), rather than spawned as fresh interpreters. A
#: worker that a nanny restarts later is spawned (this setting applies while the cluster
#: starts) and loads the kernels through :class:`app.kernels_plugin.KernelWarmUp`.
FORKED_WORKERS: Final[dict[str, object]] = {
    "distributed.worker.multiprocessing-method": "forkserver"
}


def _preload_forkserver() -> None:
    """Set the fork server's preload (:data:`app.forkserver.PRELOAD`), after Dask set its own.

    Dask sets its list (distributed, numpy, …) the first time it asks for the context; ours
    loads Dask and the planner. Takes effect when the fork server starts (the first child this
    process forks); one already running (:mod:`app.budget` and ``plan-batch`` start it
    earlier, :func:`app.forkserver.start_fork_server`) keeps what it has.
    """
    from distributed.utils import get_mp_context

    from app.forkserver import preloaded_context

    get_mp_context()
    preloaded_context()


def start_local_cluster(n_workers: int, *, forked: bool = True) -> LocalCluster:
    """Start a local Dask cluster of ``n_workers`` single-threaded worker processes.

    Parameters
    ----------
    n_workers : int
    forked : bool
        Fork the workers from a server process that has loaded the planner
        (:data:`FORKED_WORKERS`); False spawns fresh interpreters, which load it on their
        first task, as workers started by ``dask worker`` on other machines do.

    Notes
    -----
    No dashboard (it would need bokeh); the scheduler's small HTTP server (health, metrics)
    listens on a free loopback port rather than 8787, which another cluster may hold. Worker
    logs at warning level.

    Dask's statistical profiler is off in the workers: it samples every worker 100 times a
    second and keeps an hour of call trees, which nothing here reads (there is no dashboard).
    With it on, each worker of a 100,000-field ``plan-batch`` grew by about 10 MiB per 1,000
    fields, and an idle cluster of two workers spent 0.07 s of CPU a second instead of 0.04 s.
    The other periodic work is spaced out too (:data:`QUIET_CLUSTER`).
    """
    import dask
    from distributed import LocalCluster

    method = FORKED_WORKERS if forked else {"distributed.worker.multiprocessing-method": "spawn"}
    # The nannies copy the configuration when they are made: their workers inherit it.
    with dask.config.set(QUIET_CLUSTER), dask.config.set(method):
        if forked:
            _preload_forkserver()
        return LocalCluster(
            n_workers=n_workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address="127.0.0.1:0",
            silence_logs=logging.WARNING,
        )
