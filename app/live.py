"""Live reads of a run that stay fast as it grows: new fixes since the last poll, cached figures.

``GET /api/runs/{id}?since=T`` answers with the fixes after time ``T`` only (one range query
on the ``(run_id, t)`` key), the fix count (kept on the run's row, never counted), the first
and the last fix, and the run's metrics, missed ground and receiver note from a per-process
cache. The metrics and the missed ground
take about 1 s for a 6-hour, 216,000-fix run, so they are never computed in a poll: a poll
that finds them older than the fixes starts one recomputation in the background (one per run
at a time, only when a heavy-work slot is free, at most every :data:`REFRESH_INTERVAL_S`), and
answers with the last figures and ``metrics_fix_count``, the number of fixes they cover. A
full read (no ``since``) computes them when they are out of date and fills the cache.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from sqlalchemy import Engine, select
from sqlalchemy.orm import Session

from app.capacity import HeavyWork
from app.db import end_reads
from app.errors import NotFoundError
from app.models import Fix, Run
from app.runs import MAX_TRACK_POINTS, RunTrack, _finite, _thin, run_view
from app.track_fixes import datetime_to_us, us_to_datetime

#: Least time between two background recomputations of one run's metrics [s].
REFRESH_INTERVAL_S: Final = 5.0
#: Runs whose figures are kept (least recently used dropped first).
CACHE_RUNS: Final = 256


@dataclass(frozen=True, slots=True)
class Summary:
    """A run's scored figures, and which fixes they cover."""

    fix_count: int
    last_t: int
    metrics: dict[str, Any] | None
    stretches: list[dict[str, Any]]
    computed_at: float
    missed: dict[str, Any] | None = None
    receiver: dict[str, Any] | None = None


_Key = tuple[str, int, float, float]


class SummaryCache:
    """Thread-safe LRU of :class:`Summary` per (database, run, created_at, threshold)."""

    def __init__(self, size: int = CACHE_RUNS) -> None:
        self._size = size
        self._items: OrderedDict[_Key, Summary] = OrderedDict()
        self._refreshing: set[_Key] = set()
        self._lock = threading.Lock()

    def get(self, key: _Key) -> Summary | None:
        """Return the cached summary of ``key``, if any."""
        with self._lock:
            found = self._items.get(key)
            if found is not None:
                self._items.move_to_end(key)
            return found

    def put(self, key: _Key, summary: Summary) -> None:
        """Keep ``summary`` unless a newer one (covering more fixes) is there already."""
        with self._lock:
            old = self._items.get(key)
            if old is None or old.fix_count <= summary.fix_count:
                self._items[key] = summary
                self._items.move_to_end(key)
            while len(self._items) > self._size:
                self._items.popitem(last=False)

    def claim(self, key: _Key) -> bool:
        """Mark ``key`` as being recomputed; False if it already is."""
        with self._lock:
            if key in self._refreshing:
                return False
            self._refreshing.add(key)
            return True

    def release(self, key: _Key) -> None:
        """Unmark ``key``."""
        with self._lock:
            self._refreshing.discard(key)


CACHE = SummaryCache()


def _key(session: Session, run: Run, threshold_m: float) -> _Key:
    url = session.get_bind().engine.url.render_as_string(hide_password=True)
    return (url, run.id, run.created_at.timestamp(), threshold_m)


def remember(session: Session, run: Run, view: dict[str, Any], *, threshold_m: float) -> None:
    """Keep the figures of a full read (:func:`app.runs.run_view`) for the polls that follow."""
    last = view["last_fix"]
    summary = Summary(
        fix_count=int(view["fix_count"]),
        last_t=datetime_to_us(last["t"]) if last else 0,
        metrics=view["metrics"],
        stretches=view["stretches"]["features"],
        computed_at=time.monotonic(),
        missed=view.get("missed"),
        receiver=view.get("receiver"),
    )
    CACHE.put(_key(session, run, threshold_m), summary)


def full_view(
    session: Session, run: Run, *, threshold_m: float, track: RunTrack | None = None
) -> dict[str, Any]:
    """Answer ``GET /api/runs/{id}`` without ``since``: everything, scored now (and cached).

    ``track``: the run's fixes if the caller holds them (an upload), else they are loaded.
    """
    view = run_view(session, run, threshold_m=threshold_m, track=track)
    remember(session, run, view, threshold_m=threshold_m)
    view["metrics_fix_count"] = view["fix_count"]
    return view


