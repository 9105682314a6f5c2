"""The Dask engine that runs background jobs (product.md §13).

By default the server starts a local cluster of its own (worker *processes*, so a long
simulation never holds the web process's GIL) and stops it with the server; with
``TILLPATH_DASK_SCHEDULER=tcp://host:8786`` it uses an existing cluster instead. The engine
only submits :func:`app.jobs.runner.run_job` with a job id: the state is in the database, so
a sweep every few seconds can run again whatever a restart or a lost worker left queued.
"""

from __future__ import annotations

import logging
import os
import threading
import uuid
from typing import TYPE_CHECKING, Any, Final

from app.db import get_engine
from app.jobs import store
from app.jobs.runner import run_job

if TYPE_CHECKING:
    from distributed import Client, Future, LocalCluster

logger = logging.getLogger(__name__)

#: How often the engine looks for jobs to run again (lapsed leases, queued after a restart) [s].
SWEEP_EVERY_S: Final = 5.0
#: How long to wait for an existing scheduler to answer [s].
CONNECT_TIMEOUT_S: Final = 30


def default_workers() -> int:
    """Return the local cluster's size when none is configured: one worker per CPU core."""
    return max(1, os.cpu_count() or 1)


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
    process forks); one already running (as :mod:`app.budget` starts it) keeps what it has.
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


class JobEngine:
    """Submit jobs to Dask and keep them going across restarts.

    Parameters
    ----------
    database_url : str
        The jobs' database; the workers open it themselves, so it must be a file or a server
        (not in-memory SQLite).
    scheduler_address : str, optional
        An existing scheduler; None starts a local cluster.
    n_workers : int, optional
        Size of the local cluster (default :func:`default_workers`).
    """

    def __init__(
        self,
        database_url: str,
        *,
        scheduler_address: str | None = None,
        n_workers: int | None = None,
    ) -> None:
        self.database_url = database_url
        self.scheduler_address = scheduler_address
        self.n_workers = n_workers or default_workers()
        #: This engine's id in the leases of the jobs its workers run.
        self.owner = uuid.uuid4().hex
        self.cluster: LocalCluster | None = None
        self.client: Client | None = None
        self._futures: dict[int, Future[Any]] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._sweeper: threading.Thread | None = None

    @property
    def local(self) -> bool:
        """True if the engine runs its own local cluster."""
        return self.scheduler_address is None

    def start(self) -> None:
        """Start (or connect to) the cluster, run what is left queued, and start the sweep."""
        from distributed import Client

        if self.local:
            self.cluster = start_local_cluster(self.n_workers)
            self.client = Client(self.cluster, set_as_default=False)
        else:
            self.client = Client(
                self.scheduler_address, timeout=CONNECT_TIMEOUT_S, set_as_default=False
            )
        from app.kernels_plugin import KernelWarmUp

        # The one warm-up of the workers: the planner's kernels, then the job kinds' modules.
        # A plugin rather than client.run(...): it reaches every worker, present and future
        # (a restarted or added one too, on a remote cluster as well), in the background,
        # and start() does not wait for it.
        self.client.register_plugin(KernelWarmUp(job_kinds=True))
        self.sweep()
        self._sweeper = threading.Thread(target=self._sweep_loop, name="job-sweep", daemon=True)
        self._sweeper.start()

    def submit(self, job_id: int) -> None:
        """Run job ``job_id`` on a worker (unless this engine has it running already).

        Before the engine has started this does nothing: :meth:`start` submits every queued
        job once its cluster is up.
        """
        client = self.client
        if client is None:
            return
        with self._lock:
            if job_id in self._futures:
                return
            future = client.submit(
                run_job,
                self.database_url,
                job_id,
                self.owner,
                key=f"tillpath-job-{job_id}-{uuid.uuid4().hex[:8]}",
                pure=False,
                retries=0,
            )
            self._futures[job_id] = future

        def forget(_future: Future[Any], job_id: int = job_id) -> None:
            with self._lock:
                if self._futures.get(job_id) is future:
                    del self._futures[job_id]

        future.add_done_callback(forget)

    def cancel(self, job_id: int) -> None:
        """Drop job ``job_id``'s task if it has not started (a running one stops by itself)."""
        with self._lock:
            future = self._futures.pop(job_id, None)
        if future is not None:
            future.cancel()

    def sweep(self) -> None:
        """Queue again the jobs whose worker was lost, and submit every queued job."""
        engine = get_engine(self.database_url)
        store.requeue_lapsed(engine)
        for job_id in store.queued_ids(engine):
            self.submit(job_id)

    def _sweep_loop(self) -> None:
        while not self._stop.wait(SWEEP_EVERY_S):
            try:
                self.sweep()
            except Exception:  # the database or the scheduler is away: try again later
                logger.warning("job sweep failed", exc_info=True)

    def stop(self) -> None:
        """Stop the sweep; with a local cluster, queue its running jobs again and stop it.

        The jobs of a shared cluster keep running there (another server start finds them done,
        or queues them again when their lease lapses).
        """
        self._stop.set()
        if self._sweeper is not None:
            self._sweeper.join(timeout=SWEEP_EVERY_S + 5)
        if self.local:
            released = store.release(get_engine(self.database_url), self.owner)
            if released:
                logger.info("%d running job(s) queued again for the next start", released)
        if self.client is not None:
            self.client.close()
            self.client = None
        if self.cluster is not None:
            self.cluster.close()
            self.cluster = None
