"""A survey journal that loses nothing: every GPS fix, heading and range appended to SQLite as it arrives.

Write-ahead logging (``journal_mode=WAL``) with ``synchronous=FULL`` and one transaction per record: a
process killed mid-write loses at most the record being written, never one already committed, and the
journal re-opens in the state of its last commit. Records are keyed by their content's identity
(fix: time; heading: the time of the fix it follows and its order after that fix; range: time and
beacon), so re-adding a record already stored changes nothing (idempotent ``INSERT OR IGNORE``); the
state read back is ordered by time, hence identical however often a stream is replayed.

A journal in use by ``oceanloc survey`` is *started* (:meth:`Journal.start`): its ``meta`` table holds
the format marker and the survey settings (strings, written in one transaction). :meth:`Journal.open`
opens only a started journal and never creates or modifies a file that is not one.
"""

from __future__ import annotations

import math
import sqlite3
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray, IntArray
from oceanloc.errors import DataError
from oceanloc.io.nmea import GpsLog
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import RangeLog

FORMAT_KEY = "format"
JOURNAL_FORMAT = "oceanloc-survey-journal 1"
"""Value of the ``format`` meta key of a started journal."""

_TABLES = {"meta", "fixes", "ranges", "headings"}
_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS fixes (t REAL PRIMARY KEY, lat REAL NOT NULL, lon REAL NOT NULL, h REAL NOT NULL);
CREATE TABLE IF NOT EXISTS ranges (t REAL NOT NULL, beacon INTEGER NOT NULL, range_m REAL NOT NULL,
                                   PRIMARY KEY (t, beacon));
CREATE TABLE IF NOT EXISTS headings (t REAL NOT NULL, seq INTEGER NOT NULL, heading_deg REAL NOT NULL,
                                     PRIMARY KEY (t, seq));
