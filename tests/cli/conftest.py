"""The command-line tests run ``tillpath`` in subprocesses: fill the kernels' cache first."""

from __future__ import annotations

import pytest

from app.testing import warm_kernel_cache


@pytest.fixture(scope="session", autouse=True)
def _kernel_cache() -> None:
    warm_kernel_cache()
