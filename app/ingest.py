"""Bulk ingestion of a run's fixes: parsed fixes to compact columns, columns to the database.

An upload is parsed as a stream (:func:`app.tracks.read_track`) into :class:`FixColumns`
(about 60 bytes a fix: numpy arrays, never one Python object per fix, see :func:`collect`),
sorted by time with one fix per timestamp, before any write. Then the columns are stored in
one short transaction through the database's bulk path:

- **PostgreSQL**: binary ``COPY`` (psycopg's ``Cursor.copy``) straight into ``fixes`` for a
  run made in the same transaction (it has no fix yet, and the columns hold one fix per
  timestamp), else into a temporary table, then ``INSERT INTO fixes … SELECT … ON CONFLICT
  (run_id, t) DO NOTHING``;
- **SQLite**: the driver's ``executemany`` of ``INSERT … ON CONFLICT DO NOTHING``, in the
  same transaction.

Either way a timestamp the run already has is not stored again, and the upload's transaction
stores all of its fixes or none. Columns the ``fixes`` table has beyond the five base ones
(``quality``, ``hdop``, ``satellites``, where a migration adds them) are written too.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
import numpy.typing as npt
from sqlalchemy.orm import Session

from app.models import Fix
from app.track_fixes import TrackFix

#: Rows made into Python tuples at a time when the columns are written.
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


def collect(fixes: Iterable[TrackFix]) -> FixColumns:
    """Consume ``fixes`` into :class:`FixColumns`, sorted by time, first of each time kept.

    Each value is appended to a growing :class:`array.array` per column, which the columns then
    share (no copy): memory is the columns (about 60 bytes a fix, plus up to an eighth while
    they grow), never one Python object per fix nor the columns twice. (Arrays that grow by
    ``realloc`` move their pages instead of copying them; batches joined at the end would leave
    the freed batches in the process's resident memory.) Out of order, the columns are sorted
    one at a time. A :class:`~app.track_fixes.TrackFormatError` raised while reading propagates
    unchanged.

    Examples
    --------
    >>> cols = collect([TrackFix(2, 1.0, 1.0), TrackFix(1, 0.0, 0.0), TrackFix(2, 5.0, 5.0)])
    >>> cols.t.tolist(), cols.lat.tolist(), cols.duplicates
    ([1, 2], [0.0, 1.0], 1)
    """
    nan = math.nan
    t, lat, lon = array("q"), array("d"), array("d")
    heading, speed, hdop, satellites = array("d"), array("d"), array("d"), array("d")
    quality = array("B")  # index into ``names`` (None and the few FIX_QUALITIES)
    names: list[str | None] = [None]
    codes: dict[str | None, int] = {None: 0}
    add_t, add_lat, add_lon = t.append, lat.append, lon.append
    add_heading, add_speed, add_hdop = heading.append, speed.append, hdop.append
    add_satellites, add_quality = satellites.append, quality.append
    for fix in fixes:
        add_t(fix.t)
        add_lat(fix.lat)
        add_lon(fix.lon)
        add_heading(nan if fix.heading_deg is None else fix.heading_deg)
        add_speed(nan if fix.speed_mps is None else fix.speed_mps)
        add_hdop(nan if fix.hdop is None else fix.hdop)
        add_satellites(nan if fix.satellites is None else fix.satellites)
        code = codes.get(fix.quality)
        if code is None:  # a quality not seen yet in this file
            code = codes[fix.quality] = len(names)
            names.append(fix.quality)
        add_quality(code)
    columns: list[npt.NDArray[Any]] = [
        np.frombuffer(t, dtype=np.int64) if len(t) else np.array([], dtype=np.int64),
        *(
            np.frombuffer(c, dtype=np.float64) if len(c) else np.array([], dtype=np.float64)
            for c in (lat, lon, heading, speed, hdop, satellites)
        ),
        np.array(names, dtype=object)[np.frombuffer(quality, dtype=np.uint8)]
        if len(quality)
        else np.array([], dtype=object),
    ]
    del quality
    if len(columns[0]) < 2 or (np.diff(columns[0]) > 0).all():  # in time order: nothing to do
        return _fix_columns(columns, duplicates=0)
    order = np.argsort(columns[0], kind="stable")  # stable: the first of equal times stays first
    ordered = columns[0][order]
    keep = np.ones(len(ordered), dtype=bool)
    keep[1:] = ordered[1:] != ordered[:-1]
    picked = order[keep]
    duplicates = int(len(ordered) - keep.sum())
    del order, ordered, keep
    for i in range(len(columns)):  # one column at a time: one extra copy at most
        columns[i] = columns[i][picked]
    return _fix_columns(columns, duplicates=duplicates)


def _fix_columns(columns: list[npt.NDArray[Any]], *, duplicates: int) -> FixColumns:
    t, lat, lon, heading, speed, hdop, satellites, quality = columns
    return FixColumns(t, lat, lon, heading, speed, hdop, satellites, quality, duplicates)


def columns_from_fixes(fixes: Iterable[TrackFix]) -> FixColumns:
    """Return ``fixes`` as :class:`FixColumns` (a live batch: already small)."""
    return collect(fixes)


def fix_columns() -> tuple[str, ...]:
    """Return the columns written: the base ones and the optional ones the table has."""
    present = Fix.__table__.c
    return (*BASE_COLUMNS, *(name for name in OPTIONAL_COLUMNS if name in present))


def store_fixes(session: Session, run_id: int, fixes: FixColumns, *, new_run: bool = False) -> int:
    """Insert ``fixes`` into run ``run_id`` in the session's transaction; return how many were new.

    Timestamps the run already has are skipped (``ON CONFLICT (run_id, t) DO NOTHING``), and
    the run's ``fix_count`` is raised by the number stored, in the same transaction. Not
    committed here: the caller's transaction decides (all or nothing).

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
    mark = "%s" if dialect == "postgresql" else "?"
    cursor: Any = dbapi_connection.cursor()  # the driver's own (executemany takes iterators)
    try:
        if dialect == "postgresql" and new_run:
            _copy_binary(cursor, "fixes", names, fixes.rows(run_id, columns))
            stored = len(fixes)
        elif dialect == "postgresql" and len(fixes) >= COPY_MIN_ROWS:
            stored = _copy_postgresql(cursor, names, fixes.rows(run_id, columns))
        else:
            marks = ", ".join([mark] * len(columns))
            cursor.executemany(
                f"INSERT INTO fixes ({names}) VALUES ({marks}) ON CONFLICT (run_id, t) DO NOTHING",
                fixes.rows(run_id, columns),
            )
            stored = int(cursor.rowcount)
        if stored:
            # Last in the transaction: concurrent batches of a run queue here (the row's lock)
            # only once their fixes are in, and each adds what it stored itself.
            cursor.execute(
                f"UPDATE runs SET fix_count = fix_count + {mark} WHERE id = {mark}",
                (stored, run_id),
            )
        return stored
    finally:
        cursor.close()


def _copy_postgresql(cursor: Any, names: str, rows: Iterator[tuple[Any, ...]]) -> int:
    """``COPY`` the rows into a temporary table, then move the new ones into ``fixes``."""
    cursor.execute(
        "CREATE TEMPORARY TABLE fixes_load (LIKE fixes INCLUDING DEFAULTS) ON COMMIT DROP"
    )
    _copy_binary(cursor, "fixes_load", names, rows)
    cursor.execute(
        f"INSERT INTO fixes ({names}) SELECT {names} FROM fixes_load "
        "ON CONFLICT (run_id, t) DO NOTHING"
    )
    stored = int(cursor.rowcount)
    cursor.execute("DROP TABLE fixes_load")
    return stored


def _copy_binary(cursor: Any, table: str, names: str, rows: Iterator[tuple[Any, ...]]) -> None:
    """``COPY`` ``rows`` into ``table``'s columns ``names`` in the binary format.

    Binary, because the server then reads each number as it is stored instead of parsing its
    text, and psycopg sends it without formatting it (216,000 fixes: 0.12 s of client CPU, was
    0.36 s). The binary format does not say the types, so they are read from the table itself
    (a query for no row): whatever migration made the columns, each value is sent as its
    column's type.
    """
    cursor.execute(f"SELECT {names} FROM {table} LIMIT 0")
    types = [column.type_code for column in cursor.description]
    with cursor.copy(f"COPY {table} ({names}) FROM STDIN (FORMAT BINARY)") as copy:
        copy.set_types(types)
        for row in rows:
            copy.write_row(row)
