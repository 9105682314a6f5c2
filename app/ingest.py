"""Bulk ingestion of a run's fixes: parsed fixes to compact columns, columns to the database.

An upload is parsed as a stream (:func:`app.tracks.read_track`) into :class:`FixColumns`
(about 60 bytes a fix: numpy arrays, never one Python object per fix), sorted by time with one
fix per timestamp, before any write. Then the columns are stored in one short transaction
through the database's bulk path:

- **PostgreSQL**: ``COPY`` (psycopg's ``Cursor.copy``) straight into ``fixes`` for a run made
  in the same transaction (it has no fix yet, and the columns hold one fix per timestamp), else
  into a temporary table, then ``INSERT INTO fixes … SELECT … ON CONFLICT (run_id, t) DO
  NOTHING``;
- **SQLite**: the driver's ``executemany`` of ``INSERT … ON CONFLICT DO NOTHING``, in the
  same transaction.

Either way a timestamp the run already has is not stored again, and the upload's transaction
stores all of its fixes or none. Columns the ``fixes`` table has beyond the five base ones
(``quality``, ``hdop``, ``satellites``, where a migration adds them) are written too.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
import numpy.typing as npt
from sqlalchemy.orm import Session

from app.models import Fix
from app.tracks import TrackFix

#: Fixes converted to arrays at a time while parsing.
BATCH_ROWS: Final = 10_000
#: Smallest batch sent through ``COPY`` on PostgreSQL (smaller ones: one ``executemany``).
COPY_MIN_ROWS: Final = 500
#: The columns every ``fixes`` table has, and the optional ones written where they exist.
BASE_COLUMNS: Final = ("run_id", "t", "lat", "lon", "heading_deg", "speed_mps")
OPTIONAL_COLUMNS: Final = ("quality", "hdop", "satellites")


@dataclass(frozen=True, slots=True)
class FixColumns:
    """A run's fixes as columns, sorted by time, one fix per timestamp.

    Attributes
    ----------
    t : int64 array
        Times [µs since the Unix epoch], strictly increasing.
    lat, lon : float arrays
        WGS84 [deg].
    heading_deg, speed_mps, hdop, satellites : float arrays
        NaN where unknown.
    quality : object array
        Fix quality names, None where unknown.
    duplicates : int
        Fixes dropped because an earlier one had the same time.
    """

    t: npt.NDArray[np.int64]
    lat: npt.NDArray[np.float64]
    lon: npt.NDArray[np.float64]
    heading_deg: npt.NDArray[np.float64]
    speed_mps: npt.NDArray[np.float64]
    hdop: npt.NDArray[np.float64]
    satellites: npt.NDArray[np.float64]
    quality: npt.NDArray[np.object_]
    duplicates: int = 0

    def __len__(self) -> int:
        return len(self.t)

    def rows(self, run_id: int, columns: Iterable[str]) -> Iterator[tuple[Any, ...]]:
        """Yield one tuple per fix with the values of ``columns`` (None for unknown).

        Made :data:`BATCH_ROWS` at a time, so the Python objects of one batch only exist at once.
        """
        names = list(columns)
        for start in range(0, len(self.t), BATCH_ROWS):
            stop = min(start + BATCH_ROWS, len(self.t))
            lists: list[list[Any]] = []
            for name in names:
                if name == "run_id":
                    lists.append([run_id] * (stop - start))
                elif name == "quality":
                    lists.append(self.quality[start:stop].tolist())
                else:
                    values: list[Any] = getattr(self, name)[start:stop].tolist()
                    if name == "satellites":
                        lists.append([None if v != v else int(v) for v in values])
                    elif name != "t":
                        lists.append([None if v != v else v for v in values])  # NaN -> NULL
                    else:
                        lists.append(values)
            yield from zip(*lists, strict=True)


def _nan(value: float | None) -> float:
    return np.nan if value is None else value


def collect(fixes: Iterable[TrackFix], *, batch_rows: int = BATCH_ROWS) -> FixColumns:
    """Consume ``fixes`` into :class:`FixColumns`, sorted by time, first of each time kept.

    Memory is the columns (about 60 bytes a fix) plus one batch of ``batch_rows`` fix objects;
    a :class:`~app.tracks.TrackFormatError` raised while reading propagates unchanged.

    Examples
    --------
    >>> cols = collect([TrackFix(2, 1.0, 1.0), TrackFix(1, 0.0, 0.0), TrackFix(2, 5.0, 5.0)])
    >>> cols.t.tolist(), cols.lat.tolist(), cols.duplicates
    ([1, 2], [0.0, 1.0], 1)
    """
    chunks: list[tuple[npt.NDArray[Any], ...]] = []
    batch: list[TrackFix] = []

    def flush() -> None:
        chunks.append(
            (
                np.fromiter((f.t for f in batch), dtype=np.int64, count=len(batch)),
                np.fromiter((f.lat for f in batch), dtype=np.float64, count=len(batch)),
                np.fromiter((f.lon for f in batch), dtype=np.float64, count=len(batch)),
                np.fromiter((_nan(f.heading_deg) for f in batch), np.float64, len(batch)),
                np.fromiter((_nan(f.speed_mps) for f in batch), np.float64, len(batch)),
                np.fromiter((_nan(f.hdop) for f in batch), np.float64, len(batch)),
                np.fromiter(
                    (_nan(None if f.satellites is None else float(f.satellites)) for f in batch),
                    np.float64,
                    len(batch),
                ),
                np.array([f.quality for f in batch], dtype=object),
            )
        )
        batch.clear()

    for fix in fixes:
        batch.append(fix)
        if len(batch) >= batch_rows:
            flush()
    if batch:
        flush()
    if not chunks:
        empty = np.array([], dtype=np.float64)
        return FixColumns(
            np.array([], dtype=np.int64), empty, empty, empty, empty, empty, empty,
            np.array([], dtype=object),
        )  # fmt: skip
    columns = [np.concatenate(parts) for parts in zip(*chunks, strict=True)]
    chunks.clear()
    if (np.diff(columns[0]) > 0).all():  # a log in time order: nothing to sort or drop
        lat, lon, heading, speed, hdop, satellites, quality = columns[1:]
        return FixColumns(columns[0], lat, lon, heading, speed, hdop, satellites, quality)
    order = np.argsort(columns[0], kind="stable")  # stable: the first of equal times stays first
    t = columns[0][order]
    keep = np.ones(len(t), dtype=bool)
    keep[1:] = t[1:] != t[:-1]
    picked = order[keep]
    lat, lon, heading, speed, hdop, satellites, quality = (c[picked] for c in columns[1:])
    return FixColumns(
        t[keep], lat, lon, heading, speed, hdop, satellites, quality,
        duplicates=int(len(t) - keep.sum()),
    )  # fmt: skip


def columns_from_fixes(fixes: Iterable[TrackFix]) -> FixColumns:
    """Return ``fixes`` as :class:`FixColumns` (a live batch: already small)."""
    return collect(fixes)


def fix_columns() -> tuple[str, ...]:
    """Return the columns written: the base ones and the optional ones the table has."""
    present = Fix.__table__.c
    return (*BASE_COLUMNS, *(name for name in OPTIONAL_COLUMNS if name in present))


def store_fixes(session: Session, run_id: int, fixes: FixColumns, *, new_run: bool = False) -> int:
    """Insert ``fixes`` into run ``run_id`` in the session's transaction; return how many were new.

    Timestamps the run already has are skipped (``ON CONFLICT (run_id, t) DO NOTHING``).
    Not committed here: the caller's transaction decides (all or nothing).

    Parameters
    ----------
    session : Session
        In a write transaction (see :func:`app.db.write`).
    run_id : int
    fixes : FixColumns
    new_run : bool
        The run was created in this transaction, so it has no fix that could conflict
        (PostgreSQL then copies straight into ``fixes``).

    Returns
    -------
    int
    """
    if not len(fixes):
        return 0
    columns = fix_columns()
    connection = session.connection()
    dbapi_connection = connection.connection.dbapi_connection
    assert dbapi_connection is not None
    names = ", ".join(columns)
    dialect = connection.dialect.name
    cursor: Any = dbapi_connection.cursor()  # the driver's own (executemany takes iterators)
    try:
        if dialect == "postgresql" and new_run:
            with cursor.copy(f"COPY fixes ({names}) FROM STDIN") as copy:
                for row in fixes.rows(run_id, columns):
                    copy.write_row(row)
            return len(fixes)
        if dialect == "postgresql" and len(fixes) >= COPY_MIN_ROWS:
            return _copy_postgresql(cursor, names, fixes.rows(run_id, columns))
        marks = ", ".join(["%s" if dialect == "postgresql" else "?"] * len(columns))
        cursor.executemany(
            f"INSERT INTO fixes ({names}) VALUES ({marks}) ON CONFLICT (run_id, t) DO NOTHING",
            fixes.rows(run_id, columns),
        )
        return int(cursor.rowcount)
    finally:
        cursor.close()


def _copy_postgresql(cursor: Any, names: str, rows: Iterator[tuple[Any, ...]]) -> int:
    """``COPY`` the rows into a temporary table, then move the new ones into ``fixes``."""
    cursor.execute(
        "CREATE TEMPORARY TABLE fixes_load (LIKE fixes INCLUDING DEFAULTS) ON COMMIT DROP"
    )
    with cursor.copy(f"COPY fixes_load ({names}) FROM STDIN") as copy:
        for row in rows:
            copy.write_row(row)
    cursor.execute(
        f"INSERT INTO fixes ({names}) SELECT {names} FROM fixes_load "
        "ON CONFLICT (run_id, t) DO NOTHING"
    )
    stored = int(cursor.rowcount)
    cursor.execute("DROP TABLE fixes_load")
    return stored
