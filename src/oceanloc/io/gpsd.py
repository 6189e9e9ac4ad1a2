"""A gpsd client: fixes and headings from gpsd's JSON protocol over TCP, with the NMEA reader's QC.

gpsd (https://gpsd.io) reads the GNSS receiver and serves reports as JSON objects, one per line, on TCP
port 2947. The client sends ``?WATCH={"enable":true,"json":true}`` and reads:

- ``TPV`` (time-position-velocity): ``time`` (ISO 8601 UTC), ``lat``, ``lon`` (WGS84 degrees),
  ``altHAE`` (height above the ellipsoid, metres; else ``altMSL + geoidSep``, else the older ``alt``
  plus ``geoidSep``), ``mode`` (0 unknown, 1 no fix, 2 2D, 3 3D);
- ``ATT`` with a ``heading`` (gpsd reports a true heading, such as NMEA HDT, this way); a ``HDG``
  object with a ``heading`` is read the same way.

Records are the NMEA reader's (:class:`~oceanloc.io.nmea.GpsFix`, :class:`~oceanloc.io.nmea.Heading`)
and so are the rules: ``mode`` below 2 is ``invalid fix``; a 2D fix without any altitude is
``invalid fix`` too (a height is needed for ENU); a latitude outside [-90, 90] or a longitude outside
[-180, 180] is ``out-of-range value``; a NaN is ``NaN or infinite value``; a fix whose time does not
advance is ``time going backwards``; a heading takes the latest fix's time (as HDT does in
:func:`~oceanloc.io.nmea.read_nmea`). A line that is not JSON is ``truncated sentence``; gpsd's own
``ERROR`` objects are recorded with their message. Other report classes (VERSION, DEVICES, WATCH, SKY,
...) are read and ignored. Issues name the source (``gpsd://host:port``) and the line number.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from collections.abc import Iterator

from oceanloc.errors import DataError
from oceanloc.io.nmea import GpsFix, Heading
from oceanloc.io.qc import QcReport
from oceanloc.io.transports import LineStream, TcpLineSource

WATCH = b'?WATCH={"enable":true,"json":true}\n'
DEFAULT_PORT = 2947


def _number(obj: dict, key: str) -> float | None:
    value = obj.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{key} {value!r} is not a number")
    return float(value)


def _parse_time(text: object) -> float:
    if not isinstance(text, str):
        raise ValueError(f"time {text!r} is not a string")
    stamp = dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    if stamp.tzinfo is None:
        stamp = stamp.replace(tzinfo=dt.UTC)
    return stamp.timestamp()


class GpsdReportParser:
    """Stateful parser of gpsd JSON report lines (module docstring); ``feed`` gives a record or None."""

    __slots__ = ("last_t",)

    def __init__(self) -> None:
        self.last_t = -math.inf

    def feed(self, number: int, text: str, qc: QcReport, source: str) -> GpsFix | Heading | None:
        try:
            obj = json.loads(text)
        except (json.JSONDecodeError, RecursionError):
            qc.add(source, number, "truncated sentence", f"not JSON: {text[:40]!r}")
            return None
        if not isinstance(obj, dict):
            qc.add(source, number, "truncated sentence", f"not a JSON object: {text[:40]!r}")
            return None
        kind = obj.get("class")
        if kind == "TPV":
            return self._tpv(obj, number, qc, source)
        if kind in ("ATT", "HDG") and "heading" in obj:
            try:
                heading = _number(obj, "heading")
            except ValueError as exc:
                qc.add(source, number, "non-numeric field", str(exc)[:60])
                return None
            if heading is None or not math.isfinite(heading):
                qc.add(source, number, "NaN or infinite value", "heading")
                return None
            if not -360.0 <= heading <= 360.0:
                qc.add(source, number, "out-of-range value", f"heading {heading}")
                return None
            return Heading(t_unix_s=self.last_t, heading_deg=heading % 360.0, source=source, line=number)
        if kind == "ERROR":
            qc.add(source, number, "gpsd error", str(obj.get("message", ""))[:80])
        return None

    def _tpv(self, obj: dict, number: int, qc: QcReport, source: str) -> GpsFix | None:
        mode = obj.get("mode", 0)
        if not isinstance(mode, int) or mode < 2:
            qc.add(source, number, "invalid fix", f"TPV mode {mode!r} (no fix)")
            return None
        if "time" not in obj or "lat" not in obj or "lon" not in obj:
            missing = [k for k in ("time", "lat", "lon") if k not in obj]
            qc.add(source, number, "truncated sentence", f"TPV without {', '.join(missing)}")
            return None
        try:
            t = _parse_time(obj["time"])
            lat, lon = _number(obj, "lat"), _number(obj, "lon")
            hae, msl, alt = _number(obj, "altHAE"), _number(obj, "altMSL"), _number(obj, "alt")
            sep = _number(obj, "geoidSep") or 0.0
        except ValueError as exc:
            qc.add(source, number, "non-numeric field", str(exc)[:60])
            return None
        if hae is not None:
            h = hae
        elif msl is not None:
            h = msl + sep
        elif alt is not None:
            h = alt + sep
        else:
            qc.add(source, number, "invalid fix", f"{mode}D fix without altitude")
            return None
        if lat is None or lon is None or not (math.isfinite(lat) and math.isfinite(lon) and math.isfinite(h)):
            qc.add(source, number, "NaN or infinite value")
            return None
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0 and -12_000.0 < h < 100_000.0):
            qc.add(source, number, "out-of-range value", f"lat {lat}, lon {lon}, h {h} m")
            return None
        if t <= self.last_t:
            qc.add(source, number, "time going backwards", f"{t - self.last_t:+.2f} s")
            return None
        self.last_t = t
        qc.records_kept += 1
        return GpsFix(t_unix_s=t, lat_deg=lat, lon_deg=lon, h_m=h, source=source, line=number)


class GpsdClient(LineStream):
    """Connects to gpsd, asks it to watch, and yields fixes and headings (a context manager).

    Parameters
    ----------
    host, port : str, int
        gpsd's address (``127.0.0.1``, 2947).
    qc : QcReport, optional
        Where skipped reports are recorded.
    name : str
        The source name in QC issues and errors (default ``gpsd://host:port``).
    connect_timeout_s : float
        How long to wait for the connection, seconds.

    Raises
    ------
    DataError
        If gpsd cannot be reached, or closes the connection.
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        *,
        qc: QcReport | None = None,
        name: str = "",
        connect_timeout_s: float = 5.0,
    ) -> None:
        source = TcpLineSource(
            host, port, name or f"gpsd://{host}:{port}", connect_timeout_s=connect_timeout_s
        )
        super().__init__(source, qc)
        self.parser = GpsdReportParser()
        source.send(WATCH)

    def _parse(self, text: str) -> GpsFix | Heading | None:
        return self.parser.feed(self.line, text, self.qc, self.name)

    def records(self, idle_timeout_s: float) -> Iterator[GpsFix | Heading]:
        """Records as they come; :class:`~oceanloc.io.transports.StreamTimeoutError` after silence."""
        return super().records(idle_timeout_s)  # type: ignore[return-value]


def read_gpsd_lines(lines: Iterator[str] | list[str], source: str = "gpsd") -> tuple[list, QcReport]:
    """Parse recorded gpsd JSON lines (e.g. ``gpspipe -w`` output); returns (records, qc)."""
    qc = QcReport()
    parser = GpsdReportParser()
    out = []
    for number, text in enumerate(lines, start=1):
        if not text.strip():
            continue
        qc.lines_read += 1
        rec = parser.feed(number, text.strip(), qc, source)
        if rec is not None:
            out.append(rec)
    if not out:
        raise DataError(f"{source}: no valid fix or heading ({qc.summary(max_lines=3)})")
    return out, qc
