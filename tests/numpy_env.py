"""A pytest plugin loaded before anything imports numpy (``-p tests.numpy_env`` in pyproject).

On a CPU with AVX-512, numpy computes arctan2, arccos, exp, tan, log … with SIMD code of its
own (its X86_V4 dispatch) that differs from the C library's in the last bit, while the
compiled kernels (numba) call the C library's. Turned off for the tests, numpy calls the C
library's too, so ``tests/planner/test_*kernels.py`` compare each kernel with its numpy
reference bit for bit on any x86 CPU: the same arithmetic, in the same order, with the same
elementary functions. ``tests/planner/test_kernels.py`` checks that numpy loaded this way. The
planner itself runs with numpy as it comes (the kernels do not use numpy's functions).
"""

from __future__ import annotations

import os

#: The CPU flags numpy's X86_V4 dispatch needs.
AVX512_FLAGS = {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"}


def _cpu_flags() -> set[str]:
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as cpuinfo:
            return set(next((ln for ln in cpuinfo if ln.startswith("flags")), "").split())
    except OSError:
        return set()


if AVX512_FLAGS <= _cpu_flags():
    # numpy warns about a feature the CPU lacks, so only where it has it.
    os.environ.setdefault("NPY_DISABLE_CPU_FEATURES", "X86_V4")
