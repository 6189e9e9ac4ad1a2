"""A survey journal that loses nothing: every GPS fix and range appended to SQLite as it arrives.

Write-ahead logging (``journal_mode=WAL``) with ``synchronous=FULL`` and one transaction per record: a
process killed mid-write loses at most the record being written, never one already committed, and the
journal re-opens in the state of its last commit. Records are keyed by their content's identity
(fix: time; range: time and beacon), so re-adding a record already stored changes nothing
(idempotent ``INSERT OR IGNORE``); the state read back is ordered by time, hence identical however
often a stream is replayed.
"""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import DataError

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS fixes (t REAL PRIMARY KEY, lat REAL NOT NULL, lon REAL NOT NULL, h REAL NOT NULL);
CREATE TABLE IF NOT EXISTS ranges (t REAL NOT NULL, beacon INTEGER NOT NULL, range_m REAL NOT NULL,
                                   PRIMARY KEY (t, beacon));
"""


class Journal:
    """An open survey journal (a context manager; close it or use ``with``)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        try:
            self._db = sqlite3.connect(self.path, isolation_level=None, timeout=30.0)
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute("PRAGMA synchronous=FULL")
            self._db.executescript(_SCHEMA)
        except sqlite3.DatabaseError as exc:
            raise DataError(f"{self.path}: not a survey journal ({exc})") from None

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._db.close()

    def set_meta(self, key: str, value: str) -> None:
        with self._db:
            self._db.execute("BEGIN")
            self._db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, value))

    def meta(self) -> dict[str, str]:
        return dict(self._db.execute("SELECT key, value FROM meta").fetchall())

    def add_fix(self, t_unix_s: float, lat_deg: float, lon_deg: float, h_m: float) -> bool:
        """Append one GPS fix in its own transaction; False if that fix was already stored."""
        values = (float(t_unix_s), float(lat_deg), float(lon_deg), float(h_m))
        if not all(np.isfinite(values)):
            raise DataError(f"fix at {t_unix_s}: NaN or infinite value")
        with self._db:
            self._db.execute("BEGIN IMMEDIATE")
            cur = self._db.execute("INSERT OR IGNORE INTO fixes VALUES (?, ?, ?, ?)", values)
        return cur.rowcount == 1

    def add_range(self, t_unix_s: float, beacon: int, range_m: float) -> bool:
        """Append one range in its own transaction; False if already stored."""
        if not (np.isfinite(range_m) and range_m > 0.0 and np.isfinite(t_unix_s)):
            raise DataError(f"range at {t_unix_s}: negative, NaN or infinite value {range_m}")
        with self._db:
            self._db.execute("BEGIN IMMEDIATE")
            cur = self._db.execute(
                "INSERT OR IGNORE INTO ranges VALUES (?, ?, ?)",
                (float(t_unix_s), int(beacon), float(range_m)),
            )
        return cur.rowcount == 1

    def fixes(self) -> FloatArray:
        """All fixes ordered by time, ``(n, 4)``: t, lat, lon, h."""
        rows = self._db.execute("SELECT t, lat, lon, h FROM fixes ORDER BY t").fetchall()
        return np.asarray(rows, dtype=float).reshape(-1, 4)

    def ranges(self) -> FloatArray:
        """All ranges ordered by time and beacon, ``(m, 3)``: t, beacon, range."""
        rows = self._db.execute("SELECT t, beacon, range_m FROM ranges ORDER BY t, beacon").fetchall()
        return np.asarray(rows, dtype=float).reshape(-1, 3)
