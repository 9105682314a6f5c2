"""Compiled helpers the planner's kernels share: the decorators, numpy's scalar rules, sorts, sums.

Each helper is numpy's operation on scalars, with its NaN and tie rules (``np.minimum``,
``np.maximum``, ``np.clip``, ``searchsorted``, ``np.sort``), or its order of additions
(``np.add.reduce``'s pairwise sum), so a kernel built from them
computes what its numpy reference does, to the last bit (see :mod:`planner.kernels`).
"""

from __future__ import annotations

import hashlib
import logging
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

import numba
import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

_COUNT_EPS = 1e-9  # planner.lines._COUNT_EPS
_log = logging.getLogger(__name__)

_F = TypeVar("_F", bound=Callable[..., object])

#: The file in numba's cache directory that records which kernel sources it was built from.
_SOURCES_STAMP = "kernel-sources.sha256"


def drop_stale_kernels(package_dir: Path, cache_dir: Path) -> bool:
    """Empty numba's cache of the planner's kernels if any kernel's source has changed.

    Numba checks a cached kernel against its own file only: a kernel that calls one in
    another file (``screen_kernels._screen`` calls ``fit_screen._fit_cell``) would be loaded
    as it was compiled, calling the old code, after that other file changed. So the cache
    records a digest of every planner module that compiles kernels (``@_jit``); on a
    mismatch its machine code is deleted and compiled again on first use. Returns whether
    it was. A cache directory that cannot be written is left alone.
    """
    digest = hashlib.sha256()
    for source in sorted(package_dir.glob("*.py")):
        text = source.read_bytes()
        if b"@_jit" in text:
            digest.update(source.name.encode() + b"\0" + text)
    stamp = cache_dir / _SOURCES_STAMP
    try:
        if stamp.read_text() == digest.hexdigest():
            return False
    except OSError:
        pass  # no stamp yet: a new cache, or one from before this check
    try:
        for compiled in [*cache_dir.glob("*.nbi"), *cache_dir.glob("*.nbc")]:
            compiled.unlink(missing_ok=True)
        cache_dir.mkdir(exist_ok=True)
        stamp.write_text(digest.hexdigest())
    except OSError as exc:
        _log.debug("numba cache %s left as it is: %s", cache_dir, exc)
        return False
    return True


# The default cache lies next to the modules; NUMBA_CACHE_DIR (an image's) is built afresh.
if not os.environ.get("NUMBA_CACHE_DIR"):
    drop_stale_kernels(Path(__file__).parent, Path(__file__).parent / "__pycache__")


def _jit(f: _F) -> _F:
    """Compile ``f`` on first call, cached on disk; division by zero gives inf/NaN as numpy.

    Where no cache directory is writable (numba raises at decoration), compile in memory:
    slow to start, but the plan is the same.
    """
    try:
        return cast(_F, numba.njit(cache=True, error_model="numpy")(f))
    except RuntimeError as exc:
        _log.warning("planner kernels compile in memory, every process again: %s", exc)
        return cast(_F, numba.njit(error_model="numpy")(f))


def _jit_counted_by_caller(f: _F) -> _F:
    """:func:`_jit` without reference counting, for a kernel that allocates nothing.

    Numba counts references to every array a compiled function passes on (an atomic
    increment and decrement per array per call): the coverage kernel passes nine scratch
    arrays per strip, and those counts took a third of its time. Its caller allocates the
    scratch and holds every array for the call, so the kernel needs no counts (numba's
    ``_nrt`` option, as numba's own sorts use it; not in its type stubs). The arithmetic is
    the same.
    """
    uncounted: dict[str, Any] = {"_nrt": False}
    try:
        return cast(_F, numba.njit(cache=True, error_model="numpy", **uncounted)(f))
    except RuntimeError as exc:
        _log.warning("planner kernels compile in memory, every process again: %s", exc)
        return cast(_F, numba.njit(error_model="numpy", **uncounted)(f))


