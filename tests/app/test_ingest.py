"""app.ingest and app.db.write on committed databases: bulk paths, idempotency, races.

On a SQLite file and, when ``TILLPATH_TEST_DATABASE_URL`` is set, a PostgreSQL database of
its own: every storage path (``executemany``, ``COPY`` through a temporary table, ``COPY``
straight into a new run) stores each timestamp once, and a failed write stores nothing.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator

import numpy as np
import pytest
from sqlalchemy import Engine, func, select, text
from sqlalchemy.orm import Session

from app import accounts, ingest, runs
from app.db import add_row, delete_row, get_engine, write
from app.errors import ConflictError, NotFoundError
from app.models import Fix, Plan, Run, Simulation
from app.track_fixes import TrackFix
from tests.app.test_live_server import database_url  # noqa: F401

T0 = 1_795_305_600_000_000  # 2026-11-22T00:00:00Z [µs]


@pytest.fixture
def engine(database_url: str) -> Iterator[Engine]:  # noqa: F811
    yield get_engine(database_url)


def organisation_id(session: Session) -> int:
    org_id = accounts.get_or_create_organisation(session, "ingest").id
    session.commit()
    return org_id


def a_plan(session: Session) -> Plan:
    plan = Plan(
        name="p",
        organisation_id=organisation_id(session),
        request={},
        stats={},
        waypoints=[],
        geojson={},
    )
    return add_row(session, plan)


def a_run(session: Session, plan: Plan) -> Run:
    run = Run(
        plan_id=plan.id,
        organisation_id=plan.organisation_id,
        name="r",
        source="live",
        import_report={},
    )
    return add_row(session, run)


def fixes(start: int, stop: int, *, lat: float = -8.6) -> list[TrackFix]:
    return [
        TrackFix(t=T0 + i * 100_000, lat=lat + i * 1e-7, lon=115.3, heading_deg=float(i % 360))
        for i in range(start, stop)
    ]


def stored_times(session: Session, run_id: int) -> list[int]:
    rows = session.scalars(select(Fix.t).where(Fix.run_id == run_id).order_by(Fix.t)).all()
    session.commit()
    return list(rows)


@pytest.mark.parametrize("size", [10, ingest.COPY_MIN_ROWS + 10, 12_345])
def test_every_bulk_path_stores_each_timestamp_once(engine: Engine, size: int):
    with Session(engine, expire_on_commit=False) as session:
        plan = a_plan(session)
        run = a_run(session, plan)
        first = ingest.collect(fixes(0, size))
        assert write(session, lambda s: ingest.store_fixes(s, run.id, first)) == size
        # Overlapping second batch: only the later half is new.
        second = ingest.collect(fixes(size // 2, size + size // 2))
        new = write(session, lambda s: ingest.store_fixes(s, run.id, second))
        assert new == size // 2
        assert stored_times(session, run.id) == [T0 + i * 100_000 for i in range(size + size // 2)]
        headings = session.scalars(
            select(Fix.heading_deg).where(Fix.run_id == run.id).order_by(Fix.t)
        ).all()
        assert headings[:3] == [0.0, 1.0, 2.0]


def varied_fixes(n: int) -> list[TrackFix]:
    """``n`` fixes whose optional values are each missing in some fixes, in different ones."""
    qualities = [None, "rtk_fixed", "rtk_float", "dgps", "single", "dead_reckoning"]
    rng = np.random.default_rng(11)
    lat = -8.6 + rng.random(n) * 1e-3
    return [
        TrackFix(
            t=T0 + i * 100_000,
            lat=float(lat[i]),
            lon=115.3 + i * 1e-9,
            heading_deg=None if i % 3 == 0 else float(rng.random() * 360),
            speed_mps=None if i % 5 == 0 else 0.56 + i * 1e-6,
            quality=qualities[i % len(qualities)],
            hdop=None if i % 7 == 0 else 0.1 * (i % 40),
            satellites=None if i % 4 == 1 else i % 30,
        )
        for i in range(n)
    ]


@pytest.mark.parametrize(
    ("size", "new_run"),
    [(10, False), (ingest.COPY_MIN_ROWS + 10, False), (ingest.COPY_MIN_ROWS + 10, True)],
)
def test_every_bulk_path_stores_the_values_given(engine: Engine, size: int, new_run: bool):
    """Each path (``executemany``, ``COPY`` through a temporary table, ``COPY`` into a new run)
    stores every value exactly (floats to the last bit) and a missing one as NULL."""
    given = varied_fixes(size)
    with Session(engine, expire_on_commit=False) as session:
        plan = a_plan(session)
        if new_run:
            run = runs.create_run_from_columns(
                session, plan, ingest.collect(given), source="csv", report={}, name="u"
            )
        else:
            run = a_run(session, plan)
            write(session, lambda s: ingest.store_fixes(s, run.id, ingest.collect(given)))
        stored = session.execute(
            select(
                Fix.t,
                Fix.lat,
                Fix.lon,
                Fix.heading_deg,
                Fix.speed_mps,
                Fix.quality,
                Fix.hdop,
                Fix.satellites,
            )
            .where(Fix.run_id == run.id)
            .order_by(Fix.t)
        ).all()
        session.commit()
    assert [tuple(row) for row in stored] == [
        (f.t, f.lat, f.lon, f.heading_deg, f.speed_mps, f.quality, f.hdop, f.satellites)
        for f in given
    ]


def stored_count(session: Session, run_id: int) -> tuple[int, int]:
    """The run row's ``fix_count`` and the fixes counted."""
    kept = session.scalar(select(Run.fix_count).where(Run.id == run_id))
    counted = session.scalar(select(func.count()).select_from(Fix).where(Fix.run_id == run_id))
    session.commit()
    return int(kept or 0), int(counted or 0)


