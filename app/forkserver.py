"""The one fork server of a tillpath process, and what it loads before it forks any child.

Python keeps one ``multiprocessing`` fork server per process. tillpath forks two kinds of
children from it: the processes that plan a large field within a budget (:mod:`app.budget`)
and the workers of the local Dask cluster (:mod:`app.local_cluster`). Both set the same preload
here, so whichever starts the fork server first, it has loaded Dask and the planner
(:mod:`app.preload`) and every child starts with them.
"""

from __future__ import annotations

import importlib.util
import multiprocessing
import multiprocessing.forkserver
import os
import signal
from multiprocessing.context import ForkServerContext
from pathlib import Path
from typing import Any, Final

#: Imported by the fork server when it starts: Dask (its workers' own modules, about 0.3 s
#: a worker otherwise) and the planner with its compiled kernels.
PRELOAD: Final = ("distributed", "app.preload")


def _dask_config() -> dict[str, Any]:
    """Return Dask's configuration with the ``distributed.*`` defaults in it.

    Without importing ``distributed`` (about 0.4 s): ``plan-batch`` starts the fork server
    before it, so that the server's preload runs beside that import. The defaults are the
    package's ``distributed.yaml``, which the package loads the same way when it is imported;
    the user's configuration wins over them, as in Dask.
    """
    import dask

    spec = importlib.util.find_spec("distributed")
    defaults = []
    if spec is not None and spec.origin is not None:
        defaults = list(
            dask.config.collect_yaml([str(Path(spec.origin).with_name("distributed.yaml"))])
        )
    if not defaults:
        import distributed  # noqa: F401  (no such file: its defaults load with the package)
    return dask.config.merge(*defaults, dask.config.config)


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

    environ = dask.config.get(
        "distributed.nanny.pre-spawn-environ", default={}, config=_dask_config()
    )
    for name, value in (environ or {}).items():
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


def _server() -> Any:
    """Return this process's ``multiprocessing`` fork server.

    Its process id and ``_stop`` are not public (``_stop`` is there for CPython's tests), and
    nothing public tells whether it runs or stops one that is still loading its preload.
    """
    return multiprocessing.forkserver._forkserver


def start_fork_server() -> int | None:
    """Start the fork server now, its preload loading in the background.

    Returns
    -------
    int or None
        The fork server's process id if this call started it; None if one was running.

    Notes
    -----
    Otherwise it starts with the first child forked, when the caller has waited for everything
    before that; ``plan-batch`` starts it first and reads its input and starts its scheduler
    while the server loads Dask and the planner (about 1.4 s).
    """
    preloaded_context()
    server = _server()
    # Without the private pid (another Python) the server still starts early; it is only
    # never stopped by stop_fork_server.
    running = getattr(server, "_forkserver_pid", None)
    multiprocessing.forkserver.ensure_running()
    started: int | None = getattr(server, "_forkserver_pid", None)
    return started if started != running else None


def stop_fork_server(pid: int | None) -> None:
    """Stop the fork server that :func:`start_fork_server` started (``pid``), if it still runs.

    For a command that fails before it forks any child: the server would otherwise go on
    loading the planner after the command has exited (over a second; with a cold kernel cache,
    as after an install, it compiles them, about 10 s). Closing its pipe, as Python does, only
    stops it once its preload is done, so it is killed, then reaped. None: nothing to stop.
    Only for a process in which nothing else forks from the server meanwhile (a child being
    forked would be lost): the command calls it before it starts any.
    """
    server = _server()
    if pid is None or getattr(server, "_forkserver_pid", None) != pid:
        return
    if not hasattr(server, "_stop"):
        return  # another Python: the server finishes its preload, then exits with its pipe
    os.kill(pid, signal.SIGKILL)  # it has forked nothing and has nothing to save
    server._stop()  # closes its pipe, reaps it, forgets it (a later child starts a new one)
