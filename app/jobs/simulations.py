"""Job kinds ``simulation`` and ``monte_carlo``: drive a stored plan on a Dask worker.

Both read the plan, run :func:`navigation.simulate` (pure), and store a :class:`Simulation`
row in the job's finishing transaction. A Monte Carlo batch runs over seeds ``seed …
seed+runs-1``, summarises each metric as ``tillpath simulate --runs`` does, and stores the run
of median cross-track RMS, so the page can draw one representative track.
"""

from __future__ import annotations

import datetime as dt
import math
from typing import Any

import numpy as np
from sqlalchemy.orm import Session

from app import services
from app.cli.simulate import summarise
from app.jobs.runner import JobContext
from app.jobs.store import Finish
from app.models import Plan, Simulation
from app.schemas import SimulationCreate
from navigation import GuidanceParams, SimulationConfig, simulate


def simulation_params(plan_id: int, body: SimulationCreate, date: dt.date) -> dict[str, Any]:
    """Return the stored ``params`` of a simulation job: what to run, the date fixed.

    The date is fixed when the job is asked for, so a job run again after a restart drives
    with the same magnetic declination.
    """
    return {"plan_id": plan_id, "request": body.model_dump(), "date": date.isoformat()}


def _inputs(context: JobContext) -> tuple[Plan, SimulationCreate, dt.date]:
    params = context.params
    with context.session() as session:
        plan = services.read_plan(session, int(params["plan_id"]), context.access)
    body = SimulationCreate.model_validate(params["request"])
    return plan, body, dt.date.fromisoformat(params["date"])


def _store(simulation: Simulation, extra: dict[str, Any]) -> Finish:
    def finish(session: Session) -> tuple[dict[str, Any], str | None]:
        session.add(simulation)
        session.flush()
        return {"simulation_id": simulation.id, **extra}, f"/api/simulations/{simulation.id}"

    return finish


def run_simulation(context: JobContext) -> Finish:
    """Drive the plan once; progress is the share of waypoints reached."""
    plan, body, date = _inputs(context)

    def on_waypoint(reached: int, total: int) -> None:
        context.report(reached / max(total, 1))

    simulation = services.simulate_plan(plan, body, date=date, on_waypoint=on_waypoint)
    return _store(simulation, {"runs": 1})


def run_monte_carlo(context: JobContext) -> Finish:
    """Drive the plan ``runs`` times over consecutive seeds; store the median run.

    Progress counts the runs (and the waypoints within each), plus the median run driven
    again at the end to store its tracks (runs are reproducible per seed, so keeping every
    run's tracks in memory is not needed).
    """
    plan, body, date = _inputs(context)
    coverage = services.coverage_plan_from_row(plan)
    config = SimulationConfig(gps=body.gps, guidance=GuidanceParams(mode=body.guidance), date=date)
    seeds = list(range(body.seed, body.seed + body.runs))
    steps = len(seeds) + 1
    results: list[dict[str, Any]] = []
    for done, seed in enumerate(seeds):

        def on_waypoint(reached: int, total: int, done: int = done) -> None:
            context.report((done + reached / max(total, 1)) / steps)

        log = simulate(coverage, config, np.random.default_rng(seed), on_waypoint=on_waypoint)
        results.append(log.metrics.as_dict())
    rms = [
        r["cross_track_rms_m"] if r["cross_track_rms_m"] is not None else math.inf for r in results
    ]
    shown_seed = seeds[int(np.argsort(rms)[len(rms) // 2])]
    context.report(len(seeds) / steps, force=True)

    def on_last(reached: int, total: int) -> None:
        context.report((len(seeds) + reached / max(total, 1)) / steps)

    shown = body.model_copy(update={"seed": shown_seed, "runs": 1})
    simulation = services.simulate_plan(plan, shown, date=date, on_waypoint=on_last)
    summary = services.json_ready(summarise(results))
    return _store(
        simulation,
        {
            "runs": len(seeds),
            "seeds": [seeds[0], seeds[-1]],
            "shown_seed": shown_seed,
            "summary": summary,
        },
    )