@pytest.mark.parametrize("size", [10, ingest.COPY_MIN_ROWS + 10])
def test_the_run_keeps_its_fix_count_through_retried_and_racing_batches(engine: Engine, size: int):
    with Session(engine, expire_on_commit=False) as session:
        plan = a_plan(session)
        run = a_run(session, plan)
        upload = runs.create_run_from_columns(
            session, plan, ingest.collect(fixes(0, size)), source="csv", report={}, name="u"
        )
        assert stored_count(session, upload.id) == (size, size)
    errors: list[BaseException] = []

    def logger(worker: int) -> None:
        try:
            with Session(engine, expire_on_commit=False) as session:
                for i in range(6):  # overlapping batches, each sent twice
                    batch = ingest.collect(
                        fixes((worker + i) * size // 2, (worker + i + 2) * size // 2)
                    )
                    for _ in range(2):
                        write(session, lambda s, b=batch: ingest.store_fixes(s, run.id, b))
        except BaseException as exc:  # pragma: no cover - the assertion shows it
            errors.append(exc)

    threads = [threading.Thread(target=logger, args=(w,)) for w in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    with Session(engine) as session:
        kept, counted = stored_count(session, run.id)
        # Batches [(w + i) h, (w + i + 2) h) for w < 4, i < 6: the times [0, 10 h), once each.
        assert kept == counted == 10 * (size // 2)
        assert runs.count_fixes(session, run.id) == counted


def test_a_new_run_copies_its_fixes_all_or_nothing(engine: Engine):
    with Session(engine, expire_on_commit=False) as session:
        plan = a_plan(session)
        columns = ingest.collect(fixes(0, 3000))
        run = runs.create_run_from_columns(
            session, plan, columns, source="csv", report={"fixes": 3000}, name="upload"
        )
        assert len(stored_times(session, run.id)) == 3000

        def fails_halfway(s: Session) -> None:
            other = Run(
                plan_id=plan.id,
                organisation_id=plan.organisation_id,
                name="broken",
                source="csv",
                import_report={},
            )
            s.add(other)
            s.flush()
            ingest.store_fixes(s, other.id, columns, new_run=True)
            raise RuntimeError("the server died here")

        with pytest.raises(RuntimeError):
            write(session, fails_halfway)
        assert session.scalar(select(func.count()).select_from(Run)) == 1
        assert session.scalar(select(func.count()).select_from(Fix)) == 3000


def test_collect_sorts_keeps_the_first_of_equal_times_and_maps_none_to_nan():
    columns = ingest.collect(
        [
            TrackFix(T0 + 2, 1.0, 2.0),
            TrackFix(T0 + 1, 3.0, 4.0, speed_mps=1.5),
            TrackFix(T0 + 2, 9, 9),
        ]
    )
    assert columns.t.tolist() == [T0 + 1, T0 + 2]
    assert columns.lat.tolist() == [3.0, 1.0]
    assert columns.duplicates == 1
    assert np.isnan(columns.speed_mps[1]) and columns.speed_mps[0] == 1.5
    rows = list(columns.rows(7, ("run_id", "t", "speed_mps", "satellites")))
    assert rows == [(7, T0 + 1, 1.5, None), (7, T0 + 2, None, None)]


def test_a_write_for_a_plan_deleted_meanwhile_is_a_404(engine: Engine):
    with Session(engine, expire_on_commit=False) as session:
        plan_id = a_plan(session).id
        with Session(engine) as other:  # another request deletes it
            delete_row(other, Plan, plan_id, kind="plan")
        org_id = organisation_id(session)
        simulation = Simulation(
            plan_id=plan_id, organisation_id=org_id, config={}, metrics={}, tracks={}
        )
        with pytest.raises(NotFoundError, match=f"plan {plan_id} not found"):
            add_row(session, simulation, parent=(Plan, plan_id, "plan"))
        with pytest.raises(NotFoundError):
            delete_row(session, Plan, plan_id, kind="plan")
        with pytest.raises(ConflictError):  # a foreign key broken without a parent named
            add_row(session, simulation)


def test_concurrent_writers_all_succeed(engine: Engine):
    """Eight threads write 25 rows each as fast as they can: none fails, none is lost."""
    errors: list[BaseException] = []
    with Session(engine) as session:
        org_id = organisation_id(session)

    def writer(worker: int) -> None:
        try:
            with Session(engine, expire_on_commit=False) as session:
                for i in range(25):
                    add_row(
                        session,
                        Plan(
                            name=f"{worker}-{i}",
                            organisation_id=org_id,
                            request={},
                            stats={},
                            waypoints=[],
                            geojson={},
                        ),
                    )
        except BaseException as exc:  # pragma: no cover - the assertion shows it
            errors.append(exc)

    threads = [threading.Thread(target=writer, args=(w,)) for w in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    with engine.connect() as conn:
        assert conn.execute(text("SELECT count(*) FROM plans")).scalar_one() == 200


def test_an_nmea_upload_keeps_its_gga_quality_through_the_bulk_path(engine: Engine):
    """An NMEA log read as a stream and stored in bulk (``COPY`` on PostgreSQL) keeps the
    quality, HDOP and satellites of each GGA (i10's columns), and the receiver shares."""
    import datetime as dt
    import io

    from app.receiver import receiver_report
    from app.tracks import read_track
    from tests.app.track_files import RUN_START, nmea_lines, simulated_run

    quality = [4] * 360 + [5] * 180 + [2] * 60  # RTK fixed, RTK float, DGPS
    assert len(quality) > ingest.COPY_MIN_ROWS  # so PostgreSQL takes the COPY path
    track = simulated_run()
    n = len(quality)
    times = [RUN_START + dt.timedelta(seconds=round(float(t), 2)) for t in track.time_s[:n]]
    log = "\r\n".join(nmea_lines(times, track.lon[:n], track.lat[:n], quality=quality)) + "\r\n"
    stream = read_track(io.BytesIO(log.encode()))
    assert stream.format == "nmea"
    columns = ingest.collect(stream.fixes)
    assert "quality" in ingest.fix_columns() and "hdop" in ingest.fix_columns()
    with Session(engine, expire_on_commit=False) as session:
        plan = a_plan(session)
        run = runs.create_run_from_columns(
            session, plan, columns, source="nmea", report=stream.report, name="rtk"
        )
        stored = session.scalars(
            select(Fix.quality).where(Fix.run_id == run.id).order_by(Fix.t)
        ).all()
        assert stored == ["rtk_fixed"] * 360 + ["rtk_float"] * 180 + ["dgps"] * 60
        assert session.scalar(select(func.count()).where(Fix.hdop.is_(None))) == 0
        assert session.scalar(select(func.count()).where(Fix.satellites.is_(None))) == 0
        loaded = runs.load_track(session, run.id)
        session.commit()
    shares = receiver_report(loaded.quality, loaded.hdop, loaded.satellites)["shares"]
    assert shares["rtk_fixed"] == 0.6 and shares["rtk_float"] == 0.3 and shares["dgps"] == 0.1
