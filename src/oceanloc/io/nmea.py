"""NMEA 0183 GPS logs through pynmea2: GGA (position), RMC (position, date), HDT (heading), ZDA (date).

Every sentence's checksum is verified (a sentence without one is rejected too). Times are UTC: GGA
carries only the time of day, so the date comes from the latest RMC or ZDA before it (a GGA before any
date is skipped with reason ``no date``). Positions are WGS84 latitude, longitude and ellipsoidal height
(GGA altitude above the geoid plus the geoid separation). Fixes with quality 0 are skipped as
``invalid fix``; fixes whose time does not advance are skipped as ``time going backwards``; a value
outside its physical range (latitude, longitude, height, date, heading) is skipped as ``out of range``.
:class:`NmeaLineParser` holds these rules, one line at a time: :func:`read_nmea` feeds it a file's lines
and a live stream (:mod:`oceanloc.io.streams`) the lines it receives, so both keep the same fixes with
the same QC issues; :func:`gps_log_from_records` turns the records into a :class:`GpsLog`.

Speed: a well-formed GGA, RMC, HDT or ZDA sentence that is kept is read by plain string operations
(checksum, fields, the same floats bit for bit); every other line, and every line with a QC issue, goes
through pynmea2, the reference, so each reason and detail is pynmea2's reading
(``tests/io/test_nmea_fast.py`` compares the two).

Example::

    $GPZDA,184353.00,04,01,2018,00,00*60
    $GPGGA,184353.00,3242.3000,N,11714.1600,W,2,09,0.9,-1.478,M,0.0,M,,*63
    $GPHDT,13.0,T*07
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import reduce
from operator import xor
from pathlib import Path

import numpy as np
import pynmea2

from oceanloc._typing import FloatArray, IntArray
from oceanloc.errors import DataError
from oceanloc.io.qc import (
    HEIGHT_RANGE_M,
    LAT_RANGE_DEG,
    LON_RANGE_DEG,
    TIME_RANGE_UNIX_S,
    QcReport,
    out_of_range,
    read_lines,
    time_problem,
)


@dataclass(frozen=True, slots=True, kw_only=True)
class GpsLog:
    """Time-ordered GPS fixes.

    Attributes
    ----------
    t_unix_s : (n,) float
        UTC time of each fix, Unix seconds.
    lat_deg, lon_deg, h_m : (n,) float
        WGS84 position, degrees and metres (ellipsoidal).
    heading_t_unix_s, heading_deg : (h,) float
        HDT headings (true, degrees) and their times (the latest fix time when read).
    line : (n,) int
        Line number of each fix.
    qc : QcReport
    heading_line : (h,) int or None
        Line number of each heading (None when the headings do not come from a file).
    """

    t_unix_s: FloatArray
    lat_deg: FloatArray
    lon_deg: FloatArray
    h_m: FloatArray
    heading_t_unix_s: FloatArray
    heading_deg: FloatArray
    line: IntArray
    qc: QcReport
    heading_line: IntArray | None = None

    @property
    def n_fixes(self) -> int:
        return int(self.t_unix_s.size)


def read_nmea(path: str | Path, qc: QcReport | None = None) -> GpsLog:
    """Read an NMEA 0183 log; bad lines are skipped and recorded (see the module docstring).

    Every value used is range-checked before it is returned: a time of day that is not HH:MM:SS (such as
    ``186000.00``, ``246060`` or ``nan``), a date outside 1980-2099, a latitude outside [-90, 90] deg or a
    longitude outside [-180, 180] deg (or a hemisphere other than N/S, E/W), an ellipsoidal height
    outside :data:`~oceanloc.io.qc.HEIGHT_RANGE_M` or a heading outside [0, 360] deg makes its line a QC
    issue (``file:line: reason``), never a returned fix or an exception. The lines go through
    :class:`NmeaLineParser`, the rules a live stream applies too.

    Raises
    ------
    DataError
        If the file cannot be read or holds no valid fix.
    """
    p = Path(path)
    qc = QcReport() if qc is None else qc
    parser = NmeaLineParser()
    fast = parser._fast_values
    fixes: list[tuple[float, float, float, float, int]] = []
    headings: list[tuple[float, float, int]] = []
    for number, text in read_lines(p, qc):
        # Bulk path: the common well-formed sentences as plain tuples, every other line through feed.
        values = fast(number, text, qc)
        if values is _SLOW:
            rec = parser.feed(number, text, qc, p, fast=False)
            if isinstance(rec, GpsFix):
                fixes.append((rec.t_unix_s, rec.lat_deg, rec.lon_deg, rec.h_m, number))
            elif isinstance(rec, Heading):
                headings.append((rec.t_unix_s, rec.heading_deg, number))
        elif values is not None:
            (fixes if len(values) == 5 else headings).append(values)
    return _gps_log(fixes, headings, qc, str(p))


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
    """NMEA 0183 lines one at a time, with every rule of the module docstring: :func:`read_nmea`'s loop,
    and a live stream's (UDP, TCP, serial).

    State: the date of the latest RMC or ZDA and the time of the latest fix kept. :meth:`feed` returns a
    :class:`GpsFix`, a :class:`Heading` or None (a date sentence, or a line skipped and recorded in the
    :class:`~oceanloc.io.qc.QcReport` as ``source:number: reason (detail)``).
    """

    __slots__ = ("date", "last_t")

    def __init__(self) -> None:
        self.date: dt.date | None = None
        self.last_t = -math.inf

    def feed(
        self, number: int, text: str, qc: QcReport, source: str | Path, *, fast: bool = True
    ) -> GpsFix | Heading | None:
        """The record of one line of text (already decoded, see :func:`~oceanloc.io.qc.decode_line`).

        A well-formed GGA, RMC, HDT or ZDA sentence goes through a plain-string fast path
        (:meth:`_fast_values`); any line it does not fully accept, through pynmea2 (``fast=False``: only
        the latter), which gives every QC reason and detail. Both give the same records and state.
        """
        p = source
        if fast:
            values = self._fast_values(number, text, qc)
            if values is None:
                return None
            if values is not _SLOW:
                if len(values) == 5:
                    t, lat, lon, h, _ = values
                    return GpsFix(t_unix_s=t, lat_deg=lat, lon_deg=lon, h_m=h, source=str(p), line=number)
                return Heading(t_unix_s=values[0], heading_deg=values[1], source=str(p), line=number)
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
                _checked_time(msg.timestamp)
                self.date = _checked_date(msg.datetime.date())
                return None
            if kind == "HDT":
                heading = _checked_heading(msg.heading)
                return Heading(t_unix_s=self.last_t, heading_deg=heading, source=str(p), line=number)
            if kind == "RMC":
                rmc_date = _rmc_date(msg)
                if rmc_date is not None:
                    self.date = rmc_date
                if msg.status != "A":
                    qc.add(p, number, "invalid fix", "RMC status V")
                return None  # positions come from GGA, which carries the height
            if kind != "GGA":
                qc.add(p, number, "unsupported sentence", kind)
                return None
            t, lat, lon, h = _gga_fix(msg, self.date)
        except _UnusableSentenceError as skip:
            qc.add(p, number, skip.reason, skip.detail)
            return None
        except (ValueError, TypeError, AttributeError, OverflowError) as exc:
            qc.add(p, number, "non-numeric field", str(exc)[:60])
            return None
        if t <= self.last_t:
            qc.add(p, number, "time going backwards", f"{t - self.last_t:+.2f} s")
            return None
        self.last_t = t
        qc.records_kept += 1
        return GpsFix(t_unix_s=t, lat_deg=lat, lon_deg=lon, h_m=h, source=str(p), line=number)

    def _fast_values(self, number: int, text: str, qc: QcReport) -> tuple | object | None:
        """One line by plain string operations, or ``_SLOW`` where pynmea2 must decide.

        Accepts only what the pynmea2 path (:meth:`feed` with ``fast=False``) accepts with no QC issue,
        giving the same values bit for bit and the same state change: an ASCII ``$ttGGA``, ``$ttRMC``,
        ``$ttHDT`` or ``$ttZDA`` sentence (talker not ``P...``, no second ``*``) whose ``*HH`` checksum
        is right, with digits-only times, dates, hemispheres N/S E/W, ``DDMM.mmm`` coordinates and values
        in range; a fix also needs a date and a time after the latest fix's. Returns
        ``(t, lat, lon, h, line)`` for a fix, ``(t, heading, line)`` for a heading, None for a date
        sentence, ``_SLOW`` for anything else (nothing changed then).
        """
        start = text.find("$")
        if start < 0 or text[-3:-2] != "*" or not text.isascii():
            return _SLOW
        body = text[start + 1 : -3]
        if "*" in body or body[5:6] != "," or body[:1] in ("P", "p") or not body[:2].isalnum():
            return _SLOW
        if _HEX.get(text[-2:]) != reduce(xor, body.encode(), 0):
            return _SLOW
        kind = body[2:5]
        f = body[6:].split(",")
        if kind == "GGA":
            if len(f) < 11 or self.date is None or not f[5].isdigit() or int(f[5]) == 0:
                return _SLOW
            day_s = _day_seconds(f[0])
            lat = _signed_deg(f[1], f[2], "N", "S", 90.0)
            lon = _signed_deg(f[3], f[4], "E", "W", 180.0)
            if day_s is None or lat is None or lon is None:
                return _SLOW
            try:
                h = float(f[8]) + float(f[10] or 0.0)
            except ValueError:
                return _SLOW
            if not HEIGHT_RANGE_M[0] <= h <= HEIGHT_RANGE_M[1]:
                return _SLOW
            whole_s, us = day_s
            # As datetime.timestamp(): whole microseconds since the epoch, divided once.
            t = ((self.date.toordinal() - _EPOCH_ORDINAL) * 86_400 + whole_s) * 1_000_000 + us
            t /= 1_000_000
            if not (TIME_RANGE_UNIX_S[0] <= t <= TIME_RANGE_UNIX_S[1]) or t <= self.last_t:
                return _SLOW
            self.last_t = t
            qc.records_kept += 1
            return (t, lat, lon, h, number)
        if kind == "HDT":
            s = f[0]
            if not s.replace(".", "", 1).isdigit():
                return _SLOW
            heading = float(s)
            if heading > 360.0:
                return _SLOW
            return (self.last_t, heading, number)
        if kind == "ZDA":
            if len(f) < 4 or _day_seconds(f[0]) is None:
                return _SLOW
            date = _digits_date(f[3], f[2], f[1])
            if date is None:
                return _SLOW
            self.date = date
            return None
        if kind == "RMC":
            if len(f) < 9 or f[1] != "A" or (f[0] and _day_seconds(f[0]) is None):
                return _SLOW
            if (f[2] or f[4]) and (
                _signed_deg(f[2], f[3], "N", "S", 90.0) is None
                or _signed_deg(f[4], f[5], "E", "W", 180.0) is None
            ):
                return _SLOW
            d = f[8]
            if d:
                if len(d) != 6:
                    return _SLOW
                yy = d[4:]
                date = _digits_date(("20" if yy < "69" else "19") + yy, d[2:4], d[:2])
                if date is None:
                    return _SLOW
                self.date = date
            return None
        return _SLOW


_SLOW = object()
"""What :meth:`NmeaLineParser._fast_values` returns for a line the pynmea2 path must decide."""

_HEX = {a + b: int(a + b, 16) for a in "0123456789ABCDEFabcdef" for b in "0123456789ABCDEFabcdef"}
_EPOCH_ORDINAL = dt.date(1970, 1, 1).toordinal()


def _day_seconds(s: str) -> tuple[int, int] | None:
    """Whole seconds of the day and microseconds of ``HHMMSS[.s...]`` as pynmea2 reads it, else None."""
    frac = s[6:]
    if len(s) < 6 or not s[:6].isdigit() or (frac and (frac[0] != "." or not frac[1:].isdigit())):
        return None
    hour, minute, second = int(s[:2]), int(s[2:4]), int(s[4:6])
    us = int(float(frac) * 1_000_000) if frac else 0  # pynmea2's own rounding of the fraction
    if hour > 23 or minute > 59 or second > 59 or us > 999_999:
        return None
    return hour * 3600 + minute * 60 + second, us


def _signed_deg(dm: str, hemisphere: str, plus: str, minus: str, limit: float) -> float | None:
    """A ``DDDMM.mmm`` coordinate with its hemisphere as pynmea2's ``dm_to_sd``, within ``limit``."""
    if hemisphere != plus and hemisphere != minus:
        return None
    if dm == "0":
        sd = 0.0
    else:
        dot = dm.find(".")
        if dot < 3 or not dm[:dot].isdigit() or not dm[dot + 1 :].isdigit():
            return None
        sd = float(dm[: dot - 2]) + float(dm[dot - 2 :]) / 60
    if not sd <= limit:
        return None
    return sd if hemisphere == plus else -sd


