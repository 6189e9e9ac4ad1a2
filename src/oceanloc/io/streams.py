"""Live sources of positions and ranges, named by URL-like specs on the command line.

Specs (:func:`parse_spec`)::

    udp://127.0.0.1:10110              NMEA 0183 (or range lines) in UDP datagrams received on that address
    tcp://127.0.0.1:10110              NMEA 0183 (or range lines) from a TCP server, one per line
    serial:///dev/ttyUSB0?baud=9600    NMEA 0183 (or range lines) on a serial port (any pyserial URL path;
                                       baud 4800 by default, NMEA 0183's)
    gpsd://127.0.0.1:2947              fixes and headings from gpsd's JSON protocol (port 2947 by default)
    seatrac:///dev/ttyUSB1?beacons=1,2 ranges from a SeaTrac USBL pinging beacons 1 and 2 in turn
                                       (also ``baud``, ``timeout`` in seconds per ping, ``msg=REQ|REQU|REQX``)

Range lines over UDP, TCP or serial have the USBL CSV reader's format (``utc,beacon,range_m``; a header
line may switch the column to ``owtt_s`` or ``twtt_s``; ``?column=owtt_s`` presets it). Every line goes
through the file readers' own line parsers (:class:`~oceanloc.io.nmea.NmeaLineParser`,
:class:`~oceanloc.io.usbl.UsblLineParser`): a bad line is recorded in the stream's
:class:`~oceanloc.io.qc.QcReport` as ``<spec>:<line number>: <reason> (<detail>)`` and skipped; a
stream never raises anything but the project's errors (:class:`~oceanloc.errors.ConfigError` for a bad
spec, :class:`~oceanloc.errors.DataError` for a source that cannot be opened or fails).

Every stream has ``read(timeout_s) -> record | None``: the next record (a
:class:`~oceanloc.io.nmea.GpsFix`, :class:`~oceanloc.io.nmea.Heading` or
:class:`~oceanloc.io.usbl.RangeRecord`), or None when nothing valid arrived within ``timeout_s``,
so the survey loop can notice a silent link and act; and ``records(idle_timeout_s)``, an iterator
that raises :class:`StreamTimeoutError` after ``idle_timeout_s`` of silence.
"""

from __future__ import annotations

import time
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from urllib.parse import parse_qsl, urlsplit

from oceanloc.errors import ConfigError
from oceanloc.io.gpsd import GpsdClient
from oceanloc.io.nmea import GpsFix, Heading, NmeaLineParser
from oceanloc.io.qc import QcReport
from oceanloc.io.seatrac import MsgType, SeatracPinger
from oceanloc.io.transports import (
    LineSource,
    LineStream,
    SerialLineSource,
    StreamTimeoutError,
    TcpLineSource,
    UdpLineSource,
)
from oceanloc.io.usbl import RANGE_COLUMNS, RangeRecord, UsblLineParser

SCHEMES: tuple[str, ...] = ("udp", "tcp", "serial", "gpsd", "seatrac")
POSITION_SCHEMES: tuple[str, ...] = ("udp", "tcp", "serial", "gpsd")
RANGE_SCHEMES: tuple[str, ...] = ("udp", "tcp", "serial", "seatrac")
_PARAMS: dict[str, frozenset[str]] = {
    "udp": frozenset({"column"}),
    "tcp": frozenset({"column"}),
    "serial": frozenset({"baud", "column"}),
    "gpsd": frozenset(),
    "seatrac": frozenset({"baud", "beacons", "timeout", "msg"}),
}
_DEFAULT_PORT = {"gpsd": 2947}


@dataclass(frozen=True, slots=True, kw_only=True)
class StreamSpec:
    """A parsed source spec (see the module docstring); ``text`` is the spec as given."""

    text: str
    scheme: str
    host: str = ""
    port: int = 0
    path: str = ""
    params: Mapping[str, str] = field(default_factory=lambda: MappingProxyType({}))

    @property
    def baud(self) -> int:
        """Serial speed: as given, else 115200 for a SeaTrac (its default) and 4800 for NMEA 0183."""
        return int(self.params.get("baud", "115200" if self.scheme == "seatrac" else "4800"))

    @property
    def beacons(self) -> tuple[int, ...]:
        raw = self.params.get("beacons", "")
        return tuple(int(b) for b in raw.split(",")) if raw else ()