"""


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
        if not create and not self.path.is_file():
            raise DataError(f"{self.path}: no survey journal here (start one with `oceanloc survey start`)")
        if create and not self.path.parent.is_dir():
            raise DataError(f"{self.path}: folder {self.path.parent} does not exist")
        try:
            if create:
                self._db = sqlite3.connect(self.path, isolation_level=None, timeout=timeout_s)
            else:  # mode=rw: never creates a file
                uri = f"{self.path.resolve().as_uri()}?mode=rw"
                self._db = sqlite3.connect(uri, uri=True, isolation_level=None, timeout=timeout_s)
        except sqlite3.Error as exc:
            raise DataError(f"{self.path}: cannot open as a survey journal ({exc})") from None
        try:
            # Look before writing anything: WAL mode and our tables must not be forced on a foreign file.
            names = {r[0] for r in self._db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            foreign = names - _TABLES
            if foreign:
                raise DataError(
                    f"{self.path}: not a survey journal (an SQLite database with tables "
                    f"{', '.join(sorted(foreign))})"
                )
            if not create and not {"meta", "fixes", "ranges"} <= names:
                raise DataError(f"{self.path}: not a survey journal (no journal tables)")
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute("PRAGMA synchronous=FULL")
            self._db.executescript(_SCHEMA)
        except sqlite3.DatabaseError as exc:
            self._db.close()
            raise DataError(f"{self.path}: not a survey journal ({exc})") from None
        except DataError:
            self._db.close()
            raise

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
            raise DataError(f"{journal.path}: survey already started; start a new survey in a new file")
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
        return dict(self._db.execute("SELECT key, value FROM meta").fetchall())

    def add_fix(self, t_unix_s: float, lat_deg: float, lon_deg: float, h_m: float) -> bool:
        """Append one GPS fix in its own transaction; False if a fix at that time was already stored.

        Raises
        ------
        DataError
            On a NaN or infinite value, or a latitude or longitude out of range (naming the field).
        """
        values = (float(t_unix_s), float(lat_deg), float(lon_deg), float(h_m))
        if not all(np.isfinite(values)):
            raise DataError(f"fix at {t_unix_s}: NaN or infinite value")
        if not -90.0 <= values[1] <= 90.0:
            raise DataError(f"fix at {t_unix_s}: latitude {lat_deg} deg is outside [-90, 90]")
        if not -180.0 <= values[2] <= 360.0:
            raise DataError(f"fix at {t_unix_s}: longitude {lon_deg} deg is outside [-180, 360]")
        return self._write("INSERT OR IGNORE INTO fixes VALUES (?, ?, ?, ?)", [values]) == 1

    def add_range(self, t_unix_s: float, beacon: int, range_m: float) -> bool:
        """Append one range in its own transaction; False if a range at that time and beacon was stored."""
        if not (np.isfinite(range_m) and range_m > 0.0 and np.isfinite(t_unix_s)):
            raise DataError(f"range at {t_unix_s}: negative, NaN or infinite value {range_m}")
        row = (float(t_unix_s), int(beacon), float(range_m))
        return self._write("INSERT OR IGNORE INTO ranges VALUES (?, ?, ?)", [row]) == 1

    def add_heading(self, t_unix_s: float, seq: int, heading_deg: float) -> bool:
        """Append one true heading (degrees clockwise from north) in its own transaction.

        ``t_unix_s`` is the time of the fix the HDT sentence follows, ``seq`` its order after that fix
        (0 for the first); False if already stored.
        """
        if not (math.isfinite(t_unix_s) and math.isfinite(heading_deg)):
            raise DataError(f"heading at {t_unix_s}: NaN or infinite value {heading_deg}")
        row = (float(t_unix_s), int(seq), float(heading_deg))
        return self._write("INSERT OR IGNORE INTO headings VALUES (?, ?, ?)", [row]) == 1

    def _write(self, sql: str, rows: list[tuple]) -> int:
        """Run one statement over ``rows`` in one transaction; returns the rows changed.

        SQLite failures (journal locked by another writer past the timeout, disk full, read-only file)
        are :class:`DataError` naming the journal; the transaction is rolled back, nothing committed is
        touched.
        """
        try:
            with self._db:
                self._db.execute("BEGIN IMMEDIATE")
                cur = self._db.executemany(sql, rows)
        except sqlite3.Error as exc:
            raise DataError(f"{self.path}: cannot write to the journal ({exc})") from None
        return cur.rowcount

    def fix_at(self, t_unix_s: float) -> tuple[float, float, float] | None:
        """The stored fix (lat, lon, h) at that time, if any."""
        row = self._db.execute("SELECT lat, lon, h FROM fixes WHERE t = ?", (float(t_unix_s),)).fetchone()
        return None if row is None else tuple(row)

    def range_at(self, t_unix_s: float, beacon: int) -> float | None:
        """The stored range at that time to that beacon, if any."""
        row = self._db.execute(
            "SELECT range_m FROM ranges WHERE t = ? AND beacon = ?", (float(t_unix_s), int(beacon))
        ).fetchone()
        return None if row is None else float(row[0])

    def fixes(self) -> FloatArray:
        """All fixes ordered by time, ``(n, 4)``: t, lat, lon, h."""
        rows = self._db.execute("SELECT t, lat, lon, h FROM fixes ORDER BY t").fetchall()
        return np.asarray(rows, dtype=float).reshape(-1, 4)

    def ranges(self) -> FloatArray:
        """All ranges ordered by time and beacon, ``(m, 3)``: t, beacon, range."""
        rows = self._db.execute("SELECT t, beacon, range_m FROM ranges ORDER BY t, beacon").fetchall()
        return np.asarray(rows, dtype=float).reshape(-1, 3)

    def headings(self) -> FloatArray:
        """All headings ordered by time and order, ``(h, 3)``: t, seq, heading (deg from north)."""
        rows = self._db.execute("SELECT t, seq, heading_deg FROM headings ORDER BY t, seq").fetchall()
        return np.asarray(rows, dtype=float).reshape(-1, 3)

    def records(self) -> JournalRecords:
        """Everything recorded, read in one read transaction (a consistent snapshot)."""
        with self._db:
            self._db.execute("BEGIN")
            fixes, ranges, headings = self.fixes(), self.ranges(), self.headings()
        return JournalRecords(
            fix_t_unix_s=fixes[:, 0],
            lat_deg=fixes[:, 1],
            lon_deg=fixes[:, 2],
            h_m=fixes[:, 3],
            range_t_unix_s=ranges[:, 0],
            beacon=ranges[:, 1].astype(np.int64),
            range_m=ranges[:, 2],
            heading_t_unix_s=headings[:, 0],
            heading_deg=headings[:, 2],
        )


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

    @property
    def n_fixes(self) -> int:
        return int(self.fix_t_unix_s.size)

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
        Records written (one transaction each).
    already_stored : int
        Records identical to one already in the journal (idempotent re-add; nothing written).
    conflicting : int
        Records whose key (time, beacon) is stored with another value: kept as stored, listed in the QC
        report as ``duplicate record``.
    """

    kind: str
    new: int
    already_stored: int
    conflicting: int = 0

    @property
    def offered(self) -> int:
        return self.new + self.already_stored + self.conflicting

    def __str__(self) -> str:
        text = f"{self.offered} {self.kind} ({self.new} new, {self.already_stored} already stored"
        return text + (f", {self.conflicting} conflicting)" if self.conflicting else ")")


