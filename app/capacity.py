"""A bounded queue for heavy work: planning, simulating, parsing uploads and scoring runs.

Each worker process runs at most ``heavy_work_slots`` such computations at once; up to
``heavy_work_queue`` more requests wait (at most ``heavy_work_wait_s`` each) for a slot, and any
beyond that are answered 503 with ``Retry-After`` at once. So a burst of simulations queues or
is turned away cleanly instead of exhausting the threads, the connection pool or the memory,
and light requests (reads, live fixes, health) keep their own threads and connections.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache
from typing import Annotated

from fastapi import Depends

from app.dependencies import SettingsDep
from app.errors import ServerBusyError
from app.settings import Settings


class HeavyWork:
    """Slots for heavy work, with a bounded wait.

    Parameters
    ----------
    slots : int
        Computations run at once.
    queue : int
        Requests that may wait for a slot; more are refused at once.
    wait_s : float
        Longest wait for a slot [s].
    """

    def __init__(self, *, slots: int, queue: int, wait_s: float) -> None:
        self.slots = slots
        self.queue = queue
        self.wait_s = wait_s
        self._semaphore = threading.BoundedSemaphore(slots)
        self._lock = threading.Lock()
        self._waiting = 0
        self._running = 0

    @property
    def running(self) -> int:
        """Computations running now."""
        return self._running

    @contextmanager
    def slot(self, what: str) -> Iterator[None]:
        """Hold a slot for the block.

        Raises
        ------
        ServerBusyError
            If the queue is full, or no slot came free within ``wait_s``.
        """
        if self._semaphore.acquire(blocking=False):
            acquired = True
        else:
            with self._lock:
                if self._waiting >= self.queue:
                    raise ServerBusyError(what)
                self._waiting += 1
            try:
                acquired = self._semaphore.acquire(timeout=self.wait_s)
            finally:
                with self._lock:
                    self._waiting -= 1
        if not acquired:
            raise ServerBusyError(what)
        with self._lock:
            self._running += 1
        try:
            yield
        finally:
            with self._lock:
                self._running -= 1
            self._semaphore.release()

    def try_slot(self) -> bool:
        """Take a slot if one is free now, without waiting (release it with :meth:`release`)."""
        return self._semaphore.acquire(blocking=False)

    def release(self) -> None:
        """Give back a slot taken with :meth:`try_slot`."""
        self._semaphore.release()


@lru_cache(maxsize=8)
def _heavy_work(slots: int, queue: int, wait_s: float) -> HeavyWork:
    return HeavyWork(slots=slots, queue=queue, wait_s=wait_s)


def get_heavy_work(settings: Settings) -> HeavyWork:
    """Return the process's :class:`HeavyWork` for ``settings`` (one per configuration)."""
    return _heavy_work(
        settings.heavy_work_slots, settings.heavy_work_queue, settings.heavy_work_wait_s
    )


async def _heavy_work_dependency(
    settings: SettingsDep,
) -> HeavyWork:
    # Async: a look-up in a cache, not worth a thread hop per request.
    return get_heavy_work(settings)


HeavyWorkDep = Annotated[HeavyWork, Depends(_heavy_work_dependency)]