def _digits_date(year: str, month: str, day: str) -> dt.date | None:
    """The date of digit-only fields, if valid and within the years the readers accept, else None."""
    if not (year.isdigit() and month.isdigit() and day.isdigit()):
        return None
    try:
        date = dt.date(int(year), int(month), int(day))
    except (ValueError, OverflowError):
        return None
    return date if _FIRST_YEAR <= date.year < _LAST_YEAR else None


def gps_log_from_records(
    fixes: Sequence[GpsFix], headings: Sequence[Heading], qc: QcReport, source: str = "stream"
) -> GpsLog:
    """The :class:`GpsLog` of collected records, as :func:`read_nmea` returns it (DataError if no fix)."""
    return _gps_log(
        [(f.t_unix_s, f.lat_deg, f.lon_deg, f.h_m, f.line) for f in fixes],
        [(h.t_unix_s, h.heading_deg, h.line) for h in headings],
        qc,
        source,
    )


def _gps_log(fixes: list[tuple], headings: list[tuple], qc: QcReport, source: str) -> GpsLog:
    """The :class:`GpsLog` of ``(t, lat, lon, h, line)`` fixes and ``(t, heading, line)`` headings."""
    if not fixes:
        raise DataError(f"{source}: no valid GPS fix ({qc.summary(max_lines=3)})")
    a = np.asarray(fixes, dtype=float)
    hd = np.asarray(headings, dtype=float).reshape(-1, 3)
    return GpsLog(
        t_unix_s=a[:, 0],
        lat_deg=a[:, 1],
        lon_deg=a[:, 2],
        h_m=a[:, 3],
        heading_t_unix_s=hd[:, 0],
        heading_deg=hd[:, 1],
        line=np.asarray([f[4] for f in fixes], dtype=np.int64),
        qc=qc,
        heading_line=np.asarray([h[2] for h in headings], dtype=np.int64),
    )