def _refresh(engine: Engine, run_id: int, threshold_m: float) -> None:
    with Session(engine, expire_on_commit=False) as session:
        run = session.get(Run, run_id)
        if run is None:
            return
        try:
            view = run_view(session, run, threshold_m=threshold_m)
        except NotFoundError:  # deleted meanwhile
            return
        remember(session, run, view, threshold_m=threshold_m)


def _maybe_refresh(
    session: Session,
    run: Run,
    key: _Key,
    found: Summary | None,
    heavy: HeavyWork,
    threshold_m: float,
) -> None:
    if found is not None and time.monotonic() - found.computed_at < REFRESH_INTERVAL_S:
        return
    if not CACHE.claim(key):
        return
    if not heavy.try_slot():  # busy: the figures wait for the next poll
        CACHE.release(key)
        return
    engine = session.get_bind().engine

    run_id = run.id

    def work() -> None:
        try:
            _refresh(engine, run_id, threshold_m)
        finally:
            CACHE.release(key)
            heavy.release()

    threading.Thread(target=work, name=f"run-{run.id}-summary", daemon=True).start()


def live_view(
    session: Session, run: Run, *, since_us: int, threshold_m: float, heavy: HeavyWork
) -> dict[str, Any]:
    """Answer ``GET /api/runs/{id}?since=…``: the run with its fixes after ``since_us`` only.

    ``track`` holds only the newer fixes (thinned to :data:`~app.runs.MAX_TRACK_POINTS`), with
    ``time_s`` counted from the run's first fix as in a full read; ``metrics`` and
    ``stretches`` are the cached figures, covering ``metrics_fix_count`` fixes.
    """
    # The run's row keeps its count (app.ingest.store_fixes): nothing is counted here, and
    # every other read is a look-up on the (run_id, t) key.
    count = session.scalar(select(Run.fix_count).where(Run.id == run.id)) or 0
    first = session.scalar(select(Fix.t).where(Fix.run_id == run.id).order_by(Fix.t).limit(1))
    last = session.execute(
        select(Fix.t, Fix.lat, Fix.lon, Fix.heading_deg, Fix.speed_mps)
        .where(Fix.run_id == run.id)
        .order_by(Fix.t.desc())
        .limit(1)
    ).first()
    rows = session.execute(
        select(Fix.t, Fix.lon, Fix.lat)
        .where(Fix.run_id == run.id, Fix.t > since_us)
        .order_by(Fix.t)
        .limit(MAX_TRACK_POINTS * 20)
    ).all()
    end_reads(session)
    key = _key(session, run, threshold_m)
    found = CACHE.get(key)
    if found is None or found.fix_count != count:
        _maybe_refresh(session, run, key, found, heavy, threshold_m)
    view: dict[str, Any] = {
        "id": run.id,
        "plan_id": run.plan_id,
        "name": run.name,
        "source": run.source,
        "created_at": run.created_at,
        "fix_count": count,
        "import_report": run.import_report,
        "started_at": us_to_datetime(int(first)) if first is not None else None,
        "last_fix": None,
        "metrics": found.metrics if found else None,
        "metrics_fix_count": found.fix_count if found else None,
        "track": None,
        "stretches": {
            "type": "FeatureCollection",
            "features": found.stretches if found else [],
        },
    }
    # Missed ground (~0.5 s for a 6-hour log) and the receiver note come from the cache too.
    if found is not None and found.missed is not None:
        view["missed"] = found.missed
    if found is not None and found.receiver is not None:
        view["receiver"] = found.receiver
    if last is not None:
        t, lat, lon, heading, speed = last  # (Row.t is SQLAlchemy's alias of the tuple)
        view["last_fix"] = {
            "t": us_to_datetime(int(t)),
            "lat": float(lat),
            "lon": float(lon),
            "heading_deg": None if heading is None else _finite(heading),
            "speed_mps": None if speed is None else _finite(speed),
        }
    if rows and first is not None:
        table = np.array(rows, dtype=np.float64)
        keep = _thin(len(table), MAX_TRACK_POINTS)
        coords = table[keep][:, 1:3].round(8).tolist()
        if len(coords) == 1:
            coords.append(coords[0])
        time_s = ((table[keep, 0] - float(first)) / 1e6).round(3).tolist()
        view["track"] = {
            "type": "Feature",
            "properties": {"kind": "track", "source": run.source, "time_s": time_s},
            "geometry": {"type": "LineString", "coordinates": coords},
        }
    return view