def read_only(values: npt.ArrayLike, dtype: type) -> npt.NDArray[Any]:
    """``values`` as a C-contiguous, read-only array of ``dtype``: a view where it can be.

    Numba compiles one version of a kernel per argument type, and an array's write flag is
    part of its type. The heading screen's scans are read-only (the plan's cells are views
    of them), a warm-up's arrays are not: a kernel warmed on one and first called with the
    other compiled again, for seconds, inside a plan. A wrapper passes every array its
    kernel only reads through this, so both meet the one version the warm-up compiled.

    Examples
    --------
    >>> a = read_only([1, 2], np.float64)
    >>> a.dtype.name, a.flags.writeable, a.flags.c_contiguous
    ('float64', False, True)
    """
    array: npt.NDArray[Any] = np.ascontiguousarray(values, dtype=dtype)
    if array.flags.writeable:
        array = array.view()
        array.flags.writeable = False
    return array


@_jit
def _mn(a: float, b: float) -> float:
    """``np.minimum``: ``a`` on ties (and if ``a`` is NaN)."""
    return a if (a <= b or a != a) else b


@_jit
def _mx(a: float, b: float) -> float:
    """``np.maximum``: ``a`` on ties (and if ``a`` is NaN)."""
    return a if (a >= b or a != a) else b


@_jit
def _clip(x: float, lo: float, hi: float) -> float:
    """``np.clip`` of floats: ``min(max(x, lo), hi)`` with NaN kept."""
    if x != x:
        return x
    y = x if x > lo else lo
    return y if y < hi else hi


@_jit
def _right(keys: FloatArray, start: int, stop: int, q: float) -> int:
    """``keys[start:stop].searchsorted(q, side="right") + start`` (keys sorted)."""
    lo, hi = start, stop
    while lo < hi:
        mid = lo + ((hi - lo) >> 1)
        if keys[mid] <= q:
            lo = mid + 1
        else:
            hi = mid
    return lo


@_jit
def _left(keys: FloatArray, start: int, stop: int, q: float) -> int:
    """``keys[start:stop].searchsorted(q, side="left") + start`` (keys sorted)."""
    lo, hi = start, stop
    while lo < hi:
        mid = lo + ((hi - lo) >> 1)
        if keys[mid] < q:
            lo = mid + 1
        else:
            hi = mid
    return lo


#: Rings up to this many vertices are sorted in place by insertion (a field's few corners);
#: longer ones by heapsort (np.sort would allocate its result: the coverage kernel, which
#: sorts, runs without reference counts and so cannot allocate).
_INSERTION_MAX = 32


@_jit
def _before(a: float, b: float) -> bool:
    """Return whether ``a`` sorts before ``b`` in ``np.sort``: smaller, or a number before NaN."""
    return a < b or (b != b and a == a)


@_jit
def _sift_down(out: FloatArray, root: int, end: int) -> None:
    """Restore the heap (greatest first) below ``root`` within ``out[:end]``."""
    while True:
        child = 2 * root + 1
        if child >= end:
            return
        if child + 1 < end and _before(out[child], out[child + 1]):
            child += 1
        if not _before(out[root], out[child]):
            return
        out[root], out[child] = out[child], out[root]
        root = child