def parse_spec(text: str, *, allowed: Collection[str] = SCHEMES, what: str = "source") -> StreamSpec:
    """Parse and validate a spec; every error is a one-line :class:`ConfigError` naming the spec."""

    def bad(reason: str) -> ConfigError:
        return ConfigError(f"{what} {text!r}: {reason}")

    if not isinstance(text, str) or "://" not in text:
        raise bad(f"expected SCHEME://..., with SCHEME one of {', '.join(allowed)}")
    try:
        parts = urlsplit(text)
        port = parts.port
    except ValueError as exc:
        raise bad(str(exc)) from None
    scheme = parts.scheme.lower()
    if scheme not in allowed:
        raise bad(f"scheme {scheme!r} is not one of {', '.join(allowed)}")
    if parts.fragment:
        raise bad(f"unexpected '#{parts.fragment}'")
    params: dict[str, str] = {}
    for key, value in parse_qsl(parts.query, keep_blank_values=True):
        if key not in _PARAMS[scheme]:
            allowed_keys = ", ".join(sorted(_PARAMS[scheme])) or "none"
            raise bad(f"unknown option {key!r} (allowed: {allowed_keys})")
        if key in params:
            raise bad(f"option {key!r} given twice")
        params[key] = value
    host, path = parts.hostname or "", parts.path
    if scheme in ("udp", "tcp", "gpsd"):
        if not host:
            raise bad("no host (e.g. 127.0.0.1)")
        if path not in ("", "/"):
            raise bad(f"unexpected path {path!r} after the address")
        port = _DEFAULT_PORT.get(scheme) if port is None else port
        if port is None:
            raise bad("no port (e.g. :10110)")
        if not (0 if scheme == "udp" else 1) <= port <= 65535:
            raise bad(f"port {port} is outside 1..65535")
        path = ""
    else:
        if host or port is not None:
            raise bad(f"a device path needs three slashes ({scheme}:///dev/ttyUSB0), got host {host!r}")
        if not path or path == "/":
            raise bad("no device path (e.g. /dev/ttyUSB0)")
        port = 0
    if "baud" in params:
        try:
            baud = int(params["baud"])
        except ValueError:
            raise bad(f"baud {params['baud']!r} is not an integer") from None
        if not 50 <= baud <= 4_000_000:
            raise bad(f"baud {baud} is outside 50..4000000")
    if "column" in params and params["column"] not in RANGE_COLUMNS:
        raise bad(f"column {params['column']!r} is not one of {', '.join(RANGE_COLUMNS)}")
    if scheme == "seatrac":
        raw = params.get("beacons", "")
        if not raw:
            raise bad("no beacons (e.g. ?beacons=1,2)")
        try:
            ids = [int(b) for b in raw.split(",")]
        except ValueError:
            raise bad(f"beacons {raw!r} are not integers separated by commas") from None
        if any(not 1 <= b <= 15 for b in ids) or len(set(ids)) != len(ids):
            raise bad(f"beacons {raw!r} must be distinct ids from 1 to 15")
        if "timeout" in params:
            try:
                timeout = float(params["timeout"])
            except ValueError:
                raise bad(f"timeout {params['timeout']!r} is not a number of seconds") from None
            if not 0.0 < timeout <= 600.0:
                raise bad(f"timeout {timeout} s is outside (0, 600]")
        if params.get("msg", "REQU").upper() not in ("REQ", "REQU", "REQX"):
            raise bad(f"msg {params['msg']!r} is not REQ, REQU or REQX")
    return StreamSpec(
        text=text, scheme=scheme, host=host, port=port, path=path, params=MappingProxyType(params)
    )


def open_line_source(spec: StreamSpec) -> LineSource:
    """The transport a ``udp``, ``tcp`` or ``serial`` spec names."""
    if spec.scheme == "udp":
        return UdpLineSource(spec.host, spec.port, spec.text)
    if spec.scheme == "tcp":
        return TcpLineSource(spec.host, spec.port, spec.text)
    if spec.scheme == "serial":
        return SerialLineSource(spec.path, spec.baud, spec.text)
    raise ConfigError(f"{spec.text!r}: {spec.scheme} is not a line transport (udp, tcp, serial)")


# ------------------------------------------------------------------------------------------ record streams