def append_gps_log(
    journal: Journal, log: GpsLog, source: str | Path, qc: QcReport | None = None
) -> tuple[AppendCounts, AppendCounts]:
    """Append a GPS log record by record, in log order: each fix, then the headings that follow it.

    A heading read before any fix has no time (``-inf``) and is not stored. A fix whose time is stored with
    another position is kept as stored and recorded in ``qc`` (``duplicate record``, naming
    ``source`` and the line).

    Returns
    -------
    (fix counts, heading counts)
    """
    qc = log.qc if qc is None else qc
    fix_new = fix_old = fix_bad = 0
    head_new = head_old = 0
    order = np.argsort(log.heading_t_unix_s, kind="stable")
    head_t, head_deg = log.heading_t_unix_s[order], log.heading_deg[order]
    timed = np.isfinite(head_t)
    head_t, head_deg = head_t[timed], head_deg[timed]
    # seq: a heading's order among those at the same time.
    first = np.searchsorted(head_t, head_t, side="left")
    seq = np.arange(head_t.size) - first
    j = 0
    for k in range(log.n_fixes + 1):
        if k < log.n_fixes:
            t = float(log.t_unix_s[k])
            values = (float(log.lat_deg[k]), float(log.lon_deg[k]), float(log.h_m[k]))
            if journal.add_fix(t, *values):
                fix_new += 1
            elif (stored := journal.fix_at(t)) == values:
                fix_old += 1
            else:
                fix_bad += 1
                qc.add(
                    source, int(log.line[k]), "duplicate record", f"a fix at this time is stored: {stored}"
                )
        end = head_t.size if k == log.n_fixes else int(np.searchsorted(head_t, t, side="right"))
        for i in range(j, end):
            if journal.add_heading(float(head_t[i]), int(seq[i]), float(head_deg[i])):
                head_new += 1
            else:
                head_old += 1
        j = max(j, end)
    return (
        AppendCounts(kind="fixes", new=fix_new, already_stored=fix_old, conflicting=fix_bad),
        AppendCounts(kind="headings", new=head_new, already_stored=head_old),
    )


def append_range_log(
    journal: Journal, log: RangeLog, source: str | Path, qc: QcReport | None = None
) -> AppendCounts:
    """Append a range log record by record, in log order (see :func:`append_gps_log` on conflicts)."""
    qc = log.qc if qc is None else qc
    new = old = bad = 0
    for k in range(log.t_unix_s.size):
        t, beacon, rng = float(log.t_unix_s[k]), int(log.beacon[k]), float(log.range_m[k])
        if journal.add_range(t, beacon, rng):
            new += 1
        elif journal.range_at(t, beacon) == rng:
            old += 1
        else:
            bad += 1
            qc.add(
                source,
                int(log.line[k]),
                "duplicate record",
                f"beacon {beacon} at this time is stored with {journal.range_at(t, beacon)} m",
            )
    return AppendCounts(kind="ranges", new=new, already_stored=old, conflicting=bad)
