"""A bounded mixed load on a real server, and the check that every acknowledged write is there.

Used by the soak tests (``tests/soak``) and the load benchmark (``bench/bench_load.py``). A few
threads, each with its own HTTP client, loop for a fixed time over what a cooperative's users
and loggers do at once: previews, stored plans, reads and lists, live runs fed by batches of
fixes (some sent twice, as a flaky logger does), uploaded CSV logs, simulations, polls of live
runs, and deletes of plans that other threads are reading, simulating or uploading to. Every
answer is counted by status, with its latency; every write the server acknowledged (201, 200,
204) is recorded, so that :func:`verify` can read each one back afterwards.

Traffic goes only to the loopback server given; the loop stops by itself after ``duration_s``.
"""

from __future__ import annotations

import datetime as dt
import random
import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final

import httpx2

#: Seconds of fixes per live batch (10 Hz) and fixes per uploaded CSV log.
BATCH_FIXES: Final = 20
UPLOAD_FIXES: Final = 3000
#: The start of every run's clock (2026-11-22T00:00:00Z) [s since 1970].
T0_S: Final = 1_795_305_600.0

#: Relative frequency of each action.
WEIGHTS: Final[dict[str, int]] = {
    "preview": 6,
    "create_plan": 3,
    "read_plan": 5,
    "list_plans": 3,
    "live_fixes": 10,
    "poll_run": 5,
    "upload": 1,
    "simulate": 1,
    "delete_doomed": 1,
    "health": 2,
}


@dataclass
class LoadResult:
    """What a load run did and what the server answered.

    Attributes
    ----------
    statuses : Counter
        Answers by HTTP status; ``0`` counts requests that got no answer (server down).
    latencies_s : list of float
        Seconds per answered request.
    server_errors : list of str
        ``METHOD path -> status: body`` of every answer ≥ 500.
    plans : set of int
        Plans acknowledged (201) and not deleted by the load.
    fixes : dict
        Live run id -> times [s] of every fix in a batch the server acknowledged.
    uploads : dict
        Uploaded run id -> its fix count.
    simulations : set of int
        Simulations acknowledged.
    """

    statuses: Counter[int] = field(default_factory=Counter)
    latencies_s: list[float] = field(default_factory=list)
    server_errors: list[str] = field(default_factory=list)
    plans: set[int] = field(default_factory=set)
    fixes: dict[int, set[float]] = field(default_factory=dict)
    uploads: dict[int, int] = field(default_factory=dict)
    simulations: set[int] = field(default_factory=set)
    lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    @property
    def requests(self) -> int:
        """Requests sent."""
        return sum(self.statuses.values())

    @property
    def errors_5xx(self) -> int:
        """Answers with a status ≥ 500."""
        return sum(n for status, n in self.statuses.items() if status >= 500)

    def percentile_ms(self, q: float) -> float:
        """Return the ``q`` quantile (0–1) of the latencies [ms]."""
        if not self.latencies_s:
            return float("nan")
        ordered = sorted(self.latencies_s)
        return ordered[min(len(ordered) - 1, int(q * len(ordered)))] * 1000


def _csv(start_s: float, n: int, rng: random.Random) -> bytes:
    lines = ["time,lat,lon,heading_deg,speed_mps"]
    lat, lon = -8.62645, 115.29805
    for i in range(n):
        lines.append(
            f"{start_s + i / 10:.1f},{lat + rng.uniform(-4e-5, 4e-5):.8f},"
            f"{lon + rng.uniform(-4e-5, 4e-5):.8f},{rng.uniform(0, 359):.1f},0.5"
        )
    return ("\n".join(lines) + "\n").encode()