class _UnusableSentenceError(Exception):
    """A sentence that parses but cannot be used: its QC reason and detail."""

    def __init__(self, reason: str, detail: str = "") -> None:
        super().__init__(reason, detail)
        self.reason, self.detail = reason, detail


_FIRST_YEAR, _LAST_YEAR = (dt.datetime.fromtimestamp(t, tz=dt.UTC).year for t in TIME_RANGE_UNIX_S)


def _checked_date(date: object) -> dt.date:
    if not isinstance(date, dt.date):
        raise _UnusableSentenceError("non-numeric field", f"date {str(date)[:20]!r}")
    if not _FIRST_YEAR <= date.year < _LAST_YEAR:
        raise _UnusableSentenceError(
            "out of range", f"date {date.isoformat()} is outside {_FIRST_YEAR}-{_LAST_YEAR - 1}"
        )
    return date


def _checked_time(stamp: object) -> dt.time:
    # pynmea2 returns the raw text when the field is not a valid HHMMSS[.ss] time of day.
    if not isinstance(stamp, dt.time):
        raise _UnusableSentenceError(
            "non-numeric field", f"time of day {str(stamp)[:20]!r} is not HHMMSS[.ss]"
        )
    return stamp


def _checked_heading(text: object) -> float:
    heading = float(text)  # type: ignore[arg-type]
    if not math.isfinite(heading):
        raise _UnusableSentenceError("NaN or infinite value", "heading")
    if not 0.0 <= heading <= 360.0:
        raise _UnusableSentenceError("out of range", f"heading {heading:g} deg is outside [0, 360] deg")
    return heading


