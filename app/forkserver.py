"""The one fork server of a tillpath process, and what it loads before it forks any child.

Python keeps one ``multiprocessing`` fork server per process. tillpath forks two kinds of
children from it: the processes that plan a large field within a budget (:mod:`app.budget`)
and the workers of the local Dask cluster (:mod:`app.jobs.engine`). Both set the same preload
here, so whichever starts the fork server first, it has loaded Dask and the planner
(:mod:`app.preload`) and every child starts with them.
"""

from __future__ import annotations

import multiprocessing
from multiprocessing.context import ForkServerContext
from typing import Final

#: Imported by the fork server when it starts: Dask (its workers' own modules, about 0.3 s
#: a worker otherwise) and the planner with its compiled kernels.
PRELOAD: Final = ("distributed", "app.preload")


def preloaded_context() -> ForkServerContext:
    """Return the ``forkserver`` context, its preload set to :data:`PRELOAD`.

    A fork server already running keeps what it loaded when it started.
    """
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(PRELOAD))
    return context
