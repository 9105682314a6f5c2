"""Timing helpers shared by the benchmarks."""

from __future__ import annotations

import gc
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import shapely


def time_calls(function: Callable[[], Any], *, repeat: int, warmup: int = 5) -> list[float]:
    """Wall-clock seconds of ``repeat`` calls, after ``warmup`` untimed ones (GC paused)."""
    for _ in range(warmup):
        function()
    timings = []
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        for _ in range(repeat):
            started = time.perf_counter()
            function()
            timings.append(time.perf_counter() - started)
    finally:
        if gc_was_enabled:
            gc.enable()
    return timings


def time_calls_cpu(
    function: Callable[[], Any], *, repeat: int, warmup: int = 5
) -> tuple[list[float], list[float]]:
    """Wall-clock and CPU seconds (``time.process_time``) of ``repeat`` calls (GC paused).

    On a shared machine the wall clock counts the time other processes hold the cores; the
    CPU time is this process's alone, and the figure to hold to a budget there.
    """
    for _ in range(warmup):
        function()
    wall, cpu = [], []
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        for _ in range(repeat):
            started, cpu_started = time.perf_counter(), time.process_time()
            function()
            cpu.append(time.process_time() - cpu_started)
            wall.append(time.perf_counter() - started)
    finally:
        if gc_was_enabled:
            gc.enable()
    return wall, cpu


def summary_ms(timings: list[float]) -> tuple[float, float, float]:
    """Median, 10th and 90th percentile [ms]."""
    ordered = sorted(timings)
    pick = lambda q: ordered[min(len(ordered) - 1, int(q * len(ordered)))] * 1000  # noqa: E731
    return statistics.median(ordered) * 1000, pick(0.1), pick(0.9)


def verdict(value: float, budget: float, *, lower_is_better: bool = True) -> str:
    ok = value <= budget if lower_is_better else value >= budget
    return "met" if ok else "**missed**"


def small_quadrilaterals(count: int, *, seed: int = 14) -> list[shapely.Polygon]:
    """``count`` random quadrilaterals of 0.1–0.6 ha on a grid 200 m apart, WGS84 (lon, lat).

    A smallholder's plots: a few lines each at 10 m. Used by ``bench_batch`` (memory of
    ``plan-batch`` on 100,000 of them) and ``bench_planner`` (CPU per plan).
    """
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(count)))
    step = 0.002  # deg, about 200 m
    quads = []
    for i in range(count):
        x0, y0 = 10 + (i % side) * step, 50 + (i // side) * step
        w, h = rng.uniform(3e-4, 9e-4, 2)
        jitter = rng.uniform(-1e-4, 1e-4, 4)
        ring = [
            (x0, y0),
            (x0 + w, y0 + jitter[0]),
            (x0 + w + jitter[1], y0 + h),
            (x0 + jitter[2], y0 + h + jitter[3]),
        ]
        quads.append(shapely.Polygon(ring))
    return quads