def _checked_position(msg: pynmea2.NMEASentence) -> tuple[float, float]:
    """Latitude and longitude of a GGA or RMC sentence, hemispheres and WGS84 ranges checked."""
    if msg.lat_dir not in ("N", "S") or msg.lon_dir not in ("E", "W"):
        raise _UnusableSentenceError(
            "non-numeric field", f"hemisphere {msg.lat_dir!r}, {msg.lon_dir!r} (expected N/S, E/W)"
        )
    lat, lon = float(msg.latitude), float(msg.longitude)
    if not (math.isfinite(lat) and math.isfinite(lon)):
        raise _UnusableSentenceError("NaN or infinite value", "position")
    for problem in (
        out_of_range("latitude", lat, LAT_RANGE_DEG, "deg"),
        out_of_range("longitude", lon, LON_RANGE_DEG, "deg"),
    ):
        if problem:
            raise _UnusableSentenceError("out of range", problem)
    return lat, lon


def _rmc_date(msg: pynmea2.NMEASentence) -> dt.date | None:
    """The date of an RMC sentence (None if empty); a corrupt time, date or position skips it all."""
    if msg.timestamp is not None:
        _checked_time(msg.timestamp)
    if msg.lat or msg.lon:
        _checked_position(msg)
    return None if msg.datestamp is None else _checked_date(msg.datestamp)


