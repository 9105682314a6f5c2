"""Imported by the fork server (:mod:`app.budget`): load the planner's compiled kernels once.

The fork server imports the modules it is told to preload before it forks any child, so a
large field's child starts with the kernels in memory instead of spending about 0.35 s of its
planning budget on ``import numba`` and the disk cache (:mod:`planner.kernels`). Importing this
module is its whole purpose; nothing else should import it.
"""

from planner.warm_up import warm_up

warm_up()
