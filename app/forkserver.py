"""The one fork server of a tillpath process, and what it loads before it forks any child.

Python keeps one ``multiprocessing`` fork server per process. tillpath forks two kinds of
children from it: the processes that plan a large field within a budget (:mod:`app.budget`)
and the workers of the local Dask cluster (:mod:`app.local_cluster`). Both set the same preload
here, so whichever starts the fork server first, it has loaded Dask and the planner
(:mod:`app.preload`) and every child starts with them.
"""

from __future__ import annotations

import multiprocessing
import os
from multiprocessing.context import ForkServerContext
from typing import Final

#: Imported by the fork server when it starts: Dask (its workers' own modules, about 0.3 s
#: a worker otherwise) and the planner with its compiled kernels.
PRELOAD: Final = ("distributed", "app.preload")


def _dask_pre_spawn_environ() -> None:
    """Put Dask's ``distributed.nanny.pre-spawn-environ`` in this process's environment.

    A forked child has the environment its fork server started with. Dask's nannies set these
    variables (``MALLOC_TRIM_THRESHOLD_``, read by the C library when a process starts; one
    thread for OpenMP and BLAS, read when numpy loads) just before they start a worker, which
    is too late when the fork server is already running (``tillpath serve`` starts it for the
    planning budget first). Set here, before the fork server can start, every worker gets them.
    A value already in the environment is kept.
    """
    import dask
    import distributed  # noqa: F401  (loads Dask's distributed.* defaults)

    environ = dask.config.get("distributed.nanny.pre-spawn-environ", default={}) or {}
    for name, value in environ.items():
        os.environ.setdefault(str(name), str(value))


def preloaded_context() -> ForkServerContext:
    """Return the ``forkserver`` context, its preload set to :data:`PRELOAD`.

    A fork server already running keeps what it loaded, and the environment it had, when it
    started.
    """
    _dask_pre_spawn_environ()
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(PRELOAD))
    return context
