"""USBL range logs (CSV) and their alignment with a GPS log.

Format: a header line naming the columns, then one range per line::

    utc,beacon,range_m
    2018-01-04T18:43:55.120Z,1,9.184
    2018-01-04T18:43:56.610Z,2,2.731

``utc`` is ISO 8601 (a trailing ``Z``, ``UTC`` or an offset such as ``+02:00``, ``+0200`` or ``-08``; no
offset means UTC); ``beacon`` an integer id in :data:`~oceanloc.io.qc.BEACON_ID_RANGE`; the third
column is one of ``range_m`` (metres), ``owtt_s`` (one-way travel time) or ``twtt_s`` (two-way,
turn-around removed), converted with the sound speed given to :func:`read_usbl`. Lines with a
non-numeric field, a NaN, a time outside :data:`~oceanloc.io.qc.TIME_RANGE_UNIX_S`, a beacon id out of
range, a range not in ``(0, max_range_m]``, an unknown beacon id (when the known ids are given), a time
earlier than the previous line, or the same time and beacon as an earlier line (``duplicate record``:
the first is used) are skipped and recorded in the QC report. A header line later in the file (two
logs joined) switches the column from there on.

:class:`UsblLineParser` holds these rules, one line at a time: :func:`read_usbl` feeds it a file's lines
and a live stream (:mod:`oceanloc.io.streams`) the lines it receives, so both keep the same ranges with
the same QC issues; :func:`range_log_from_records` turns the records into a :class:`RangeLog`. A plain
``YYYY-MM-DDTHH:MM:SS.fffZ,beacon,value`` line that is kept is read by string operations (the bulk
speed of ``survey add``); every other line by the general rules, which alone name QC issues.
"""

from __future__ import annotations

import datetime as dt
import math
import re
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.geo.enu import EnuOrigin, geodetic_to_enu
from oceanloc.io.nmea import GpsLog
from oceanloc.io.qc import (
    BEACON_ID_RANGE,
    MAX_RANGE_M,
    TIME_RANGE_UNIX_S,
    QcReport,
    read_lines,
    time_problem,
)