def _gga_fix(msg: pynmea2.NMEASentence, date: dt.date | None) -> tuple[float, float, float, float]:
    """Time (Unix s), latitude, longitude (deg) and ellipsoidal height (m) of a GGA sentence."""
    if msg.timestamp is None or not msg.lat or not msg.lon:
        raise _UnusableSentenceError("truncated sentence", "empty time or position")
    stamp = _checked_time(msg.timestamp)
    if int(msg.gps_qual or 0) == 0:
        raise _UnusableSentenceError("invalid fix", "GGA quality 0")
    if date is None:
        raise _UnusableSentenceError("no date", "GGA before any RMC or ZDA")
    lat, lon = _checked_position(msg)
    h = float(msg.altitude) + float(msg.geo_sep or 0.0)
    if not math.isfinite(h):
        raise _UnusableSentenceError("NaN or infinite value", "height")
    if problem := out_of_range("ellipsoidal height", h, HEIGHT_RANGE_M, "m"):
        raise _UnusableSentenceError("out of range", problem)
    t = dt.datetime.combine(date, stamp).replace(tzinfo=dt.UTC).timestamp()
    if problem := time_problem(t):
        raise _UnusableSentenceError("out of range", problem)
    return t, lat, lon, h


def format_gga(t: dt.datetime, lat_deg: float, lon_deg: float, h_m: float, quality: int = 2) -> str:
    """One GGA sentence with its checksum (geoid separation 0: the height is ellipsoidal)."""
    lat_s = f"{int(abs(lat_deg)):02d}{(abs(lat_deg) % 1) * 60:07.4f}"
    lon_s = f"{int(abs(lon_deg)):03d}{(abs(lon_deg) % 1) * 60:07.4f}"
    fields = (
        t.strftime("%H%M%S.%f")[:9],
        lat_s,
        "N" if lat_deg >= 0 else "S",
        lon_s,
        "E" if lon_deg >= 0 else "W",
        str(quality),
        "09",
        "0.9",
        f"{h_m:.3f}",
        "M",
        "0.0",
        "M",
        "",
        "",
    )
    return str(pynmea2.GGA("GP", "GGA", fields))


def format_zda(t: dt.datetime) -> str:
    """One ZDA sentence (date and time) with its checksum."""
    fields = (t.strftime("%H%M%S.%f")[:9], f"{t.day:02d}", f"{t.month:02d}", f"{t.year:04d}", "00", "00")
    return str(pynmea2.ZDA("GP", "ZDA", fields))


def format_hdt(heading_deg: float) -> str:
    """One HDT sentence (true heading) with its checksum."""
    return str(pynmea2.HDT("GP", "HDT", (f"{heading_deg % 360.0:.1f}", "T")))
