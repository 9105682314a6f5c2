"""Compile every kernel of the planner, or load them from numba's disk cache, in one call.

The compiled loops live in :mod:`planner.kernels` (the heading scorers and the helpers the
other kernel modules build on) and in :mod:`planner.fit_kernels`,
:mod:`planner.coverage_kernels`, :mod:`planner.cell_kernels`, :mod:`planner.order_kernels`,
:mod:`planner.edge_kernels`, :mod:`planner.decomposition_kernels`,
:mod:`planner.screen_kernels`, :mod:`planner.parity_kernels`, :mod:`planner.turn_kernels`
and :mod:`planner.band_kernels`.
Each module warms its own kernels; this module, above them all, warms them all, so that
:mod:`planner.kernels` imports none of the modules that import it.
"""

from __future__ import annotations

from planner import (
    band_kernels,
    cell_kernels,
    coverage_kernels,
    decomposition_kernels,
    edge_kernels,
    fit_kernels,
    kernels,
    order_kernels,
    parity_kernels,
    screen_kernels,
    turn_kernels,
)


def warm_up() -> None:
    """Compile every kernel module's kernels, or load them from the disk cache, on tiny inputs.

    For an image build (fill ``NUMBA_CACHE_DIR``), a server before it serves, or a worker
    before its first plan: the first call in a process with a cold cache compiles for seconds
    (about 9 s of CPU), a warm cache loads in about 0.35 s (:mod:`planner.kernels`).
    """
    kernels.warm_up()
    fit_kernels.warm_up()
    coverage_kernels.warm_up()
    cell_kernels.warm_up()
    order_kernels.warm_up()
    edge_kernels.warm_up()
    decomposition_kernels.warm_up()
    screen_kernels.warm_up()
    parity_kernels.warm_up()
    turn_kernels.warm_up()
    band_kernels.warm_up()
