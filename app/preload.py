"""Imported by the fork server before it forks any child: the planner, loaded once.

tillpath's processes fork their children from one ``multiprocessing`` fork server that has
imported this module (and Dask, :mod:`app.forkserver`): the children that plan a large field
within a budget (:mod:`app.budget`) and the workers of the local Dask cluster
(:func:`app.local_cluster.start_local_cluster`). Each child starts with the planner, its compiled
kernels, ``plan-batch``'s task and the warm-up plugin in memory, shared copy-on-write, instead
of paying for them itself: about 0.7 s of a core per child (``import planner`` with scipy
0.3 s, ``numba`` and the kernels' disk cache 0.4 s), and one copy of the kernels' ~115 MiB of
machine code.

The job kinds are not loaded here: they bring the web app, the simulator and scipy.stats (over
a second of imports), which ``plan-batch``'s workers never need; the server's engine imports
them in its workers when they start.

Importing this module is its whole purpose; nothing else should import it. It only imports and
loads: it opens no socket and no database connection of the app's (pyproj keeps its read-only
PROJ database open, as in any process that has projected).

A failure here must not take the fork server down: Python's fork server survives only an
``ImportError`` in its preload, and every worker and budgeted plan is forked from it. So a
failed kernel load is logged, and each worker loads the kernels again through
:class:`app.kernels_plugin.KernelWarmUp`, where a real error shows on the first plan.
"""

import logging

import app.cli.batch_tasks  # noqa: F401  (plan-batch's task)
import app.kernels_plugin  # noqa: F401  (unpickled by every worker as the plugin registers)
from planner.warm_up import warm_up

try:
    warm_up()
except Exception:
    logging.getLogger(__name__).exception("the fork server could not load the planner's kernels")