class _Worker:
    """One thread of the load: its client, its random choices, its own plans and runs."""

    def __init__(
        self,
        index: int,
        base_url: Callable[[], str],
        field_geojson: dict[str, Any],
        result: LoadResult,
        deadline: float,
        doomed: list[int],
        headers: dict[str, str],
    ) -> None:
        self.index = index
        self.base_url = base_url
        self.field = field_geojson
        self.result = result
        self.deadline = deadline
        self.doomed = doomed
        self.rng = random.Random(1000 + index)
        self.client = httpx2.Client(timeout=60, headers=headers)
        self.own_plans: list[int] = []
        self.live_runs: dict[int, int] = {}  # run id -> next fix index

    def request(self, method: str, path: str, **kwargs: Any) -> httpx2.Response | None:
        started = time.perf_counter()
        try:
            response = self.client.request(method, self.base_url() + path, **kwargs)
        except httpx2.TransportError:
            with self.result.lock:
                self.result.statuses[0] += 1
            time.sleep(0.2)  # the server is down (restarting): do not spin
            return None
        elapsed = time.perf_counter() - started
        with self.result.lock:
            self.result.statuses[response.status_code] += 1
            self.result.latencies_s.append(elapsed)
            if response.status_code >= 500:
                self.result.server_errors.append(
                    f"{method} {path} -> {response.status_code}: {response.text[:300]}"
                )
        return response

    def plan_body(self, name: str) -> dict[str, Any]:
        return {"name": name, "field": self.field, "interval_m": self.rng.choice([2, 3, 4])}

    def run(self) -> None:
        actions = list(WEIGHTS)
        weights = [WEIGHTS[a] for a in actions]
        with self.client:
            self.create_plan()
            while time.monotonic() < self.deadline:
                action = self.rng.choices(actions, weights)[0]
                getattr(self, action)()

    def any_plan(self) -> int | None:
        with self.result.lock:
            known = list(self.result.plans) + self.doomed
        return self.rng.choice(known) if known else None

    # --- actions ----------------------------------------------------------------------

    def preview(self) -> None:
        self.request("POST", "/api/plans/preview", json=self.plan_body("preview"))

    def create_plan(self, *, doomed: bool = False) -> None:
        name = f"{'doomed' if doomed else 'kept'} {self.index}-{len(self.own_plans)}"
        response = self.request("POST", "/api/plans", json=self.plan_body(name))
        if response is not None and response.status_code == 201:
            plan_id = int(response.json()["id"])
            with self.result.lock:
                if doomed:
                    self.doomed.append(plan_id)
                else:
                    self.result.plans.add(plan_id)
                    self.own_plans.append(plan_id)

    def read_plan(self) -> None:
        plan_id = self.any_plan()
        if plan_id is not None:
            self.request("GET", f"/api/plans/{plan_id}")
            if self.rng.random() < 0.3:
                self.request("GET", f"/api/plans/{plan_id}/export/gpx")

    def list_plans(self) -> None:
        self.request("GET", "/api/plans", params={"limit": 20})

    def live_fixes(self) -> None:
        if not self.live_runs or self.rng.random() < 0.05:
            if not self.own_plans:
                return
            plan_id = self.rng.choice(self.own_plans)
            response = self.request("POST", f"/api/plans/{plan_id}/runs", json={})
            if response is None or response.status_code != 201:
                return
            run_id = int(response.json()["id"])
            self.live_runs[run_id] = 0
            with self.result.lock:
                self.result.fixes[run_id] = set()
        run_id = self.rng.choice(list(self.live_runs))
        start = self.live_runs[run_id]
        if self.rng.random() < 0.2 and start >= BATCH_FIXES:
            start -= BATCH_FIXES  # a retried batch
        times = [T0_S + (start + i) / 10 for i in range(BATCH_FIXES)]
        batch = [
            {
                "t": t if i % 2 else dt.datetime.fromtimestamp(t, dt.UTC).isoformat(),
                "lat": -8.62645 + self.rng.uniform(-4e-5, 4e-5),
                "lon": 115.29805 + self.rng.uniform(-4e-5, 4e-5),
            }
            for i, t in enumerate(times)
        ]
        response = self.request("POST", f"/api/runs/{run_id}/fixes", json=batch)
        if response is not None and response.status_code == 200:
            with self.result.lock:
                self.result.fixes[run_id].update(round(t, 1) for t in times)
            self.live_runs[run_id] = max(self.live_runs[run_id], start + BATCH_FIXES)

    def poll_run(self) -> None:
        if not self.live_runs:
            return
        run_id = self.rng.choice(list(self.live_runs))
        since = dt.datetime.fromtimestamp(T0_S + self.live_runs[run_id] / 10 - 2, dt.UTC)
        if self.rng.random() < 0.2:
            self.request("GET", f"/api/runs/{run_id}")
        else:
            self.request("GET", f"/api/runs/{run_id}", params={"since": since.isoformat()})

    def pick_doomed(self) -> int | None:
        with self.result.lock:
            return self.rng.choice(self.doomed) if self.doomed else None

    def upload(self) -> None:
        plan_id = self.pick_doomed() if self.rng.random() < 0.5 else None  # may be deleted
        if plan_id is None and self.own_plans:
            plan_id = self.rng.choice(self.own_plans)
        if plan_id is None:
            return
        data = _csv(T0_S, UPLOAD_FIXES, self.rng)
        response = self.request(
            "POST", f"/api/plans/{plan_id}/runs", files={"file": ("log.csv", data)}
        )
        if response is not None and response.status_code == 201:
            with self.result.lock:
                if plan_id in self.result.plans:
                    self.result.uploads[int(response.json()["id"])] = UPLOAD_FIXES

    def simulate(self) -> None:
        plan_id = self.any_plan()
        if plan_id is None:
            return
        response = self.request("POST", f"/api/plans/{plan_id}/simulations", json={"seed": 1})
        if response is not None and response.status_code == 201:
            with self.result.lock:
                if plan_id in self.result.plans:
                    self.result.simulations.add(int(response.json()["id"]))

    def delete_doomed(self) -> None:
        if len(self.doomed) < 3:
            self.create_plan(doomed=True)
            return
        with self.result.lock:
            plan_id = self.doomed.pop(0) if self.doomed else None
        if plan_id is not None:
            self.request("DELETE", f"/api/plans/{plan_id}")

    def health(self) -> None:
        self.request("GET", "/api/health")


