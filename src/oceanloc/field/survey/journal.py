"""A survey journal that loses nothing: every GPS fix, heading and range appended to SQLite as it arrives.

Write-ahead logging (``journal_mode=WAL``) with ``synchronous=FULL``; a record added on its own
(:meth:`Journal.add_fix`, ...) is one transaction, a recorded file (:func:`append_gps_log`,
:func:`append_range_log`) is written in transactions of :data:`APPEND_CHUNK` records in file order. A
process killed mid-write loses at most the transaction being written, never one already committed, so
what is committed of a file is always a prefix of it, and the journal re-opens in the state of its last
commit. Records are keyed by their content's identity
(fix: time; heading: the time of the fix it follows and its order after that fix; range: time and
beacon), so re-adding a record already stored changes nothing (idempotent ``INSERT OR IGNORE``); the
state read back is ordered by time, hence identical however often a stream is replayed.

A journal in use by ``oceanloc survey`` is *started* (:meth:`Journal.start`): its ``meta`` table holds
the format marker and the survey settings (strings, written in one transaction). :meth:`Journal.open`
opens only a started journal and never creates or modifies a file that is not one.

Nothing out of range goes in: every time, position, height, beacon id, range and heading is checked
against :mod:`oceanloc.io.qc`'s physical ranges before it is written (:func:`fix_problem`,
:func:`range_problem`, :func:`heading_problem`), and the append functions check a whole log before its
first write. Should a bad record be in a journal anyway (written by an older version or by hand), the
readers skip it and report it (:attr:`JournalRecords.invalid`, a logged warning), so every command still
works, and :meth:`Journal.remove_invalid` deletes it. SQLite failures are :class:`JournalError` naming
the journal: damaged pages, a read-only folder, a lock held past the timeout.

A live survey (``oceanloc survey run``) also keeps the USBL angles of each range (table ``usbl``, written
in the range's transaction) and its *events* (table ``events``: each epoch's estimate, plan and command
sent, link states, start and stop, as JSON), so a survey can be audited and replayed afterwards.

Results derived from the records can be kept beside them (table ``derived``: :meth:`Journal.store_derived`,
:meth:`Journal.derived`), each under the :meth:`Journal.fingerprint` of the records it was computed
from, so a reader that finds the same fingerprint can use the stored result instead of recomputing it
(``survey status`` on a 24-hour journal), and one that finds another recomputes. It is a cache: losing it
loses nothing, and no record depends on it.
"""

from __future__ import annotations

import itertools
import json
import logging
import math
import os
import sqlite3
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import DataError
from oceanloc.io.nmea import GpsLog
from oceanloc.io.qc import (
    BEACON_ID_RANGE,
    HEIGHT_RANGE_M,
    LAT_RANGE_DEG,
    MAX_RANGE_M,
    TIME_RANGE_UNIX_S,
    QcReport,
    out_of_range,
    time_problem,
)
from oceanloc.io.records import to_jsonable
from oceanloc.io.usbl import RangeLog

T = TypeVar("T")

FORMAT_KEY = "format"
JOURNAL_FORMAT = "oceanloc-survey-journal 1"
"""Value of the ``format`` meta key of a started journal."""

_LOG = logging.getLogger(__name__)

JOURNAL_LON_RANGE_DEG: tuple[float, float] = (-180.0, 360.0)
"""Longitudes the journal stores, degrees (east of Greenwich up to 360 is accepted as well)."""

HEADING_RANGE_DEG: tuple[float, float] = (0.0, 360.0)
"""True headings the journal stores, degrees clockwise from north."""

_SQLITE_MAGIC = b"SQLite format 3\x00"
_TABLES = {"meta", "fixes", "ranges", "headings", "usbl", "events", "derived"}
_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS fixes (t REAL PRIMARY KEY, lat REAL NOT NULL, lon REAL NOT NULL, h REAL NOT NULL);
CREATE TABLE IF NOT EXISTS ranges (t REAL NOT NULL, beacon INTEGER NOT NULL, range_m REAL NOT NULL,
                                   PRIMARY KEY (t, beacon));
CREATE TABLE IF NOT EXISTS headings (t REAL NOT NULL, seq INTEGER NOT NULL, heading_deg REAL NOT NULL,
                                     PRIMARY KEY (t, seq));
CREATE TABLE IF NOT EXISTS usbl (t REAL NOT NULL, beacon INTEGER NOT NULL, azimuth_deg REAL,
                                 elevation_deg REAL, PRIMARY KEY (t, beacon));
