"""The file readers' line rules, one line at a time: for streams (UDP, TCP, serial, gpsd, SeaTrac).

:func:`~oceanloc.io.nmea.read_nmea` and :func:`~oceanloc.io.usbl.read_usbl` read whole files; a live
survey gets the same lines one by one. This module applies, line by line and with the same state (the
NMEA date from RMC/ZDA, the last time kept), the rules those readers apply, recording skipped lines in
the same :class:`~oceanloc.io.qc.QcReport` with the same reasons:

- :func:`decode_line`: bytes to text as :func:`~oceanloc.io.qc.read_lines` does (NUL bytes or invalid
  UTF-8: ``wrong encoding``; blank lines are not counted);
- :class:`NmeaLineParser`: checksum, sentence types, GGA quality, date, ``time going backwards``, as
  :func:`~oceanloc.io.nmea.read_nmea`; yields :class:`GpsFix` and :class:`Heading` records;
- :class:`UsblLineParser`: the USBL CSV line (``utc,beacon,range_m`` or ``owtt_s``/``twtt_s``), as
  :func:`~oceanloc.io.usbl.read_usbl`; yields :class:`RangeRecord`.

``tests/io/test_lines.py`` checks that a file fed line by line gives exactly the fixes, ranges and QC
issues of the file reader. :func:`gps_log_from_records` and :func:`range_log_from_records` turn
collected records into the readers' :class:`~oceanloc.io.nmea.GpsLog` and
:class:`~oceanloc.io.usbl.RangeLog`, so a live stream and a file go through one code path.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pynmea2

from oceanloc.errors import ConfigError, DataError
from oceanloc.io.nmea import GpsLog
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import RANGE_COLUMNS, RangeLog, _parse_utc


def decode_line(raw: bytes, number: int, qc: QcReport, source: str | Path) -> str | None:
    """One raw line as text (stripped), or None if blank or not valid text (then recorded in ``qc``)."""
    if not raw.strip():
        return None
    qc.lines_read += 1
    if b"\x00" in raw:
        qc.add(source, number, "wrong encoding", "NUL bytes")
        return None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        qc.add(source, number, "wrong encoding", f"not UTF-8 at byte {exc.start}")
        return None
    return text.strip().lstrip("\ufeff")


# ------------------------------------------------------------------------------------------------ NMEA


@dataclass(frozen=True, slots=True, kw_only=True)
class GpsFix:
    """One GPS fix: UTC Unix seconds, WGS84 degrees and ellipsoidal height (m); where it came from."""

    t_unix_s: float
    lat_deg: float
    lon_deg: float
    h_m: float
    source: str = ""
    line: int = 0

    def to_record(self) -> dict:
        return {
            "t_unix_s": self.t_unix_s,
            "lat_deg": self.lat_deg,
            "lon_deg": self.lon_deg,
            "h_m": self.h_m,
            "source": self.source,
            "line": self.line,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class Heading:
    """A true heading (degrees clockwise from north) at ``t_unix_s`` (the latest fix's time when read)."""

    t_unix_s: float
    heading_deg: float
    source: str = ""
    line: int = 0

    def to_record(self) -> dict:
        return {
            "t_unix_s": self.t_unix_s,
            "heading_deg": self.heading_deg,
            "source": self.source,
            "line": self.line,
        }


class NmeaLineParser:
    """Stateful NMEA 0183 line parser with :func:`~oceanloc.io.nmea.read_nmea`'s rules.

    State: the date of the latest RMC or ZDA and the time of the latest fix kept. ``feed`` returns a
    :class:`GpsFix`, a :class:`Heading` or None (a date sentence, or a line skipped and recorded).
    """

    __slots__ = ("date", "last_t")

    def __init__(self) -> None:
        self.date: dt.date | None = None
        self.last_t = -math.inf

    def feed(self, number: int, text: str, qc: QcReport, source: str | Path) -> GpsFix | Heading | None:
        p = source
        start = text.find("$")
        if start < 0:
            qc.add(p, number, "truncated sentence", "no '$'")
            return None
        text = text[start:]
        try:
            msg = pynmea2.parse(text, check=True)
        except pynmea2.ChecksumError as exc:
            reason = "truncated sentence" if "missing" in str(exc) else "bad checksum"
            qc.add(p, number, reason, text[:40])
            return None
        except pynmea2.SentenceTypeError:
            qc.add(p, number, "unsupported sentence", text[:12])
            return None
        except (pynmea2.ParseError, ValueError) as exc:
            qc.add(p, number, "truncated sentence", str(exc)[:60])
            return None
        try:
            kind = msg.sentence_type
            if kind == "ZDA":
                self.date = msg.datetime.date()
                return None
            if kind == "HDT":
                heading = float(msg.heading)
                if not np.isfinite(heading):
                    raise ValueError("heading")
                return Heading(t_unix_s=self.last_t, heading_deg=heading, source=str(p), line=number)
            if kind == "RMC":
                if msg.datestamp is not None:
                    self.date = msg.datestamp
                if msg.status != "A":
                    qc.add(p, number, "invalid fix", "RMC status V")
                return None
            if kind != "GGA":
                qc.add(p, number, "unsupported sentence", kind)
                return None
            if msg.timestamp is None or not msg.lat or not msg.lon:
                qc.add(p, number, "truncated sentence", "empty time or position")
                return None
            if int(msg.gps_qual or 0) == 0:
                qc.add(p, number, "invalid fix", "GGA quality 0")
                return None
            if self.date is None:
                qc.add(p, number, "no date", "GGA before any RMC or ZDA")
                return None
            lat, lon = float(msg.latitude), float(msg.longitude)
            h = float(msg.altitude) + float(msg.geo_sep or 0.0)
        except (ValueError, TypeError, AttributeError) as exc:
            qc.add(p, number, "non-numeric field", str(exc)[:60])
            return None
        if not (np.isfinite(lat) and np.isfinite(lon) and np.isfinite(h)):
            qc.add(p, number, "NaN or infinite value")
            return None
        t = dt.datetime.combine(self.date, msg.timestamp).replace(tzinfo=dt.UTC).timestamp()
        if t <= self.last_t:
            qc.add(p, number, "time going backwards", f"{t - self.last_t:+.2f} s")
            return None
        self.last_t = t
        qc.records_kept += 1
        return GpsFix(t_unix_s=t, lat_deg=lat, lon_deg=lon, h_m=h, source=str(p), line=number)


def gps_log_from_records(
    fixes: Sequence[GpsFix], headings: Sequence[Heading], qc: QcReport, source: str = "stream"
) -> GpsLog:
    """The :class:`~oceanloc.io.nmea.GpsLog` of collected records (DataError if there is no fix)."""
    if not fixes:
        raise DataError(f"{source}: no valid GPS fix ({qc.summary(max_lines=3)})")
    a = np.asarray([(f.t_unix_s, f.lat_deg, f.lon_deg, f.h_m) for f in fixes], dtype=float)
    hd = np.asarray([(h.t_unix_s, h.heading_deg) for h in headings], dtype=float).reshape(-1, 2)
    return GpsLog(
        t_unix_s=a[:, 0],
        lat_deg=a[:, 1],
        lon_deg=a[:, 2],
        h_m=a[:, 3],
        heading_t_unix_s=hd[:, 0],
        heading_deg=hd[:, 1],
        line=np.asarray([f.line for f in fixes], dtype=np.int64),
        qc=qc,
    )


# ------------------------------------------------------------------------------------------------ USBL


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
    """Stateful USBL range-line parser with :func:`~oceanloc.io.usbl.read_usbl`'s rules.

    ``column`` presets the measurement column (``range_m``, ``owtt_s`` or ``twtt_s``) for a stream that
    sends no header; a header line (``utc,beacon,range_m``) sets or changes it whenever it arrives.
    Without a column, a first line that is not a header is a :class:`DataError`, as in a file.
    """

    __slots__ = ("column", "known", "last_t", "max_range_m", "sound_speed_mps")

    def __init__(
        self,
        *,
        sound_speed_mps: float = 1500.0,
        beacons: Collection[int] | None = None,
        max_range_m: float = 10_000.0,
        column: str | None = None,
    ) -> None:
        if not 1300.0 <= sound_speed_mps <= 1700.0:
            raise ConfigError(f"sound speed {sound_speed_mps} m/s is outside [1300, 1700]")
        if column is not None and column not in RANGE_COLUMNS:
            raise ConfigError(f"range column {column!r} is not one of {', '.join(RANGE_COLUMNS)}")
        self.sound_speed_mps = float(sound_speed_mps)
        self.known = None if beacons is None else {int(b) for b in beacons}
        self.max_range_m = float(max_range_m)
        self.column = column
        self.last_t = -math.inf

    def feed(self, number: int, text: str, qc: QcReport, source: str | Path) -> RangeRecord | None:
        p = source
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
        except ValueError:
            qc.add(p, number, "non-numeric field", f"utc {fields[0][:30]!r}")
            return None
        try:
            beacon = int(fields[1])
            value = float(fields[2])
        except ValueError:
            qc.add(p, number, "non-numeric field", f"{fields[1][:12]!r}, {fields[2][:20]!r}")
            return None
        if not math.isfinite(value):
            qc.add(p, number, "NaN or infinite value", self.column)
            return None
        factor = RANGE_COLUMNS[self.column]
        rng = value if factor == 0.0 else factor * self.sound_speed_mps * value
        if not 0.0 < rng <= self.max_range_m:
            qc.add(p, number, "negative or absurd range", f"{rng:.3f} m")
            return None
        if self.known is not None and beacon not in self.known:
            qc.add(p, number, "unknown beacon id", str(beacon))
            return None
        if t < self.last_t:
            qc.add(p, number, "time going backwards", f"{t - self.last_t:+.3f} s")
            return None
        self.last_t = t
        qc.records_kept += 1
        owtt = None if factor == 0.0 else rng / self.sound_speed_mps
        return RangeRecord(
            t_unix_s=t, beacon=beacon, range_m=rng, travel_time_s=owtt, source=str(p), line=number
        )


def range_log_from_records(records: Sequence[RangeRecord], qc: QcReport, source: str = "stream") -> RangeLog:
    """The :class:`~oceanloc.io.usbl.RangeLog` of the ``ok`` records (DataError if there is none)."""
    ok = [r for r in records if r.ok and r.range_m is not None]
    if not ok:
        raise DataError(f"{source}: no valid range ({qc.summary(max_lines=3)})")
    return RangeLog(
        t_unix_s=np.asarray([r.t_unix_s for r in ok], dtype=float),
        beacon=np.asarray([r.beacon for r in ok], dtype=np.int64),
        range_m=np.asarray([r.range_m for r in ok], dtype=float),
        line=np.asarray([r.line for r in ok], dtype=np.int64),
        qc=qc,
    )