@_jit
def _sorted_into(values: FloatArray, out: FloatArray) -> None:
    """``out[:] = np.sort(values)``, without allocating.

    Floats sort the same whichever the algorithm: equal values are the same bits, but for
    ``-0.0`` and ``0.0``, which compare equal and may come out in another order than
    ``np.sort``'s (the tests compare bits with the zeros' signs ignored); NaN goes last as
    in ``np.sort``.
    """
    n = len(values)
    if n > _INSERTION_MAX:
        for i in range(n):  # not out[:] = values: a slice copy may allocate
            out[i] = values[i]
        for root in range(n // 2 - 1, -1, -1):
            _sift_down(out, root, n)
        for end in range(n - 1, 0, -1):
            out[0], out[end] = out[end], out[0]
            _sift_down(out, 0, end)
        return
    for i in range(n):
        x = values[i]
        j = i
        # x before out[j - 1]: smaller, or a number before a NaN (np.sort's order).
        while j > 0 and (x < out[j - 1] or (out[j - 1] != out[j - 1] and x == x)):
            out[j] = out[j - 1]
            j -= 1
        out[j] = x


@_jit
def _stable_order_into(keys: IntArray, n: int, out: IntArray) -> None:
    """``out[:n] = np.argsort(keys[:n], kind="mergesort")``: ties in their order."""
    if n > _INSERTION_MAX:
        out[:n] = np.argsort(keys[:n], kind="mergesort")
        return
    for i in range(n):
        j = i
        while j > 0 and keys[i] < keys[out[j - 1]]:
            out[j] = out[j - 1]
            j -= 1
        out[j] = i


@_jit
def _line_count(width: float, d: float) -> int:
    """:func:`planner.lines.line_counts` of one width."""
    if width <= d:
        return 1
    return int(np.ceil((width - d) / d - _COUNT_EPS)) + 1


#: numpy's pairwise summation: blocks of this many values are added eight ways at once.
_PW_BLOCKSIZE = 128


@_jit
def _block_sum(values: FloatArray, start: int, n: int) -> float:
    """Add at most ``_PW_BLOCKSIZE`` values as numpy's ``pairwise_sum`` does: eight ways."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += values[start + i]
        return res
    r0, r1, r2, r3 = values[start], values[start + 1], values[start + 2], values[start + 3]
    r4, r5, r6, r7 = values[start + 4], values[start + 5], values[start + 6], values[start + 7]
    i = 8
    while i < n - n % 8:
        r0 += values[start + i]
        r1 += values[start + i + 1]
        r2 += values[start + i + 2]
        r3 += values[start + i + 3]
        r4 += values[start + i + 4]
        r5 += values[start + i + 5]
        r6 += values[start + i + 6]
        r7 += values[start + i + 7]
        i += 8
    total: float = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        total += values[start + i]
        i += 1
    return total


@_jit
def _pairwise_sum(values: FloatArray, start: int, n: int) -> float:
    """Add ``values[start:start + n]`` as numpy's ``pairwise_sum`` does (``np.add.reduce``).

    ``values.sum()`` is ``0.0 +`` this; a segment of ``np.add.reduceat`` is its first value
    ``+`` this of the rest. Above a block, numpy adds the sums of two halves (the first a
    multiple of 8 long); that recursion runs here on a stack of its own (numba's disk cache
    mishandles recursive functions: they crash when loaded).
    """
    if n <= _PW_BLOCKSIZE:
        return _block_sum(values, start, n)
    # Frames: a span, its phase (0 new, 1 left half pending, 2 right half pending), its left sum.
    depth = 64  # spans halve: 2**64 values
    at, count = np.empty(depth, np.int64), np.empty(depth, np.int64)
    phase, left = np.zeros(depth, np.int64), np.empty(depth)
    top = 0
    at[0], count[0], phase[0] = start, n, 0
    result = 0.0
    while True:
        if phase[top] == 0 and count[top] > _PW_BLOCKSIZE:
            half = count[top] // 2
            half -= half % 8
            phase[top] = 1
            top += 1
            at[top], count[top], phase[top] = at[top - 1], half, 0
            continue
        # This frame's sum is known: a block's, or both halves'.
        result = _block_sum(values, at[top], count[top]) if phase[top] == 0 else left[top] + result
        top -= 1
        if top < 0:
            return result
        if phase[top] == 1:  # the left half is done: on to the right half
            half = count[top] // 2
            half -= half % 8
            left[top] = result
            phase[top] = 2
            top += 1
            at[top], count[top], phase[top] = at[top - 1] + half, count[top - 1] - half, 0
        else:
            phase[top] = 3  # both halves done: its sum is left + result, next round
