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
from app.local_cluster import start_local_cluster

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
