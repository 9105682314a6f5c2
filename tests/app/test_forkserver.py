"""The process's fork server (``app.forkserver``): started early, stopped before it forks."""

from __future__ import annotations

import json
import subprocess
import sys

#: In a fresh interpreter: start the fork server twice, stop it, say what happened.
_START_STOP = """
import json, os, sys, time
from app.forkserver import start_fork_server, stop_fork_server
pid = start_fork_server()
again = start_fork_server()
started = time.perf_counter()
stop_fork_server(pid)
stopped_s = time.perf_counter() - started
try:
    os.kill(pid, 0)
    alive = True
except ProcessLookupError:
    alive = False
print(json.dumps({"pid": pid, "again": again, "alive": alive, "stopped_s": stopped_s,
                  "distributed": "distributed" in sys.modules}))
"""


def test_a_fork_server_stopped_while_it_loads_is_gone_at_once() -> None:
    """Killed and reaped, not left to load the planner after its command has exited; a second
    start finds it running and returns None (None is never stopped: it may have children)."""
    out = subprocess.run(
        [sys.executable, "-c", _START_STOP], capture_output=True, text=True, check=True
    )
    result = json.loads(out.stdout)
    assert isinstance(result["pid"], int) and result["again"] is None
    assert result["alive"] is False
    assert result["stopped_s"] < 0.5  # its preload takes over a second
    # Started before this process imports distributed: the preload runs beside that import.
    assert result["distributed"] is False


_ENVIRON = """
import json, os
from app.forkserver import preloaded_context
for name in ("MALLOC_TRIM_THRESHOLD_", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
             "OPENBLAS_NUM_THREADS"):
    os.environ.pop(name, None)
before = dict(os.environ)
preloaded_context()
added = {k: v for k, v in os.environ.items() if k not in before}
import dask, distributed
expected = {str(k): str(v) for k, v in
            dask.config.get("distributed.nanny.pre-spawn-environ").items()}
print(json.dumps([added, expected]))
"""


def test_the_pre_spawn_environment_read_without_distributed_is_dasks() -> None:
    """Read from distributed's defaults file, it is what Dask has once distributed is in."""
    out = subprocess.run(
        [sys.executable, "-c", _ENVIRON], capture_output=True, text=True, check=True
    )
    added, expected = json.loads(out.stdout)
    assert expected and added == expected
