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
the first is used) are skipped and recorded in the QC report.
"""

from __future__ import annotations

import datetime as dt
import math
import re
from collections.abc import Collection
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
    """Read a USBL range CSV (see the module docstring).

    Raises
    ------
    DataError
        If the file cannot be read, has no recognizable header, or holds no valid range.
    """
    p = Path(path)
    qc = QcReport() if qc is None else qc
    if not 1300.0 <= sound_speed_mps <= 1700.0:
        raise ConfigError(f"sound speed {sound_speed_mps} m/s is outside [1300, 1700]")
    if not (math.isfinite(max_range_m) and max_range_m > 0.0):
        raise ConfigError(f"max_range_m {max_range_m} m must be positive and finite")
    known = None if beacons is None else {int(b) for b in beacons}
    columns: list[str] | None = None
    rows: list[tuple[float, int, float]] = []
    lines: list[int] = []
    last_t = -math.inf
    seen: dict[tuple[float, int], int] = {}  # (time, beacon) -> index in rows
    for number, text in read_lines(p, qc):
        if text.startswith("#"):
            qc.lines_read -= 1
            continue
        fields = [f.strip() for f in text.split(",")]
        if columns is None:
            names = [f.lower() for f in fields]
            if len(names) == 3 and names[0] == "utc" and names[1] == "beacon" and names[2] in RANGE_COLUMNS:
                columns = names
                qc.lines_read -= 1
                continue
            raise DataError(
                f"{p}:{number}: expected a header 'utc,beacon,range_m' (or owtt_s, twtt_s), got {text[:60]!r}"
            )
        if len(fields) != 3 or not all(fields):
            qc.add(p, number, "truncated sentence", f"{len(fields)} fields, expected 3")
            continue
        try:
            t = _parse_utc(fields[0])
        except (ValueError, OverflowError):
            qc.add(p, number, "non-numeric field", f"utc {fields[0][:40]!r} is not ISO 8601")
            continue
        try:
            beacon = int(fields[1])
            value = float(fields[2])
        except ValueError:
            qc.add(p, number, "non-numeric field", f"{fields[1][:12]!r}, {fields[2][:20]!r}")
            continue
        if problem := time_problem(t):
            qc.add(p, number, "out of range", problem)
            continue
        if not BEACON_ID_RANGE[0] <= beacon <= BEACON_ID_RANGE[1]:
            qc.add(p, number, "out of range", _beacon_problem(fields[1]))
            continue
        if not math.isfinite(value):
            qc.add(p, number, "NaN or infinite value", columns[2])
            continue
        factor = RANGE_COLUMNS[columns[2]]
        rng = value if factor == 0.0 else factor * sound_speed_mps * value
        if not 0.0 < rng <= max_range_m:
            qc.add(p, number, "negative or absurd range", f"{rng:.6g} m is not in (0, {max_range_m:g}] m")
            continue
        if known is not None and beacon not in known:
            qc.add(p, number, "unknown beacon id", str(beacon))
            continue
        if t < last_t:
            qc.add(p, number, "time going backwards", f"{t - last_t:+.3f} s")
            continue
        if (first := seen.get((t, beacon))) is not None:
            same = "the same range" if rows[first][2] == rng else f"another range ({rows[first][2]:g} m)"
            qc.add(
                p,
                number,
                "duplicate record",
                f"beacon {beacon} at this time has {same} on line {lines[first]}",
            )
            continue
        seen[(t, beacon)] = len(rows)
        last_t = t
        rows.append((t, beacon, rng))
        lines.append(number)
    qc.records_kept += len(rows)
    if not rows:
        raise DataError(f"{p}: no valid range ({qc.summary(max_lines=3)})")
    t_arr, b_arr, r_arr = (np.asarray(c) for c in zip(*rows, strict=True))
    return RangeLog(
        t_unix_s=t_arr.astype(float),
        beacon=b_arr.astype(np.int64),
        range_m=r_arr.astype(float),
        line=np.asarray(lines, dtype=np.int64),
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
    gps: GpsLog, ranges: RangeLog, origin: EnuOrigin | None = None, max_gap_s: float = 2.0
) -> AlignedRanges:
    """Interpolate the GPS track (in ENU) to each range epoch.

    A range is kept only if GPS fixes exist on both sides within ``max_gap_s`` of it (linear
    interpolation between them); otherwise it is dropped and counted in ``dropped_no_gps``. The ENU
    origin defaults to the first fix, as in the papers.
    """
    if max_gap_s <= 0.0:
        raise ConfigError("max_gap_s must be positive")
    org = origin or EnuOrigin(
        lat_deg=float(gps.lat_deg[0]), lon_deg=float(gps.lon_deg[0]), h_m=float(gps.h_m[0])
    )
    enu = geodetic_to_enu(gps.lat_deg, gps.lon_deg, gps.h_m, org)
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