class NmeaStream(LineStream):
    """GPS fixes and headings from NMEA 0183 lines, with :func:`~oceanloc.io.nmea.read_nmea`'s QC."""

    def __init__(self, source: LineSource, qc: QcReport | None = None) -> None:
        super().__init__(source, qc)
        self.parser = NmeaLineParser()

    def _parse(self, text: str) -> GpsFix | Heading | None:
        return self.parser.feed(self.line, text, self.qc, self.name)


class RangeTextStream(LineStream):
    """Ranges from USBL CSV lines, with :func:`~oceanloc.io.usbl.read_usbl`'s QC (module docstring)."""

    def __init__(
        self,
        source: LineSource,
        *,
        sound_speed_mps: float = 1500.0,
        beacons: Collection[int] | None = None,
        column: str = "range_m",
        qc: QcReport | None = None,
    ) -> None:
        super().__init__(source, qc)
        self.parser = UsblLineParser(sound_speed_mps=sound_speed_mps, beacons=beacons, column=column)

    def _parse(self, text: str) -> RangeRecord | None:
        return self.parser.feed(self.line, text, self.qc, self.name)


class SeatracRangeStream:
    """Ranges from a SeaTrac USBL (:class:`~oceanloc.io.seatrac.SeatracPinger`), one beacon per read."""

    def __init__(self, pinger: SeatracPinger, name: str) -> None:
        self.pinger = pinger
        self.name = name
        self.qc = pinger.qc
        self._next = 0

    def read(self, timeout_s: float) -> RangeRecord:
        """Ping the next beacon; its record (failed pings too) within ``timeout_s`` or the spec's ``timeout``.

        A ping always ends with a record: ``no response`` when the beacon stayed silent.
        """
        beacon = self.pinger.beacons[self._next % len(self.pinger.beacons)]
        self._next += 1
        return self.pinger.ping(beacon, timeout_s)

    def records(self, idle_timeout_s: float) -> Iterator[RangeRecord]:
        """Every ping's record; :class:`StreamTimeoutError` when no ping succeeded for ``idle_timeout_s``."""
        last_ok = time.monotonic()
        while True:
            rec = self.read(idle_timeout_s)
            if rec.ok:
                last_ok = time.monotonic()
            elif time.monotonic() - last_ok > idle_timeout_s:
                raise StreamTimeoutError(f"{self.name}: no range for {idle_timeout_s:g} s ({rec.message})")
            yield rec

    def close(self) -> None:
        self.pinger.close()

    def __enter__(self) -> SeatracRangeStream:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


PositionStream = NmeaStream | GpsdClient
RangeStream = RangeTextStream | SeatracRangeStream


def open_position_stream(text: str, *, qc: QcReport | None = None) -> PositionStream:
    """Open the position source a spec names (udp, tcp, serial: NMEA; gpsd: its JSON protocol)."""
    spec = parse_spec(text, allowed=POSITION_SCHEMES, what="position source")
    if spec.scheme == "gpsd":
        return GpsdClient(spec.host, spec.port, qc=qc, name=spec.text)
    return NmeaStream(open_line_source(spec), qc=qc)


def open_range_stream(
    text: str,
    *,
    sound_speed_mps: float = 1500.0,
    beacons: Collection[int] | None = None,
    qc: QcReport | None = None,
) -> RangeStream:
    """Open the range source a spec names (udp, tcp, serial: range lines; seatrac: a USBL pinger)."""
    spec = parse_spec(text, allowed=RANGE_SCHEMES, what="range source")
    if spec.scheme == "seatrac":
        msg = {"REQ": MsgType.MSG_REQ, "REQU": MsgType.MSG_REQU, "REQX": MsgType.MSG_REQX}
        pinger = SeatracPinger(
            spec.path,
            beacons=spec.beacons,
            sound_speed_mps=sound_speed_mps,
            msg_type=msg[spec.params.get("msg", "REQU").upper()],
            timeout_s=float(spec.params.get("timeout", "3")),
            baud=spec.baud,
            qc=qc,
        )
        return SeatracRangeStream(pinger, spec.text)
    return RangeTextStream(
        open_line_source(spec),
        sound_speed_mps=sound_speed_mps,
        beacons=beacons,
        column=spec.params.get("column", "range_m"),
        qc=qc,
    )