RANGE_COLUMNS: dict[str, float] = {"range_m": 0.0, "owtt_s": 1.0, "twtt_s": 0.5}
"""Accepted measurement columns and the factor applied to ``c * value`` (0: already metres)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class RangeLog:
    """Time-ordered ranges to beacons.

    Attributes
    ----------
    t_unix_s : (n,) float
        UTC, Unix seconds.
    beacon : (n,) int
    range_m : (n,) float
    line : (n,) int
    qc : QcReport
    """

    t_unix_s: FloatArray
    beacon: IntArray
    range_m: FloatArray
    line: IntArray
    qc: QcReport


def read_usbl(
    path: str | Path,
    *,
    sound_speed_mps: float = 1500.0,
    beacons: Collection[int] | None = None,
    max_range_m: float = MAX_RANGE_M,
    qc: QcReport | None = None,
) -> RangeLog:
    """Read a USBL range CSV (see the module docstring) through :class:`UsblLineParser`.

    Raises
    ------
    ConfigError
        If the sound speed is outside [1300, 1700] m/s or ``max_range_m`` is not positive and finite.
    DataError
        If the file cannot be read, its first line is not a header, or it holds no valid range.
    """
    p = Path(path)
    qc = QcReport() if qc is None else qc
    parser = UsblLineParser(sound_speed_mps=sound_speed_mps, beacons=beacons, max_range_m=max_range_m)
    fast = parser._fast_values
    rows: list[tuple[float, int, float, int]] = []
    for number, text in read_lines(p, qc):
        # Bulk path: the common well-formed lines as plain tuples, every other line through feed.
        values = fast(number, text, qc)
        if values is _SLOW:
            rec = parser.feed(number, text, qc, p, fast=False)
            if rec is not None and rec.ok and rec.range_m is not None:
                rows.append((rec.t_unix_s, rec.beacon, rec.range_m, number))
        else:
            rows.append(values)
    if not rows:
        raise DataError(f"{p}: no valid range ({qc.summary(max_lines=3)})")
    return RangeLog(
        t_unix_s=np.asarray([r[0] for r in rows], dtype=float),
        beacon=np.asarray([r[1] for r in rows], dtype=np.int64),
        range_m=np.asarray([r[2] for r in rows], dtype=float),
        line=np.asarray([r[3] for r in rows], dtype=np.int64),
        qc=qc,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class RangeRecord:
    """One range to a beacon, or one failed attempt (``status`` other than ``ok``, ``range_m`` None).

    Attributes
    ----------
    t_unix_s : float
        UTC Unix seconds of the range epoch.
    beacon : int
    range_m : float or None
        Slant range, metres (None when the attempt failed).
    status : str
        ``ok``, or why there is no range (``timeout``, ``no response``, ...).
    message : str
        One line for the operator when the status is not ``ok``.
    travel_time_s : float or None
        One-way travel time the range came from, seconds, when the source gives one.
    azimuth_deg, elevation_deg : float or None
        USBL signal angles, degrees, when the source gives valid ones (kept for the journal).
    source : str
        The stream (spec, port or file) and ``line`` the number of the line read from it.
    """

    t_unix_s: float
    beacon: int
    range_m: float | None
    status: str = "ok"
    message: str = ""
    travel_time_s: float | None = None
    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    source: str = ""
    line: int = 0

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def to_record(self) -> dict:
        return {
            "t_unix_s": self.t_unix_s,
            "beacon": self.beacon,
            "range_m": self.range_m,
            "status": self.status,
            "message": self.message,
            "travel_time_s": self.travel_time_s,
            "azimuth_deg": self.azimuth_deg,
            "elevation_deg": self.elevation_deg,
            "source": self.source,
            "line": self.line,
        }


class UsblLineParser:
    """USBL range lines one at a time, with every rule of the module docstring: :func:`read_usbl`'s
    loop, and a live stream's (UDP, TCP, serial).

    ``column`` presets the measurement column (``range_m``, ``owtt_s`` or ``twtt_s``) for a stream that
    sends no header; a header line (``utc,beacon,range_m``) sets or changes it whenever it arrives.
    Without a column (a file), a first line that is not a header is a :class:`DataError`. State: the
    column, the time of the latest range kept and the beacons ranged at that time (a later line with the
    same time and beacon is a ``duplicate record``; times never go back, so no older one can match).
    """

    __slots__ = ("_at_last_t", "_days", "column", "known", "last_t", "max_range_m", "sound_speed_mps")

    def __init__(
        self,
        *,
        sound_speed_mps: float = 1500.0,
        beacons: Collection[int] | None = None,
        max_range_m: float = MAX_RANGE_M,
        column: str | None = None,
    ) -> None:
        if not 1300.0 <= sound_speed_mps <= 1700.0:
            raise ConfigError(f"sound speed {sound_speed_mps} m/s is outside [1300, 1700]")
        if not (math.isfinite(max_range_m) and max_range_m > 0.0):
            raise ConfigError(f"max_range_m {max_range_m} m must be positive and finite")
        if column is not None and column not in RANGE_COLUMNS:
            raise ConfigError(f"range column {column!r} is not one of {', '.join(RANGE_COLUMNS)}")
        self.sound_speed_mps = float(sound_speed_mps)
        self.known = None if beacons is None else {int(b) for b in beacons}
        self.max_range_m = float(max_range_m)
        self.column = column
        self.last_t = -math.inf
        self._at_last_t: dict[int, tuple[float, int]] = {}  # beacon -> (range_m, line) at last_t
        self._days: dict[str, int] = {}  # YYYY-MM-DD -> days since 1970-01-01, for the fast path

    def feed(
        self, number: int, text: str, qc: QcReport, source: str | Path, *, fast: bool = True
    ) -> RangeRecord | None:
        """The range of one line of text (already decoded, see :func:`~oceanloc.io.qc.decode_line`), or
        None (a header, a comment, or a line skipped and recorded as ``source:number: reason``).

        A plain ``YYYY-MM-DDTHH:MM:SS.fffZ,beacon,value`` line kept goes through a string fast path
        (:meth:`_fast_values`, ``fast=False``: never); every other line through the general rules."""
        p = source
        if fast:
            values = self._fast_values(number, text, qc)
            if values is not _SLOW:
                t, beacon, rng, _ = values
                factor = RANGE_COLUMNS[self.column]
                owtt = None if factor == 0.0 else rng / self.sound_speed_mps
                return RangeRecord(
                    t_unix_s=t, beacon=beacon, range_m=rng, travel_time_s=owtt, source=str(p), line=number
                )
        if text.startswith("#"):
            qc.lines_read -= 1
            return None
        fields = [f.strip() for f in text.split(",")]
        names = [f.lower() for f in fields]
        if len(names) == 3 and names[0] == "utc" and names[1] == "beacon" and names[2] in RANGE_COLUMNS:
            self.column = names[2]
            qc.lines_read -= 1
            return None
        if self.column is None:
            raise DataError(
                f"{p}:{number}: expected a header 'utc,beacon,range_m' (or owtt_s, twtt_s), got {text[:60]!r}"
            )
        if len(fields) != 3 or not all(fields):
            qc.add(p, number, "truncated sentence", f"{len(fields)} fields, expected 3")
            return None
        try:
            t = _parse_utc(fields[0])
        except (ValueError, OverflowError):
            qc.add(p, number, "non-numeric field", f"utc {fields[0][:40]!r} is not ISO 8601")
            return None
        try:
            beacon = int(fields[1])
            value = float(fields[2])
        except ValueError:
            qc.add(p, number, "non-numeric field", f"{fields[1][:12]!r}, {fields[2][:20]!r}")
            return None
        if problem := time_problem(t):
            qc.add(p, number, "out of range", problem)
            return None
        if not BEACON_ID_RANGE[0] <= beacon <= BEACON_ID_RANGE[1]:
            qc.add(p, number, "out of range", _beacon_problem(fields[1]))
            return None
        if not math.isfinite(value):
            qc.add(p, number, "NaN or infinite value", self.column)
            return None
        factor = RANGE_COLUMNS[self.column]
        rng = value if factor == 0.0 else factor * self.sound_speed_mps * value
        if not 0.0 < rng <= self.max_range_m:
            detail = f"{rng:.6g} m is not in (0, {self.max_range_m:g}] m"
            qc.add(p, number, "negative or absurd range", detail)
            return None
        if self.known is not None and beacon not in self.known:
            qc.add(p, number, "unknown beacon id", str(beacon))
            return None
        if t < self.last_t:
            qc.add(p, number, "time going backwards", f"{t - self.last_t:+.3f} s")
            return None
        if t == self.last_t and (first := self._at_last_t.get(beacon)) is not None:
            same = "the same range" if first[0] == rng else f"another range ({first[0]:g} m)"
            detail = f"beacon {beacon} at this time has {same} on line {first[1]}"
            qc.add(p, number, "duplicate record", detail)
            return None
        if t > self.last_t:
            self._at_last_t.clear()
            self.last_t = t
        self._at_last_t[beacon] = (rng, number)
        qc.records_kept += 1
        owtt = None if factor == 0.0 else rng / self.sound_speed_mps
        return RangeRecord(
            t_unix_s=t, beacon=beacon, range_m=rng, travel_time_s=owtt, source=str(p), line=number
        )

    def _fast_values(self, number: int, text: str, qc: QcReport) -> tuple[float, int, float, int] | object:
        """``(t, beacon, range_m, line)`` of a line :meth:`feed` keeps, by string operations, or ``_SLOW``.

        Accepts only an ASCII ``YYYY-MM-DDTHH:MM:SS.fff[fff]Z,digits,number`` line (no spaces) that the
        general rules keep with no QC issue, with the same values bit for bit and the same state change;
        anything else (a header, a comment, any problem) gives ``_SLOW`` and changes nothing.
        """
        fields = text.split(",")
        if len(fields) != 3 or self.column is None or not text.isascii():
            return _SLOW
        stamp, beacon_s, value_s = fields
        n = len(stamp)
        if (
            (n != 24 and n != 27)
            or stamp[4] != "-"
            or stamp[7] != "-"
            or stamp[10] != "T"
            or stamp[19] != "."
            or stamp[-1] != "Z"
            or stamp[13] != ":"
            or stamp[16] != ":"
            or not (
                stamp[:4] + stamp[5:7] + stamp[8:10] + stamp[11:13] + stamp[14:16] + stamp[17:19]
            ).isdigit()
            or not stamp[20:-1].isdigit()
            or not beacon_s.isdigit()
            or value_s != value_s.strip()
        ):
            return _SLOW
        days = self._days.get(stamp[:10])
        if days is None:
            try:
                date = dt.date.fromisoformat(stamp[:10])
            except ValueError:
                return _SLOW
            days = self._days[stamp[:10]] = date.toordinal() - _EPOCH_ORDINAL
        hour, minute, second = int(stamp[11:13]), int(stamp[14:16]), int(stamp[17:19])
        if hour > 23 or minute > 59 or second > 59:
            return _SLOW
        us = int(stamp[20:-1]) * (1000 if n == 24 else 1)
        # As datetime.timestamp(): whole microseconds since the epoch, divided once.
        t = ((days * 86_400 + hour * 3600 + minute * 60 + second) * 1_000_000 + us) / 1_000_000
        beacon = int(beacon_s)
        try:
            value = float(value_s)
        except ValueError:
            return _SLOW
        factor = RANGE_COLUMNS[self.column]
        rng = value if factor == 0.0 else factor * self.sound_speed_mps * value
        if (
            not TIME_RANGE_UNIX_S[0] <= t <= TIME_RANGE_UNIX_S[1]
            or beacon > BEACON_ID_RANGE[1]
            or not math.isfinite(value)
            or not 0.0 < rng <= self.max_range_m
            or (self.known is not None and beacon not in self.known)
            or t < self.last_t
            or (t == self.last_t and beacon in self._at_last_t)
        ):
            return _SLOW
        if t > self.last_t:
            self._at_last_t.clear()
            self.last_t = t
        self._at_last_t[beacon] = (rng, number)
        qc.records_kept += 1
        return (t, beacon, rng, number)


_SLOW = object()
"""What :meth:`UsblLineParser._fast_values` returns for a line the general rules must decide."""

_EPOCH_ORDINAL = dt.date(1970, 1, 1).toordinal()


def range_log_from_records(
    records: Sequence[RangeRecord | None], qc: QcReport, source: str = "stream"
) -> RangeLog:
    """The :class:`RangeLog` of the ``ok`` records (None: no record), as :func:`read_usbl` returns it.

    Raises
    ------
    DataError
        If there is no ``ok`` record.
    """
    ok = [r for r in records if r is not None and r.ok and r.range_m is not None]
    if not ok:
        raise DataError(f"{source}: no valid range ({qc.summary(max_lines=3)})")
    return RangeLog(
        t_unix_s=np.asarray([r.t_unix_s for r in ok], dtype=float),
        beacon=np.asarray([r.beacon for r in ok], dtype=np.int64),
        range_m=np.asarray([r.range_m for r in ok], dtype=float),
        line=np.asarray([r.line for r in ok], dtype=np.int64),
        qc=qc,
    )


_ISO_UTC_RE = re.compile(
    r"(?P<date>\d{4}-\d{2}-\d{2}|\d{8})[Tt ](?P<time>\d{2}(?::?\d{2}(?::?\d{2}(?:[.,]\d+)?)?)?)"
    r"\s*(?P<tz>[Zz]|UTC|GMT|[+-]\d{2}(?::?\d{2})?)?"
)


def _parse_utc(text: str) -> float:
    """ISO 8601 date and time to Unix seconds; ``Z``, ``UTC``, ``GMT`` or an offset (``+02``, ``+0200``,
    ``+02:00``, with or without a space before it); no zone means UTC. ValueError if not ISO 8601."""
    match = _ISO_UTC_RE.fullmatch(text.strip())
    if match:
        tz = match["tz"] or ""
        tz = "+00:00" if tz.upper() in ("Z", "UTC", "GMT") else tz
        text = f"{match['date']}T{match['time']}{tz}"
    stamp = dt.datetime.fromisoformat(text)
    if stamp.tzinfo is None:
        stamp = stamp.replace(tzinfo=dt.UTC)
    return stamp.timestamp()


def _beacon_problem(text: str) -> str:
    shown = text if len(text) <= 24 else f"{text[:10]}...{text[-6:]} ({len(text)} digits)"
    return f"beacon id {shown} is outside [{BEACON_ID_RANGE[0]}, {BEACON_ID_RANGE[1]}]"


def format_utc(t_unix_s: float) -> str:
    """ISO 8601 UTC with milliseconds and a ``Z``."""
    stamp = dt.datetime.fromtimestamp(t_unix_s, tz=dt.UTC)
    return stamp.strftime("%Y-%m-%dT%H:%M:%S.") + f"{stamp.microsecond // 1000:03d}Z"


@dataclass(frozen=True, slots=True, kw_only=True)
class AlignedRanges:
    """Ranges with the vehicle position interpolated to their epochs.

    Attributes
    ----------
    t_unix_s : (m,) float
    beacon : (m,) int
    range_m : (m,) float
    vehicle_enu_m : (m, 3) float
        GPS antenna position at each range epoch, local ENU, metres.
    origin : EnuOrigin
        The frame's origin (the first GPS fix, as in the papers).
    dropped_no_gps : int
        Ranges with no GPS fix within ``max_gap_s``: dropped and counted.
    line : (m,) int
    """

    t_unix_s: FloatArray
    beacon: IntArray
    range_m: FloatArray
    vehicle_enu_m: FloatArray
    origin: EnuOrigin
    dropped_no_gps: int
    line: IntArray

    def select(self, beacon: int) -> BoolArray:
        return self.beacon == beacon


def align_ranges(
    gps: GpsLog,
    ranges: RangeLog,
    origin: EnuOrigin | None = None,
    max_gap_s: float = 2.0,
    *,
    track_enu_m: FloatArray | None = None,
) -> AlignedRanges:
    """Interpolate the GPS track (in ENU) to each range epoch.

    A range is kept only if GPS fixes exist on both sides within ``max_gap_s`` of it (linear
    interpolation between them); otherwise it is dropped and counted in ``dropped_no_gps``. The ENU
    origin defaults to the first fix, as in the papers. ``track_enu_m (n, 3)``: the fixes already in
    ENU of ``origin``, if the caller has them (else converted here).
    """
    if max_gap_s <= 0.0:
        raise ConfigError("max_gap_s must be positive")
    org = origin or EnuOrigin(
        lat_deg=float(gps.lat_deg[0]), lon_deg=float(gps.lon_deg[0]), h_m=float(gps.h_m[0])
    )
    enu = geodetic_to_enu(gps.lat_deg, gps.lon_deg, gps.h_m, org) if track_enu_m is None else track_enu_m
    t = ranges.t_unix_s
    right = np.searchsorted(gps.t_unix_s, t, side="left")
    left = np.clip(right - 1, 0, gps.n_fixes - 1)
    right_c = np.clip(right, 0, gps.n_fixes - 1)
    exact = gps.t_unix_s[right_c] == t
    gap_l = t - gps.t_unix_s[left]
    gap_r = gps.t_unix_s[right_c] - t
    ok = exact | ((right > 0) & (right < gps.n_fixes) & (gap_l <= max_gap_s) & (gap_r <= max_gap_s))
    pos = np.stack([np.interp(t, gps.t_unix_s, enu[:, k]) for k in range(3)], axis=1)
    return AlignedRanges(
        t_unix_s=t[ok],
        beacon=ranges.beacon[ok],
        range_m=ranges.range_m[ok],
        vehicle_enu_m=pos[ok],
        origin=org,
        dropped_no_gps=int((~ok).sum()),
        line=ranges.line[ok],
    )
