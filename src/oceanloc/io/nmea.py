"""NMEA 0183 GPS logs through pynmea2: GGA (position), RMC (position, date), HDT (heading), ZDA (date).

Every sentence's checksum is verified (a sentence without one is rejected too). Times are UTC: GGA
carries only the time of day, so the date comes from the latest RMC or ZDA before it (a GGA before any
date is skipped with reason ``no date``). Positions are WGS84 latitude, longitude and ellipsoidal height
(GGA altitude above the geoid plus the geoid separation). Fixes with quality 0 are skipped as
``invalid fix``; fixes whose time does not advance are skipped as ``time going backwards``.

Example::

    $GPZDA,184353.00,04,01,2018,00,00*60
    $GPGGA,184353.00,3242.3000,N,11714.1600,W,2,09,0.9,-1.478,M,0.0,M,,*63
    $GPHDT,13.0,T*07
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pynmea2

from oceanloc._typing import FloatArray, IntArray
from oceanloc.errors import DataError
from oceanloc.io.qc import QcReport, read_lines


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
    """

    t_unix_s: FloatArray
    lat_deg: FloatArray
    lon_deg: FloatArray
    h_m: FloatArray
    heading_t_unix_s: FloatArray
    heading_deg: FloatArray
    line: IntArray
    qc: QcReport

    @property
    def n_fixes(self) -> int:
        return int(self.t_unix_s.size)


def read_nmea(path: str | Path, qc: QcReport | None = None) -> GpsLog:
    """Read an NMEA 0183 log; bad lines are skipped and recorded (see the module docstring).

    Raises
    ------
    DataError
        If the file cannot be read or holds no valid fix.
    """
    p = Path(path)
    qc = QcReport() if qc is None else qc
    date: dt.date | None = None
    rows: list[tuple[float, float, float, float]] = []
    lines: list[int] = []
    headings: list[tuple[float, float]] = []
    last_t = -np.inf
    for number, text in read_lines(p, qc):
        start = text.find("$")
        if start < 0:
            qc.add(p, number, "truncated sentence", "no '$'")
            continue
        text = text[start:]
        try:
            msg = pynmea2.parse(text, check=True)
        except pynmea2.ChecksumError as exc:
            reason = "truncated sentence" if "missing" in str(exc) else "bad checksum"
            qc.add(p, number, reason, text[:40])
            continue
        except pynmea2.SentenceTypeError:
            qc.add(p, number, "unsupported sentence", text[:12])
            continue
        except (pynmea2.ParseError, ValueError) as exc:
            qc.add(p, number, "truncated sentence", str(exc)[:60])
            continue
        try:
            kind = msg.sentence_type
            if kind == "ZDA":
                date = msg.datetime.date()
                continue
            if kind == "HDT":
                heading = float(msg.heading)
                if not np.isfinite(heading):
                    raise ValueError("heading")
                headings.append((last_t, heading))
                continue
            if kind == "RMC":
                if msg.datestamp is not None:
                    date = msg.datestamp
                if msg.status != "A":
                    qc.add(p, number, "invalid fix", "RMC status V")
                continue  # positions come from GGA, which carries the height
            if kind != "GGA":
                qc.add(p, number, "unsupported sentence", kind)
                continue
            if msg.timestamp is None or not msg.lat or not msg.lon:
                qc.add(p, number, "truncated sentence", "empty time or position")
                continue
            if int(msg.gps_qual or 0) == 0:
                qc.add(p, number, "invalid fix", "GGA quality 0")
                continue
            if date is None:
                qc.add(p, number, "no date", "GGA before any RMC or ZDA")
                continue
            lat, lon = float(msg.latitude), float(msg.longitude)
            h = float(msg.altitude) + float(msg.geo_sep or 0.0)
        except (ValueError, TypeError, AttributeError) as exc:
            qc.add(p, number, "non-numeric field", str(exc)[:60])
            continue
        if not (np.isfinite(lat) and np.isfinite(lon) and np.isfinite(h)):
            qc.add(p, number, "NaN or infinite value")
            continue
        t = dt.datetime.combine(date, msg.timestamp).replace(tzinfo=dt.UTC).timestamp()
        if t <= last_t:
            qc.add(p, number, "time going backwards", f"{t - last_t:+.2f} s")
            continue
        last_t = t
        rows.append((t, lat, lon, h))
        lines.append(number)
    qc.records_kept += len(rows)
    if not rows:
        raise DataError(f"{p}: no valid GPS fix ({qc.summary(max_lines=3)})")
    a = np.asarray(rows)
    hd = np.asarray(headings).reshape(-1, 2)
    return GpsLog(
        t_unix_s=a[:, 0],
        lat_deg=a[:, 1],
        lon_deg=a[:, 2],
        h_m=a[:, 3],
        heading_t_unix_s=hd[:, 0],
        heading_deg=hd[:, 1],
        line=np.asarray(lines, dtype=np.int64),
        qc=qc,
    )


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