def mixed_load(
    base_url: Callable[[], str],
    field_geojson: dict[str, Any],
    *,
    duration_s: float,
    threads: int,
    headers: dict[str, str] | None = None,
    result: LoadResult | None = None,
) -> LoadResult:
    """Run the mixed load from ``threads`` threads for ``duration_s``; return what happened.

    Parameters
    ----------
    base_url : callable
        Returns the server's base URL (it may change if the server is restarted).
    field_geojson : dict
        The field planned (a small one keeps planning and simulating cheap).
    duration_s : float
        How long the load runs [s].
    threads : int
        Concurrent clients.
    headers : dict, optional
        Sent with every request (``Authorization: Bearer …`` of an account).
    result : LoadResult, optional
        Add to this result (a second phase of the same load).
    """
    result = result or LoadResult()
    doomed: list[int] = []
    deadline = time.monotonic() + duration_s
    workers = [
        _Worker(i, base_url, field_geojson, result, deadline, doomed, dict(headers or {}))
        for i in range(threads)
    ]
    pool = [threading.Thread(target=w.run, name=f"load-{w.index}") for w in workers]
    for thread in pool:
        thread.start()
    for thread in pool:
        thread.join()
    return result


def verify(
    base_url: str, result: LoadResult, *, headers: dict[str, str] | None = None
) -> list[str]:
    """Read back every acknowledged write; return what is missing (empty if nothing).

    Every plan and simulation must be there, every uploaded run with all its fixes, and every
    live run with at least every fix of its acknowledged batches (a batch whose answer was lost
    in a restart may be stored without having been acknowledged).
    """
    missing: list[str] = []
    with httpx2.Client(base_url=base_url, headers=headers, timeout=120) as client:
        for plan_id in sorted(result.plans):
            if client.get(f"/api/plans/{plan_id}").status_code != 200:
                missing.append(f"plan {plan_id}")
        for simulation_id in sorted(result.simulations):
            if client.get(f"/api/simulations/{simulation_id}").status_code != 200:
                missing.append(f"simulation {simulation_id}")
        everything = {"since": "1980-01-06T00:00:00Z"}  # every fix, and no scoring
        for run_id, count in sorted(result.uploads.items()):
            response = client.get(f"/api/runs/{run_id}", params=everything)
            if response.status_code != 200 or response.json()["fix_count"] != count:
                missing.append(f"uploaded run {run_id} ({response.status_code})")
        for run_id, times in sorted(result.fixes.items()):
            response = client.get(f"/api/runs/{run_id}", params=everything)
            if response.status_code != 200:
                missing.append(f"live run {run_id} ({response.status_code})")
                continue
            run = response.json()
            stored: set[float] = set()
            if run["track"] is not None:
                start = dt.datetime.fromisoformat(run["started_at"]).timestamp()
                offsets = run["track"]["properties"]["time_s"]
                stored = {round(start + s, 1) for s in offsets}
            lost = times - stored
            if lost:
                missing.append(f"live run {run_id}: {len(lost)} acknowledged fixes missing")
    return missing
