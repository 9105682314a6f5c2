"""A Dask worker plugin that loads the planner's compiled kernels once per worker.

Registered by the job engine and ``tillpath plan-batch`` on every worker, present and future
(a restarted worker too), so a worker's first planning task does not pay for ``import numba``
and the kernels' disk cache (about 0.35 s), or their compile where the cache is cold (seconds,
:mod:`planner.kernels`). The job engine's also imports every job kind's module
(:func:`app.jobs.runner.warm_up`: the app's database stack, about 1.1 s of CPU once the kernels
are in), which a planning batch does not need. They load in a background thread: the worker is
ready at once, and a task that needs them before they are loaded waits for them.

The module lives outside :mod:`app.jobs` on purpose: a worker unpickles the plugin by importing
its module, and importing anything in ``app.jobs`` imports the package, which brings the web app
(about 1 s of a core a worker, inside ``plan-batch``'s run).
"""

from __future__ import annotations

import threading
from typing import Any, Final

from distributed.diagnostics.plugin import WorkerPlugin

#: The plugin's name on the workers: registering it again replaces it instead of adding one.
NAME: Final = "tillpath-planner-kernels"


def _warm_up(job_kinds: bool) -> None:
    from planner.warm_up import warm_up

    warm_up()
    if job_kinds:
        from app.jobs.runner import warm_up as import_job_kinds

        import_job_kinds()


class KernelWarmUp(WorkerPlugin):
    """Load every planner kernel (:mod:`planner.warm_up`) in a thread when a worker starts.

    Parameters
    ----------
    job_kinds : bool
        Import every job kind's module too, after the kernels (the job engine's workers).
    """

    name = NAME

    def __init__(self, *, job_kinds: bool = False) -> None:
        self.job_kinds = job_kinds

    def setup(self, worker: Any) -> None:
        """Start loading the kernels; return at once."""
        threading.Thread(
            target=_warm_up, args=(self.job_kinds,), name="planner-warm-up", daemon=True
        ).start()