CREATE TABLE IF NOT EXISTS events (seq INTEGER PRIMARY KEY, t REAL NOT NULL, kind TEXT NOT NULL,
                                   body TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS derived (name TEXT PRIMARY KEY, fingerprint TEXT NOT NULL, t REAL NOT NULL,
                                    payload BLOB NOT NULL);
"""

EVENT_KINDS: tuple[str, ...] = ("start", "estimate", "plan", "command", "link", "stop")
"""Kinds of the live survey's journaled events (:meth:`Journal.add_event`): the run's start and options,
each epoch's estimate, plan and command sent, a link state change (HOLD and why), and the stop."""


class JournalError(DataError):
    """The journal file cannot be read or written: damaged, read-only, locked or not a journal."""


def _num(x: object) -> float:
    """``float(x)``, or NaN when it is not a number (a huge integer, text, None)."""
    try:
        return float(x)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        return math.nan


def _time_problem(t: object) -> str | None:
    return time_problem(_num(t))


def fix_problem(t_unix_s: object, lat_deg: object, lon_deg: object, h_m: object) -> str | None:
    """None if a fix may be stored, else what is wrong with it (the field, its value, the allowed range)."""
    return (
        _time_problem(t_unix_s)
        or out_of_range("latitude", _num(lat_deg), LAT_RANGE_DEG, "deg")
        or out_of_range("longitude", _num(lon_deg), JOURNAL_LON_RANGE_DEG, "deg")
        or out_of_range("height", _num(h_m), HEIGHT_RANGE_M, "m")
    )


def _beacon_problem(beacon: object) -> str | None:
    lo, hi = BEACON_ID_RANGE
    if isinstance(beacon, (int, np.integer)) and not isinstance(beacon, bool) and lo <= beacon <= hi:
        return None
    shown = str(beacon)
    shown = shown if len(shown) <= 24 else f"{shown[:10]}...{shown[-6:]} ({len(shown)} characters)"
    return f"beacon id {shown} is not an integer in [{lo}, {hi}]"


def range_problem(t_unix_s: object, beacon: object, range_m: object) -> str | None:
    """None if a range may be stored, else what is wrong with it (the field, its value, the allowed range)."""
    if problem := _time_problem(t_unix_s) or _beacon_problem(beacon):
        return problem
    r = _num(range_m)
    if not (math.isfinite(r) and 0.0 < r <= MAX_RANGE_M):
        return f"range {r:.12g} m is not in (0, {MAX_RANGE_M:g}] m"
    return None


def heading_problem(t_unix_s: object, seq: object, heading_deg: object) -> str | None:
    """None if a heading may be stored, else what is wrong with it."""
    if problem := _time_problem(t_unix_s):
        return problem
    if not (isinstance(seq, (int, np.integer)) and 0 <= seq <= BEACON_ID_RANGE[1]):
        return f"heading order {seq} is not an integer in [0, {BEACON_ID_RANGE[1]}]"
    return out_of_range("heading", _num(heading_deg), HEADING_RANGE_DEG, "deg")


def _sql_in(column: str, bounds: tuple[float, float], *, open_low: bool = False) -> str:
    """SQL true only for a number in the bounds (false for NULL, text, blobs, inf beyond them).

    No ``typeof`` test is needed: SQLite orders every INTEGER or REAL value below every TEXT or BLOB
    value, so text and blobs fail ``<= upper bound``, and NULL (NaN is stored as NULL) makes the whole
    condition NULL (read as false through ``IFNULL``).
    """
    if open_low:
        return f"({column} > {bounds[0]!r} AND {column} <= {bounds[1]!r})"
    return f"({column} BETWEEN {bounds[0]!r} AND {bounds[1]!r})"


_VALID_SQL: dict[str, str] = {
    "fixes": " AND ".join(
        [
            _sql_in("t", TIME_RANGE_UNIX_S),
            _sql_in("lat", LAT_RANGE_DEG),
            _sql_in("lon", JOURNAL_LON_RANGE_DEG),
            _sql_in("h", HEIGHT_RANGE_M),
        ]
    ),
    "ranges": " AND ".join(
        [
            _sql_in("t", TIME_RANGE_UNIX_S),
            "typeof(beacon) = 'integer'",
            _sql_in("beacon", (float(BEACON_ID_RANGE[0]), float(BEACON_ID_RANGE[1]))),
            _sql_in("range_m", (0.0, MAX_RANGE_M), open_low=True),
        ]
    ),
    "headings": " AND ".join(
        [
            _sql_in("t", TIME_RANGE_UNIX_S),
            "typeof(seq) = 'integer'",
            _sql_in("seq", (0.0, float(BEACON_ID_RANGE[1]))),
            _sql_in("heading_deg", HEADING_RANGE_DEG),
        ]
    ),
}
"""Per table, the SQL condition a stored row must meet to be read (the same checks as on the way in)."""

_COLUMNS = {"fixes": "t, lat, lon, h", "ranges": "t, beacon, range_m", "headings": "t, seq, heading_deg"}
_ORDER = {"fixes": "t", "ranges": "t, beacon", "headings": "t, seq"}
_PROBLEM = {"fixes": fix_problem, "ranges": range_problem, "headings": heading_problem}


_FINGERPRINT_SQL = {
    "fixes": "count(*), max(rowid), total(t), total(lat), total(lon), total(h), total(rowid * t), "
    "total(rowid * (lat + lon + h))",
    "ranges": "count(*), max(rowid), total(t), total(beacon), total(range_m), total(rowid * t), "
    "total(rowid * (beacon + range_m))",
}
"""Aggregates of the valid fixes and ranges that :meth:`Journal.fingerprint` is made of: counts, the last
row id, sums of every column and a row-id-weighted sum (so a value moved between records changes it)."""


def _fingerprint(*parts: tuple) -> str:
    return json.dumps([[v if v is None else repr(v) for v in part] for part in parts])


@dataclass(frozen=True, slots=True, kw_only=True)
class RecordSummary:
    """Counts of a journal's valid records, the time span of its fixes (UTC Unix seconds; NaN with no
    fix) and its :meth:`Journal.fingerprint`, read by SQL without reading the records
    (``survey status``)."""

    n_fixes: int
    n_headings: int
    n_ranges: int
    first_fix_t_unix_s: float
    last_fix_t_unix_s: float
    fingerprint: str


@dataclass(frozen=True, slots=True, kw_only=True)
class JournalEvent:
    """One journaled live-survey event: its number, Unix time (s), kind and JSON body."""

    seq: int
    t_unix_s: float
    kind: str
    body: dict


@dataclass(frozen=True, slots=True, kw_only=True)
class InvalidRecord:
    """A stored row that fails the checks on the way in (never written by this version; skipped on reading).

    Attributes
    ----------
    table : str
        ``fixes``, ``ranges`` or ``headings``.
    rowid : int
        SQLite rowid (what :meth:`Journal.remove_invalid` deletes).
    values : tuple
        The stored values, as stored.
    problem : str
        What is wrong (the field, its value, the allowed range).
    """

    table: str
    rowid: int
    values: tuple
    problem: str

    def __str__(self) -> str:
        return f"{self.table} row {self.rowid} {self.values}: {self.problem}"


class Journal:
    """An open survey journal (a context manager; close it or use ``with``).

    Parameters
    ----------
    path : str or Path
        The SQLite file.
    create : bool
        Create the file if it does not exist (default). With ``False`` a missing file is a
        :class:`DataError` and nothing is created.
    timeout_s : float
        How long a write waits for another writer to finish, seconds.

    Raises
    ------
    DataError
        If the file is not SQLite, or is an SQLite database with tables of its own (not a journal).
    """

    def __init__(self, path: str | Path, *, create: bool = True, timeout_s: float = 30.0) -> None:
        self.path = Path(path)
        self._timeout_s = timeout_s
        if not create and not self.path.is_file():
            raise DataError(f"{self.path}: no survey journal here (start one with `oceanloc survey start`)")
        if create and not self.path.parent.is_dir():
            raise DataError(f"{self.path}: folder {self.path.parent} does not exist")
        # A journal in a read-only folder (or a read-only file) is opened read-only, so it can still be
        # read; a write then fails with a message saying why (see _read_only_reason).
        self.read_only = not create and self._read_only_reason() is not None
        try:
            if create:
                self._db = sqlite3.connect(self.path, isolation_level=None, timeout=timeout_s)
            elif self.read_only:
                self._db = self._connect_read_only(timeout_s)
            else:  # mode=rw: never creates a file
                uri = f"{self.path.resolve().as_uri()}?mode=rw"
                self._db = sqlite3.connect(uri, uri=True, isolation_level=None, timeout=timeout_s)
        except sqlite3.Error as exc:
            raise JournalError(self._explain(exc, "cannot open as a survey journal")) from None
        try:
            # Look before writing anything: WAL mode and our tables must not be forced on a foreign file.
            names = {r[0] for r in self._db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            foreign = names - _TABLES
            if foreign:
                raise JournalError(
                    f"{self.path}: not a survey journal (an SQLite database with tables "
                    f"{', '.join(sorted(foreign))})"
                )
            if not create and not {"meta", "fixes", "ranges"} <= names:
                raise JournalError(f"{self.path}: not a survey journal (no journal tables)")
            if not self.read_only:
                self._db.execute("PRAGMA journal_mode=WAL")
                self._db.execute("PRAGMA synchronous=FULL")
                self._db.executescript(_SCHEMA)
        except sqlite3.Error as exc:
            self._db.close()
            raise JournalError(self._explain(exc, "not a survey journal")) from None
        except DataError:
            self._db.close()
            raise

    def _connect_read_only(self, timeout_s: float) -> sqlite3.Connection:
        """A read-only connection: ``mode=ro`` where SQLite can use the WAL index beside the file, else
        ``immutable=1`` (a read-only folder where no ``-shm`` file can be made; no one can write there,
        and a journal closed cleanly has everything in the main file)."""
        base = self.path.resolve().as_uri()
        db = sqlite3.connect(f"{base}?mode=ro", uri=True, isolation_level=None, timeout=timeout_s)
        try:
            db.execute("SELECT name FROM sqlite_master").fetchall()
            return db
        except sqlite3.Error:
            db.close()
        return sqlite3.connect(f"{base}?immutable=1", uri=True, isolation_level=None, timeout=timeout_s)

    def _read_only_reason(self) -> str | None:
        """Why SQLite cannot write here (a read-only folder or file), or None."""
        folder = self.path.parent if str(self.path.parent) else Path(".")
        if not os.access(folder, os.W_OK):
            return (
                f"the folder {folder} is read-only (a journal needs to create {self.path.name}-wal and "
                f"{self.path.name}-shm beside it); copy the journal to a writable folder"
            )
        if self.path.exists() and not os.access(self.path, os.W_OK):
            return "the file is read-only; make it writable or copy it"
        return None

    def _looks_like_sqlite(self) -> bool:
        try:
            with self.path.open("rb") as f:
                return f.read(len(_SQLITE_MAGIC)) == _SQLITE_MAGIC
        except OSError:
            return False

    def _explain(self, exc: sqlite3.Error, what: str) -> str:
        """One-line message for an SQLite failure: read-only, damaged, locked, else ``what`` and SQLite's."""
        name = getattr(exc, "sqlite_errorname", "")
        denied = name.startswith(("SQLITE_READONLY", "SQLITE_CANTOPEN", "SQLITE_PERM"))
        denied = denied or "readonly" in str(exc)
        if denied and (reason := self._read_only_reason()):
            return f"{self.path}: cannot use the journal: {reason}"
        if name.startswith("SQLITE_CORRUPT") or (
            name.startswith("SQLITE_NOTADB") and self._looks_like_sqlite()
        ):
            return (
                f"{self.path}: the journal file is damaged ({exc}); nothing was changed. Keep a copy, then "
                f"recover what can be read with `sqlite3 {self.path.name} .recover`"
            )
        if name.startswith(("SQLITE_BUSY", "SQLITE_LOCKED")):
            return f"{self.path}: {what} ({exc}); another process holds the journal, try again"
        if name.startswith(("SQLITE_FULL", "SQLITE_IOERR")):
            return f"{self.path}: {what} ({exc}); check the disk"
        return f"{self.path}: {what} ({exc})"

    def _query(self, sql: str, params: tuple = ()) -> list[tuple]:
        """All rows of one read; SQLite failures (a damaged page, ...) are :class:`JournalError`."""
        try:
            return self._db.execute(sql, params).fetchall()
        except sqlite3.Error as exc:
            raise JournalError(self._explain(exc, "cannot read the journal")) from None

    @classmethod
    def start(cls, path: str | Path, meta: Mapping[str, str]) -> Journal:
        """Create (or adopt an unstarted) journal and write the format marker and ``meta`` atomically.

        Raises
        ------
        DataError
            If the journal was already started (its settings are never overwritten).
        """
        journal = cls(path, create=True)
        if FORMAT_KEY in journal.meta():
            journal.close()
            raise JournalError(f"{journal.path}: survey already started; start a new survey in a new file")
        journal.set_meta_many({**meta, FORMAT_KEY: JOURNAL_FORMAT})
        return journal

    @classmethod
    def open(cls, path: str | Path) -> Journal:
        """Open a started journal; a missing, foreign or never-started file is a :class:`DataError`."""
        journal = cls(path, create=False)
        fmt = journal.meta().get(FORMAT_KEY)
        if fmt != JOURNAL_FORMAT:
            journal.close()
            if fmt is None:
                raise DataError(
                    f"{journal.path}: survey journal was never started (run `oceanloc survey start` first)"
                )
            raise DataError(
                f"{journal.path}: unsupported journal format {fmt!r} (expected {JOURNAL_FORMAT!r})"
            )
        return journal

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._db.close()

    def set_meta(self, key: str, value: str) -> None:
        self.set_meta_many({key: value})

    def set_meta_many(self, items: Mapping[str, str]) -> None:
        """Write several meta keys in one transaction."""
        self._write("INSERT OR REPLACE INTO meta VALUES (?, ?)", [(k, str(v)) for k, v in items.items()])

    def meta(self) -> dict[str, str]:
        return dict(self._query("SELECT key, value FROM meta"))

    def add_fix(self, t_unix_s: float, lat_deg: float, lon_deg: float, h_m: float) -> bool:
        """Append one GPS fix in its own transaction; False if a fix at that time was already stored.

        Raises
        ------
        DataError
            On a value out of range (see :func:`fix_problem`), naming the field and the allowed range;
            nothing is written.
        """
        if problem := fix_problem(t_unix_s, lat_deg, lon_deg, h_m):
            raise DataError(f"fix at {_num(t_unix_s):.12g} s: {problem}")
        values = (float(t_unix_s), float(lat_deg), float(lon_deg), float(h_m))
        return self._write("INSERT OR IGNORE INTO fixes VALUES (?, ?, ?, ?)", [values]) == 1

    def add_range(self, t_unix_s: float, beacon: int, range_m: float) -> bool:
        """Append one range in its own transaction; False if a range at that time and beacon was stored.

        Raises
        ------
        DataError
            On a value out of range (see :func:`range_problem`); nothing is written.
        """
        if problem := range_problem(t_unix_s, beacon, range_m):
            raise DataError(f"range at {_num(t_unix_s):.12g} s: {problem}")
        row = (float(t_unix_s), int(beacon), float(range_m))
        return self._write("INSERT OR IGNORE INTO ranges VALUES (?, ?, ?)", [row]) == 1

    def add_usbl_range(
        self,
        t_unix_s: float,
        beacon: int,
        range_m: float,
        azimuth_deg: float | None,
        elevation_deg: float | None,
    ) -> bool:
        """Append one range with its USBL angles (degrees; None when the modem gave none), both in one
        transaction; False if a range at that time and beacon was stored (nothing is changed then)."""
        if problem := range_problem(t_unix_s, beacon, range_m):
            raise DataError(f"range at {_num(t_unix_s):.12g} s: {problem}")
        for name, angle in (("azimuth", azimuth_deg), ("elevation", elevation_deg)):
            if angle is not None and not (math.isfinite(angle) and -360.0 <= angle <= 360.0):
                raise DataError(
                    f"range at {_num(t_unix_s):.12g} s: USBL {name} {angle} deg not in [-360, 360]"
                )
        row = (float(t_unix_s), int(beacon), float(range_m))
        angles = (float(t_unix_s), int(beacon), azimuth_deg, elevation_deg)

        def work(db: sqlite3.Connection) -> bool:
            new = db.execute("INSERT OR IGNORE INTO ranges VALUES (?, ?, ?)", row).rowcount == 1
            if new and (azimuth_deg is not None or elevation_deg is not None):
                db.execute("INSERT OR IGNORE INTO usbl VALUES (?, ?, ?, ?)", angles)
            return new

        return self._transaction(work)

    def usbl_angles(self) -> FloatArray:
        """Stored USBL angles ordered by time and beacon, ``(u, 4)``: t, beacon, azimuth, elevation
        (degrees; NaN where the modem gave none)."""
        if not self._has_table("usbl"):
            return np.zeros((0, 4))
        rows = self._query("SELECT t, beacon, azimuth_deg, elevation_deg FROM usbl ORDER BY t, beacon")
        return np.asarray(rows, dtype=float).reshape(-1, 4)

    def add_event(self, t_unix_s: float, kind: str, body: Mapping[str, object]) -> int:
        """Journal one live-survey event (:data:`EVENT_KINDS`) with its JSON body; returns its number."""
        return self.add_events(t_unix_s, [(kind, body)])[0]

    def add_events(self, t_unix_s: float, events: list[tuple[str, Mapping[str, object]]]) -> list[int]:
        """Journal several events of one time in one transaction; returns their numbers."""
        rows = []
        for kind, body in events:
            if kind not in EVENT_KINDS:
                raise DataError(f"event kind {kind!r} is not one of {', '.join(EVENT_KINDS)}")
            rows.append(
                (float(t_unix_s), kind, json.dumps(to_jsonable(body), allow_nan=False, separators=(",", ":")))
            )
        sql = "INSERT INTO events (t, kind, body) VALUES (?, ?, ?)"
        return self._transaction(lambda db: [int(db.execute(sql, row).lastrowid) for row in rows])

    def events(self, kind: str | None = None, *, after_seq: int = 0) -> list[JournalEvent]:
        """Journaled events in order, of one kind or all, numbered above ``after_seq``."""
        if not self._has_table("events"):
            return []
        where, params = "seq > ?", (int(after_seq),)
        if kind is not None:
            where, params = "seq > ? AND kind = ?", (int(after_seq), kind)
        rows = self._query(f"SELECT seq, t, kind, body FROM events WHERE {where} ORDER BY seq", params)
        return [
            JournalEvent(seq=int(q), t_unix_s=float(t), kind=k, body=json.loads(b)) for q, t, k, b in rows
        ]

    def last_event(self, kind: str) -> JournalEvent | None:
        """The latest event of that kind, if any."""
        if not self._has_table("events"):
            return None
        rows = self._query(
            "SELECT seq, t, kind, body FROM events WHERE kind = ? ORDER BY seq DESC LIMIT 1", (kind,)
        )
        return (
            JournalEvent(
                seq=int(rows[0][0]), t_unix_s=float(rows[0][1]), kind=rows[0][2], body=json.loads(rows[0][3])
            )
            if rows
            else None
        )

    def _has_table(self, name: str) -> bool:
        return bool(self._query("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", (name,)))

    def add_heading(self, t_unix_s: float, seq: int, heading_deg: float) -> bool:
        """Append one true heading (degrees clockwise from north) in its own transaction.

        ``t_unix_s`` is the time of the fix the HDT sentence follows, ``seq`` its order after that fix
        (0 for the first); False if already stored.

        Raises
        ------
        DataError
            On a value out of range (see :func:`heading_problem`); nothing is written.
        """
        if problem := heading_problem(t_unix_s, seq, heading_deg):
            raise DataError(f"heading at {_num(t_unix_s):.12g} s: {problem}")
        row = (float(t_unix_s), int(seq), float(heading_deg))
        return self._write("INSERT OR IGNORE INTO headings VALUES (?, ?, ?)", [row]) == 1

    def _write(self, sql: str, rows: list[tuple]) -> int:
        """Run one statement over ``rows`` in one transaction; returns the rows changed."""
        return self._transaction(lambda db: db.executemany(sql, rows).rowcount)

    def _transaction(self, work: Callable[[sqlite3.Connection], T]) -> T:
        """Run ``work(connection)`` in one write transaction and return what it returns.

        SQLite failures (journal locked by another writer past the timeout, disk full, read-only file)
        are :class:`DataError` naming the journal; the transaction is rolled back, nothing committed is
        touched.
        """
        try:
            with self._db:
                self._db.execute("BEGIN IMMEDIATE")
                return work(self._db)
        except sqlite3.Error as exc:
            if self.read_only:
                raise JournalError(
                    f"{self.path}: the journal is read-only here: {self._read_only_reason()}"
                ) from None
            raise JournalError(self._explain(exc, "cannot write to the journal")) from None

    def fix_at(self, t_unix_s: float) -> tuple[float, float, float] | None:
        """The stored fix (lat, lon, h) at that time, if any."""
        rows = self._query("SELECT lat, lon, h FROM fixes WHERE t = ?", (_num(t_unix_s),))
        return tuple(rows[0]) if rows else None

    def range_at(self, t_unix_s: float, beacon: int) -> float | None:
        """The stored range at that time to that beacon, if any."""
        if _beacon_problem(beacon):
            return None
        rows = self._query(
            "SELECT range_m FROM ranges WHERE t = ? AND beacon = ?", (_num(t_unix_s), int(beacon))
        )
        return float(rows[0][0]) if rows else None

    def heading_at(self, t_unix_s: float, seq: int) -> float | None:
        """The stored heading (deg) after the fix at that time with that order, if any."""
        rows = self._query(
            "SELECT heading_deg FROM headings WHERE t = ? AND seq = ?", (_num(t_unix_s), int(seq))
        )
        return float(rows[0][0]) if rows else None

    def _valid(self, table: str, where: str = "") -> FloatArray:
        """The valid rows of a table (and ``where``), ordered, as floats: one query read straight into
        numpy (no per-row Python objects beyond the cursor's tuples)."""
        cond, order = f"IFNULL({_VALID_SQL[table]}, 0)" + (f" AND {where}" if where else ""), _ORDER[table]
        width = 3 + (table == "fixes")
        row = np.dtype([(f"c{k}", np.float64) for k in range(width)])
        try:
            cur = self._db.execute(f"SELECT {_COLUMNS[table]} FROM {table} WHERE {cond} ORDER BY {order}")
            out = np.fromiter(cur, dtype=row)
        except sqlite3.Error as exc:
            raise JournalError(self._explain(exc, "cannot read the journal")) from None
        return out.view(np.float64).reshape(-1, width)

    def count(self, table: str) -> int:
        """Rows stored in ``fixes``, ``headings`` or ``ranges`` (valid or not)."""
        if table not in _COLUMNS:
            raise ValueError(f"no journal table {table!r}")
        return int(self._query(f"SELECT count(*) FROM {table}")[0][0])

    def fixes(self) -> FloatArray:
        """All valid fixes ordered by time, ``(n, 4)``: t, lat, lon, h (see :meth:`invalid_records`)."""
        return self._valid("fixes")

    def ranges(self) -> FloatArray:
        """All valid ranges ordered by time and beacon, ``(m, 3)``: t, beacon, range."""
        return self._valid("ranges")

    def headings(self) -> FloatArray:
        """All valid headings ordered by time and order, ``(h, 3)``: t, seq, heading (deg from north)."""
        return self._valid("headings")

    def invalid_records(
        self, tables: tuple[str, ...] = ("fixes", "headings", "ranges")
    ) -> list[InvalidRecord]:
        """Every stored row that fails the checks on the way in (out of range, not a number), by table."""
        out = []
        for table in tables:
            rows = self._query(
                f"SELECT rowid, {_COLUMNS[table]} FROM {table} WHERE NOT IFNULL({_VALID_SQL[table]}, 0) "
                "ORDER BY rowid"
            )
            for rowid, *values in rows:
                problem = _PROBLEM[table](*values) or "not a number of the column's type"
                out.append(
                    InvalidRecord(table=table, rowid=int(rowid), values=tuple(values), problem=problem)
                )
        return out

    def remove_invalid(self) -> list[InvalidRecord]:
        """Delete every invalid stored row (:meth:`invalid_records`) in one transaction; returns them.

        Valid records are never touched; a second call removes nothing.
        """
        bad = self.invalid_records()
        for table in ("fixes", "headings", "ranges"):
            ids = [(r.rowid,) for r in bad if r.table == table]
            if ids:
                self._write(f"DELETE FROM {table} WHERE rowid = ?", ids)
        return bad

    def check(self) -> list[str]:
        """Problems of the journal file: SQLite's ``quick_check`` of every page, then the invalid records.

        An empty list means every page is readable and every record valid.
        """
        pages = [r[0] for r in self._query("PRAGMA quick_check")]
        problems = [] if pages == ["ok"] else [f"{self.path}: damaged: {p}" for p in pages]
        return problems + [f"{self.path}: {r}" for r in self.invalid_records()]

    def records(self, *, headings: bool = True, warn: bool = True) -> JournalRecords:
        """Every valid record, read in one read transaction (a consistent snapshot).

        Invalid stored rows (see :meth:`invalid_records`) are skipped, listed in
        :attr:`JournalRecords.invalid` and reported once as a logged warning, so every command reading the
        journal still works. The check is SQL's: one query per table reads the valid rows, and the
        invalid ones are listed only when a table holds more rows than that.

        With ``headings=False`` only the headings recorded since the second-to-last fix are read (all
        that :func:`~oceanloc.field.survey.estimates.vehicle_yaw` looks at);
        :attr:`JournalRecords.n_headings` is still the journal's count. ``warn=False``: no warning (the
        caller has reported the invalid rows, e.g. through :meth:`summary`).
        """
        try:
            with self._db:
                self._db.execute("BEGIN")
                fixes, ranges = self.fixes(), self.ranges()
                if headings or fixes.shape[0] < 2:
                    heads = self.headings()
                    n_head = heads.shape[0]
                else:
                    heads = self._valid("headings", f"t >= {float(fixes[-2, 0])!r}")
                    n_head = self.count_valid("headings")
                valid = {"fixes": fixes.shape[0], "headings": n_head, "ranges": ranges.shape[0]}
                bad = tuple(t for t in ("fixes", "headings", "ranges") if self.count(t) != valid[t])
                invalid = self.invalid_records(bad)
        except sqlite3.Error as exc:
            raise JournalError(self._explain(exc, "cannot read the journal")) from None
        if warn:
            self._warn_invalid(invalid)
        return JournalRecords(
            fix_t_unix_s=fixes[:, 0],
            lat_deg=fixes[:, 1],
            lon_deg=fixes[:, 2],
            h_m=fixes[:, 3],
            range_t_unix_s=ranges[:, 0],
            beacon=ranges[:, 1].astype(np.int64),
            range_m=ranges[:, 2],
            heading_t_unix_s=heads[:, 0],
            heading_deg=heads[:, 2],
            invalid=tuple(str(r) for r in invalid),
            heading_count=None if headings else n_head,
        )

    def _warn_invalid(self, invalid: list[InvalidRecord]) -> None:
        """Report skipped invalid records once, as a logged warning."""
        if invalid:
            _LOG.warning(
                "%s: %d invalid record(s) skipped (first: %s); `oceanloc survey check %s` lists "
                "them, with --remove-invalid it deletes them",
                self.path,
                len(invalid),
                invalid[0],
                self.path,
            )

    def summary(self) -> RecordSummary:
        """The valid records' counts, the fixes' time span and the :meth:`fingerprint`, in one read
        transaction (one scan of each table); invalid stored rows are reported as :meth:`records`
        reports them."""
        tables = ("fixes", "headings", "ranges")
        try:
            with self._db:
                self._db.execute("BEGIN")
                fixes, ranges = (self._fingerprint_row(t) for t in ("fixes", "ranges"))
                n = {
                    "fixes": int(fixes[0]),
                    "headings": self.count_valid("headings"),
                    "ranges": int(ranges[0]),
                }
                invalid = self.invalid_records(tuple(t for t in tables if self.count(t) != n[t]))
        except sqlite3.Error as exc:
            raise JournalError(self._explain(exc, "cannot read the journal")) from None
        self._warn_invalid(invalid)
        first, last = (math.nan if v is None else float(v) for v in fixes[-2:])
        return RecordSummary(
            n_fixes=n["fixes"], n_headings=n["headings"], n_ranges=n["ranges"], first_fix_t_unix_s=first,
            last_fix_t_unix_s=last, fingerprint=_fingerprint(fixes[:-2], ranges),
        )  # fmt: skip

    def _fingerprint_row(self, table: str) -> tuple:
        """:data:`_FINGERPRINT_SQL` of a table's valid rows (fixes: then the first and last time)."""
        extra = ", min(t), max(t)" if table == "fixes" else ""
        sql = f"SELECT {_FINGERPRINT_SQL[table]}{extra} FROM {table} WHERE IFNULL({_VALID_SQL[table]}, 0)"
        return self._query(sql)[0]

    def tail(self, fixes: int = 2) -> JournalRecords:
        """The last ``fixes`` valid fixes and the valid headings recorded since the first of them, no
        ranges: what the planner's start and heading need
        (:func:`~oceanloc.field.survey.estimates.vehicle_yaw`), read without reading the whole journal;
        ``heading_count`` is the journal's count."""
        cond = f"IFNULL({_VALID_SQL['fixes']}, 0)"
        try:
            with self._db:
                self._db.execute("BEGIN")
                rows = self._query(
                    f"SELECT t, lat, lon, h FROM fixes WHERE {cond} ORDER BY t DESC LIMIT ?", (fixes,)
                )
                last = np.array(rows[::-1], dtype=float).reshape(-1, 4)
                heads = (
                    self._valid("headings", f"t >= {float(last[0, 0])!r}")
                    if last.shape[0]
                    else np.zeros((0, 3))
                )
                n_head = self.count_valid("headings")
        except sqlite3.Error as exc:
            raise JournalError(self._explain(exc, "cannot read the journal")) from None
        empty = np.zeros(0)
        return JournalRecords(
            fix_t_unix_s=last[:, 0], lat_deg=last[:, 1], lon_deg=last[:, 2], h_m=last[:, 3],
            range_t_unix_s=empty, beacon=np.zeros(0, dtype=np.int64), range_m=empty,
            heading_t_unix_s=heads[:, 0], heading_deg=heads[:, 2], heading_count=n_head,
        )  # fmt: skip

    def fingerprint(self) -> str:
        """A fingerprint of the valid fixes and ranges (not the headings, events or derived results):
        it changes when a fix or range is added, removed or altered (SQL aggregates,
        :data:`_FINGERPRINT_SQL`; a scan of each table, no rows read into Python). Also in
        :meth:`summary`."""
        try:
            with self._db:
                self._db.execute("BEGIN")
                fixes, ranges = (self._fingerprint_row(t) for t in ("fixes", "ranges"))
        except sqlite3.Error as exc:
            raise JournalError(self._explain(exc, "cannot read the journal")) from None
        return _fingerprint(fixes[:-2], ranges)

    def derived(self, name: str, fingerprint: str) -> bytes | None:
        """The result stored under ``name`` if it was computed from records with this fingerprint, else
        None (also for a journal written before results were stored)."""
        try:
            rows = self._db.execute(
                "SELECT payload FROM derived WHERE name = ? AND fingerprint = ?", (name, fingerprint)
            ).fetchall()
        except sqlite3.OperationalError:  # no such table: an older journal opened read-only
            return None
        except sqlite3.Error as exc:
            raise JournalError(self._explain(exc, "cannot read the journal")) from None
        return bytes(rows[0][0]) if rows else None

    def store_derived(self, name: str, fingerprint: str, payload: bytes, *, timeout_s: float = 0.5) -> bool:
        """Keep a derived result (replacing the one of that name); False, and nothing written, if the
        journal is read-only or another writer holds it past ``timeout_s`` (a cache never waits long, so a
        reader never delays a live survey's writes)."""
        if self.read_only:
            return False
        try:
            self._db.execute(f"PRAGMA busy_timeout = {int(1e3 * timeout_s)}")
            with self._db:
                self._db.execute("BEGIN IMMEDIATE")
                self._db.execute(
                    "INSERT OR REPLACE INTO derived VALUES (?, ?, ?, ?)",
                    (name, fingerprint, time.time(), sqlite3.Binary(payload)),
                )
            return True
        except sqlite3.Error:
            return False
        finally:
            self._db.execute(f"PRAGMA busy_timeout = {int(1e3 * self._timeout_s)}")

    def count_valid(self, table: str) -> int:
        """Valid rows in ``fixes``, ``headings`` or ``ranges`` (counted by SQL, checks as on the way in)."""
        if table not in _COLUMNS:
            raise ValueError(f"no journal table {table!r}")
        return int(self._query(f"SELECT count(*) FROM {table} WHERE IFNULL({_VALID_SQL[table]}, 0)")[0][0])


@dataclass(frozen=True, slots=True, kw_only=True)
class JournalRecords:
    """What a journal holds, ordered as stored (fixes by time; ranges by time, beacon; headings by time).

    Attributes
    ----------
    fix_t_unix_s, lat_deg, lon_deg, h_m : (n,) float
        GPS fixes: UTC Unix seconds, WGS84 degrees and ellipsoidal metres.
    range_t_unix_s : (m,) float
    beacon : (m,) int
    range_m : (m,) float
    heading_t_unix_s, heading_deg : (h,) float
        HDT true headings (degrees clockwise from north) and the time of the fix each follows.
    invalid : tuple of str
        Stored rows skipped because they fail the checks on the way in (see
        :meth:`Journal.invalid_records`); empty for a journal written by this version.
    heading_count : int or None
        Valid headings in the journal when only the latest were read
        (``Journal.records(headings=False)``); None when ``heading_deg`` holds them all.
    """

    fix_t_unix_s: FloatArray
    lat_deg: FloatArray
    lon_deg: FloatArray
    h_m: FloatArray
    range_t_unix_s: FloatArray
    beacon: IntArray
    range_m: FloatArray
    heading_t_unix_s: FloatArray
    heading_deg: FloatArray
    invalid: tuple[str, ...] = ()
    heading_count: int | None = None

    @property
    def n_fixes(self) -> int:
        return int(self.fix_t_unix_s.size)

    @property
    def n_headings(self) -> int:
        """Valid headings in the journal (also when only the latest were read)."""
        return int(self.heading_deg.size) if self.heading_count is None else self.heading_count

    @property
    def n_ranges(self) -> int:
        return int(self.range_t_unix_s.size)

    def gps_log(self) -> GpsLog:
        """The fixes as a :class:`GpsLog` (``line``: the fix's index in the journal)."""
        return GpsLog(
            t_unix_s=self.fix_t_unix_s,
            lat_deg=self.lat_deg,
            lon_deg=self.lon_deg,
            h_m=self.h_m,
            heading_t_unix_s=self.heading_t_unix_s,
            heading_deg=self.heading_deg,
            line=np.arange(self.n_fixes, dtype=np.int64),
            qc=QcReport(),
        )

    def range_log(self) -> RangeLog:
        """The ranges as a :class:`RangeLog` (``line``: the range's index in the journal)."""
        return RangeLog(
            t_unix_s=self.range_t_unix_s,
            beacon=self.beacon.astype(np.int64),
            range_m=self.range_m,
            line=np.arange(self.n_ranges, dtype=np.int64),
            qc=QcReport(),
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class AppendCounts:
    """How many records of one kind an append offered, and how many were new.

    Attributes
    ----------
    kind : str
        ``fixes``, ``headings`` or ``ranges``.
    new : int
        Records written (in transactions of :data:`APPEND_CHUNK` records for a file).
    already_stored : int
        Records identical to one already in the journal (idempotent re-add; nothing written).
    conflicting : int
        Records whose key (fix: time; heading: time and order; range: time and beacon) is stored with
        another value: kept as stored, listed in the QC report as ``duplicate record`` with both values.
    rejected : int
        Records failing the checks on the way in (out of range): not written, listed in the QC report as
        ``out of range``.
    """

    kind: str
    new: int
    already_stored: int
    conflicting: int = 0
    rejected: int = 0

    @property
    def offered(self) -> int:
        return self.new + self.already_stored + self.conflicting + self.rejected

    def __str__(self) -> str:
        text = f"{self.offered} {self.kind} ({self.new} new, {self.already_stored} already stored"
        text += f", {self.conflicting} conflicting" if self.conflicting else ""
        return text + (f", {self.rejected} rejected)" if self.rejected else ")")


def _inside(a: FloatArray, bounds: tuple[float, float]) -> BoolArray:
    return np.isfinite(a) & (a >= bounds[0]) & (a <= bounds[1])


def _reject(
    qc: QcReport,
    source: str | Path,
    lines: IntArray,
    ok: BoolArray,
    problem: Callable[..., str | None],
    columns: tuple[np.ndarray, ...],
) -> None:
    """Record each rejected record (``~ok``) in ``qc`` with its line and what is wrong with it."""
    for k in np.flatnonzero(~ok):
        values = [c[k].item() for c in columns]
        qc.add(source, int(lines[k]), "out of range", problem(*values) or "not a number")


APPEND_CHUNK = 2_000
"""Records per transaction of :func:`append_gps_log` and :func:`append_range_log` (a transaction costs
about a millisecond, a record a few microseconds)."""

_KEY_WIDTH = {"fixes": 1, "headings": 2, "ranges": 2}


@dataclass(slots=True)
class _Chunk:
    """One table's rows of a chunk in record order: their values and where each stands in the log."""

    table: str
    rows: FloatArray
    pos: IntArray
    lines: IntArray


def _classify(db: sqlite3.Connection, chunk: _Chunk) -> tuple[BoolArray, BoolArray, FloatArray, list]:
    """Which rows of the chunk are new (the first of their key, not stored) and which repeat the record of
    their key exactly; per row the values it is compared with (stored, or an earlier row's) and the stored
    row as read (None for an earlier row of the chunk)."""
    rows, kw = chunk.rows, _KEY_WIDTH[chunk.table]
    if rows.shape[0] == 0:
        return np.zeros(0, dtype=bool), np.zeros(0, dtype=bool), rows, []
    stored_raw = db.execute(
        f"SELECT {_COLUMNS[chunk.table]} FROM {chunk.table} WHERE t BETWEEN ? AND ?",
        (float(rows[:, 0].min()), float(rows[:, 0].max())),
    ).fetchall()
    width = rows.shape[1]
    try:
        stored = np.array(stored_raw, dtype=float).reshape(-1, width)
    except (TypeError, ValueError):  # an invalid stored row (text, NULL): its values compare as NaN
        stored = np.array([[_num(v) for v in r] for r in stored_raw], dtype=float).reshape(-1, width)
    both = np.concatenate([stored, rows])
    _, first, inverse = np.unique(both[:, :kw], axis=0, return_index=True, return_inverse=True)
    ref = first[inverse.reshape(-1)[stored.shape[0] :]]  # first row (stored, then chunk) of each key
    new = ref == np.arange(rows.shape[0]) + stored.shape[0]
    ref_values = both[ref]
    same = ~new & np.all(ref_values[:, kw:] == rows[:, kw:], axis=1)
    raw = [stored_raw[i] if i < len(stored_raw) else None for i in ref]
    return new, same, ref_values, raw


def _write_chunk(journal: Journal, parts: list[_Chunk]) -> tuple[dict[str, list[int]], list[tuple]]:
    """Insert the new rows of one chunk (several tables) in one transaction; per table the counts
    ``[new, already stored, conflicting]``, and the conflicts as ``(pos, line, message)``."""
    counts: dict[str, list[int]] = {}
    conflicts: list[tuple] = []
    try:
        with journal._db:
            journal._db.execute("BEGIN IMMEDIATE")
            for part in parts:
                new, same, ref_values, raw = _classify(journal._db, part)
                values = part.rows[new].tolist()
                if part.table != "fixes":  # beacon id, heading order: integers
                    values = [(r[0], int(r[1]), r[2]) for r in values]
                marks = ", ".join("?" * part.rows.shape[1])
                journal._db.executemany(f"INSERT INTO {part.table} VALUES ({marks})", values)
                bad = ~new & ~same
                counts[part.table] = [int(new.sum()), int(same.sum()), int(bad.sum())]
                for i in np.flatnonzero(bad):
                    stored = raw[i] if raw[i] is not None else tuple(ref_values[i].tolist())
                    message = _conflict_message(part.table, part.rows[i], stored)
                    conflicts.append((int(part.pos[i]), int(part.lines[i]), message))
    except sqlite3.Error as exc:
        if journal.read_only:
            raise JournalError(
                f"{journal.path}: the journal is read-only here: {journal._read_only_reason()}"
            ) from None
        raise JournalError(journal._explain(exc, "cannot write to the journal")) from None
    return counts, conflicts


def _conflict_message(table: str, row: FloatArray, stored: tuple) -> str:
    """What ``duplicate record`` says: the stored values and this line's."""
    if table == "fixes":
        values = tuple(row[1:].tolist())
        return f"a fix at this time is stored with other values: {tuple(stored[1:])}, this line {values}"
    if table == "headings":
        return (
            f"heading {int(row[1]) + 1} after the fix at {row[0]:.3f} s is stored with {stored[2]} deg, "
            f"this line {float(row[2])} deg"
        )
    return f"beacon {int(row[1])} at this time is stored with {stored[2]} m, this line {float(row[2])} m"


def _append_chunked(
    journal: Journal, parts: list[_Chunk], qc: QcReport, source: str | Path, chunk_size: int
) -> dict[str, list[int]]:
    """Write the records of ``parts`` (each table's rows in log order, ``pos`` their place in the log)
    in chunks of ``chunk_size`` consecutive records, one transaction each, so what is committed is
    always a prefix of the log; conflicts go to ``qc`` in log order. Per table ``[new, old, conflicting]``.
    """
    total = {p.table: [0, 0, 0] for p in parts}
    all_pos = np.sort(np.concatenate([p.pos for p in parts]))
    if all_pos.size == 0:
        return total
    bounds = [*all_pos[::chunk_size].tolist(), int(all_pos[-1]) + 1]
    for lo, hi in itertools.pairwise(bounds):
        chunk = []
        for p in parts:
            a, b = np.searchsorted(p.pos, [lo, hi], side="left")
            chunk.append(_Chunk(p.table, p.rows[a:b], p.pos[a:b], p.lines[a:b]))
        counts, conflicts = _write_chunk(journal, chunk)
        for table, c in counts.items():
            total[table] = [u + v for u, v in zip(total[table], c, strict=True)]
        for _, line, message in sorted(conflicts, key=lambda c: c[0]):
            qc.add(source, line, "duplicate record", message)
    return total


def append_gps_log(
    journal: Journal,
    log: GpsLog,
    source: str | Path,
    qc: QcReport | None = None,
    *,
    chunk_size: int = APPEND_CHUNK,
) -> tuple[AppendCounts, AppendCounts]:
    """Append a GPS log in log order: each fix, then the headings that follow it.

    The whole log is checked before the first write: a fix or heading out of range (see
    :func:`fix_problem`) is not written and is recorded in ``qc`` (``out of range``, naming ``source``
    and the line). A heading read before any fix has no time (``-inf``) and is not stored. A fix or
    heading whose key is stored with another value is kept as stored and recorded in ``qc``
    (``duplicate record``, with both values).

    The records are written in transactions of ``chunk_size`` records in log order (``executemany``
    inside one ``BEGIN IMMEDIATE``): a process killed mid-append leaves a prefix of the log committed,
    and appending the log again adds the rest (records already stored change nothing).

    Returns
    -------
    (fix counts, heading counts)
    """
    qc = log.qc if qc is None else qc
    fix_ok = (
        _inside(log.t_unix_s, TIME_RANGE_UNIX_S)
        & _inside(log.lat_deg, LAT_RANGE_DEG)
        & _inside(log.lon_deg, JOURNAL_LON_RANGE_DEG)
        & _inside(log.h_m, HEIGHT_RANGE_M)
    )
    order = np.argsort(log.heading_t_unix_s, kind="stable")
    head_t, head_deg = log.heading_t_unix_s[order], log.heading_deg[order]
    head_line = np.zeros(order.size, dtype=np.int64) if log.heading_line is None else log.heading_line[order]
    timed = np.isfinite(head_t)
    head_t, head_deg, head_line = head_t[timed], head_deg[timed], head_line[timed]
    # seq: a heading's order among those at the same time.
    first = np.searchsorted(head_t, head_t, side="left")
    seq = np.arange(head_t.size) - first
    head_ok = _inside(head_t, TIME_RANGE_UNIX_S) & _inside(head_deg, HEADING_RANGE_DEG)
    if not (fix_ok.all() and head_ok.all()):
        _reject(qc, source, log.line, fix_ok, fix_problem, (log.t_unix_s, log.lat_deg, log.lon_deg, log.h_m))
        _reject(qc, source, head_line, head_ok, heading_problem, (head_t, seq, head_deg))
    # Log order: fix k, then the headings up to its time not yet written (their index below next_j[k]).
    n = log.n_fixes
    end = np.searchsorted(head_t, log.t_unix_s, side="right")
    next_j = np.maximum.accumulate(end) if n else np.zeros(0, dtype=np.int64)
    before = np.concatenate([[0], next_j[:-1]]) if n else np.zeros(0, dtype=np.int64)
    fix_pos = np.arange(n) + before
    after_fix = np.searchsorted(next_j, np.arange(head_t.size), side="right")  # fix k the heading follows
    head_pos = np.minimum(after_fix + 1, n) + np.arange(head_t.size)
    fixes = np.column_stack([log.t_unix_s, log.lat_deg, log.lon_deg, log.h_m])
    heads = np.column_stack([head_t, seq.astype(float), head_deg])
    counts = _append_chunked(
        journal,
        [
            _Chunk("fixes", fixes[fix_ok], fix_pos[fix_ok], np.asarray(log.line)[fix_ok]),
            _Chunk("headings", heads[head_ok], head_pos[head_ok], head_line[head_ok]),
        ],
        qc,
        source,
        chunk_size,
    )
    fix_c, head_c = counts["fixes"], counts["headings"]
    return (
        AppendCounts(
            kind="fixes",
            new=fix_c[0],
            already_stored=fix_c[1],
            conflicting=fix_c[2],
            rejected=int((~fix_ok).sum()),
        ),
        AppendCounts(
            kind="headings",
            new=head_c[0],
            already_stored=head_c[1],
            conflicting=head_c[2],
            rejected=int((~head_ok).sum()),
        ),
    )


def append_range_log(
    journal: Journal,
    log: RangeLog,
    source: str | Path,
    qc: QcReport | None = None,
    *,
    chunk_size: int = APPEND_CHUNK,
) -> AppendCounts:
    """Append a range log in log order, in transactions of ``chunk_size`` records; the whole log is
    checked before the first write (see :func:`append_gps_log` on rejected and conflicting records and on
    the prefix committed by a killed process)."""
    qc = log.qc if qc is None else qc
    beacon = np.asarray(log.beacon)
    ok = (
        _inside(log.t_unix_s, TIME_RANGE_UNIX_S)
        & (beacon >= BEACON_ID_RANGE[0])
        & (beacon <= BEACON_ID_RANGE[1])
        & np.isfinite(log.range_m)
        & (log.range_m > 0.0)
        & (log.range_m <= MAX_RANGE_M)
    )
    if not ok.all():
        _reject(qc, source, log.line, ok, range_problem, (log.t_unix_s, beacon, log.range_m))
    rows = np.column_stack([log.t_unix_s, beacon.astype(float), log.range_m])
    pos = np.arange(log.t_unix_s.size)
    part = _Chunk("ranges", rows[ok], pos[ok], np.asarray(log.line)[ok])
    c = _append_chunked(journal, [part], qc, source, chunk_size)
    new, old, bad = c["ranges"]
    return AppendCounts(
        kind="ranges", new=new, already_stored=old, conflicting=bad, rejected=int((~ok).sum())
    )
