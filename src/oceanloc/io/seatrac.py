"""Blueprint Subsea SeaTrac (X010, X150) serial protocol: framing, CRC16, the PING messages and a pinger.

What the SeaTrac Developer Guide (Serial Command Interface Reference, sections 5 and 8.1) specifies and
this module implements:

- **Frames.** A command from the host starts with ``#``, a response or status message from the beacon
  with ``$``. Then the bytes (CID, payload) as upper-case hexadecimal pairs, then the 16-bit checksum
  of those bytes as 4 hex characters, least-significant byte first, then CR LF. Multi-byte fields are
  little-endian.
- **Checksum.** CRC-16-IBM (polynomial x^16 + x^15 + x^2 + 1, normal 0x8005, processed reflected with
  0xA001), initial value 0, no final XOR (the catalogue's CRC-16/ARC), over the CID and payload bytes.
  The guide's own examples check it: ``#0281C1`` (CID_SYS_INFO, checksum 0xC181) and its
  41-byte response ending ``73BA`` (checksum 0xBA73).
- **PING.** ``CID_PING_SEND`` (0x40; command: destination beacon id, message type) is acknowledged by a
  response with the same CID (status, beacon id). The remote reply arrives later as ``CID_PING_RESP``
  (0x42), an ``ACOFIX_T``, or the attempt fails with ``CID_PING_ERROR`` (0x43; status, beacon id), e.g.
  ``CST_XCVR_RESP_TIMEOUT`` when nothing was heard within the beacon's range timeout.
- **ACOFIX_T.** dest id, src id, flags, message type (UINT8 each); yaw, pitch, roll (INT16,
  deci-degrees); local depth (UINT16, dm); VOS (UINT16, dm/s); RSSI (INT16, centibels). Then, present
  by flag bits: bit 0 RANGE_VALID: range count (UINT32, 16 kHz ticks), range time (INT32, 100 ns),
  range distance (UINT16, dm); bit 1 USBL_VALID: channel count (UINT8), RSSI per channel (INT16[n],
  centibels), azimuth, elevation (INT16, deci-degrees), fit error (INT16, hundredths); bit 2
  POSITION_VALID: easting, northing, depth (INT16, dm). Bits 3 (POSITION_ENHANCED) and 4
  (POSITION_FLT_ERROR) qualify the position.

**Travel time to range.** A range is ``sound_speed_mps * RANGE_TIME``. RANGE_TIME is the one-way travel
time: the guide derives it from RANGE_COUNT with the beacon's internal timing offsets and the remote
turn-around compensated, and RANGE_DIST is RANGE_TIME times the beacon's own VOS. RANGE_TIME is used
because it is independent of the VOS the beacon was configured with (the survey's sound speed, from the
journal, is applied instead) and has a 100 ns resolution (0.15 mm), where RANGE_DIST has 0.1 m and the
beacon's VOS, and RANGE_COUNT is the raw round trip in 62.5 us ticks with the turn-around still in it.

Everything here is a pure function or a small frozen dataclass except :class:`SeatracPinger`, the
serial client. Bad frames raise :class:`SeatracDecodeError` (a :class:`~oceanloc.errors.DataError`)
saying what is wrong; the pinger records them in its QC report and carries on.
"""

from __future__ import annotations

import contextlib
import math
import struct
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

from oceanloc.errors import ConfigError, DataError
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import RangeRecord


class SeatracDecodeError(DataError):
    """A SeaTrac frame or message that cannot be decoded (bad hex, bad CRC, short payload)."""


class Cid(IntEnum):
    """Command identification codes used here (Developer Guide, CID_E)."""

    SYS_ALIVE = 0x01
    SYS_INFO = 0x02
    STATUS = 0x10
    PING_SEND = 0x40
    PING_REQ = 0x41
    PING_RESP = 0x42
    PING_ERROR = 0x43


class MsgType(IntEnum):
    """Acoustic message types (AMSGTYPE_E)."""

    MSG_OWAY = 0x00
    MSG_OWAYU = 0x01
    MSG_REQ = 0x02
    MSG_RESP = 0x03
    MSG_REQU = 0x04
    MSG_RESPU = 0x05
    MSG_REQX = 0x06
    MSG_RESPX = 0x07
    MSG_UNKNOWN = 0xFF


class Cst(IntEnum):
    """Status codes (CST_E) a PING exchange can carry."""

    OK = 0x00
    FAIL = 0x01
    EEPROM_ERROR = 0x03
    CMD_PARAM_MISSING = 0x04
    CMD_PARAM_INVALID = 0x05
    XCVR_BUSY = 0x30
    XCVR_ID_REJECTED = 0x31
    XCVR_CSUM_ERROR = 0x32
    XCVR_LENGTH_ERROR = 0x33
    XCVR_RESP_TIMEOUT = 0x34
    XCVR_RESP_ERROR = 0x35
    XCVR_RESP_WRONG = 0x36
    XCVR_PLOAD_ERROR = 0x37


RANGE_VALID = 0x01
USBL_VALID = 0x02
POSITION_VALID = 0x04
POSITION_ENHANCED = 0x08
POSITION_FLT_ERROR = 0x10

BEACON_IDS = range(1, 16)
"""Valid remote beacon ids (0 is BEACON_ALL, which a PING cannot address)."""

RANGE_TIME_PER_S = 10_000_000
"""RANGE_TIME units per second (100 ns resolution)."""


def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
        table.append(crc)
    return tuple(table)


_CRC_TABLE = _crc_table()


def crc16(data: bytes) -> int:
    """CRC-16-IBM of ``data`` as the Developer Guide computes it (reflected 0xA001, initial 0, no XOR)."""
    crc = 0
    for byte in data:
        crc = (crc >> 8) ^ _CRC_TABLE[(crc ^ byte) & 0xFF]
    return crc


def status_name(status: int) -> str:
    """The guide's name of a status code (``XCVR_RESP_TIMEOUT``), or its hex value if unknown."""
    try:
        return Cst(status).name
    except ValueError:
        return f"0x{status:02X}"


# ----------------------------------------------------------------------------------------------- frames


@dataclass(frozen=True, slots=True, kw_only=True)
class Frame:
    """One decoded frame: its sync character, command id and payload bytes (checksum verified)."""

    sync: str
    cid: int
    payload: bytes


def encode_frame(cid: int, payload: bytes = b"", *, sync: str = "#") -> bytes:
    """``sync`` + hex(CID, payload) + hex(CRC16, little-endian) + CR LF, as bytes."""
    if sync not in ("#", "$"):
        raise ConfigError(f"SeaTrac sync character must be '#' or '$', got {sync!r}")
    if not 0 <= cid <= 0xFF:
        raise ConfigError(f"SeaTrac CID must be a byte, got {cid}")
    body = bytes([cid]) + bytes(payload)
    crc = crc16(body)
    return (sync + (body + bytes([crc & 0xFF, crc >> 8])).hex().upper() + "\r\n").encode("ascii")


def decode_frame(line: bytes | str, *, sync: str | None = "$") -> Frame:
    """Decode one frame (with or without its CR LF); ``sync=None`` accepts ``#`` and ``$``.

    Raises
    ------
    SeatracDecodeError
        Naming what is wrong: a missing sync character, a character that is not hex, an odd count of
        hex characters, fewer bytes than a CID and a checksum, or a checksum mismatch.
    """
    if isinstance(line, bytes):
        try:
            text = line.decode("ascii")
        except UnicodeDecodeError as exc:
            raise SeatracDecodeError(f"non-ASCII byte at position {exc.start}") from None
    else:
        text = line
    text = text.strip("\r\n \t")
    if not text:
        raise SeatracDecodeError("empty frame")
    allowed = ("#", "$") if sync is None else (sync,)
    if text[0] not in allowed:
        want = " or ".join(repr(s) for s in allowed)
        raise SeatracDecodeError(f"frame does not start with {want}: {text[:16]!r}")
    hexpart = text[1:]
    for i, ch in enumerate(hexpart):
        if ch not in "0123456789ABCDEFabcdef":
            raise SeatracDecodeError(f"non-hex character {ch!r} at column {i + 2}")
    if len(hexpart) % 2:
        raise SeatracDecodeError(f"odd number of hex characters ({len(hexpart)})")
    raw = bytes.fromhex(hexpart)
    if len(raw) < 3:
        raise SeatracDecodeError(f"frame too short: {len(raw)} bytes, need a CID and a 2-byte checksum")
    body, got = raw[:-2], raw[-2] | (raw[-1] << 8)
    want = crc16(body)
    if got != want:
        raise SeatracDecodeError(f"bad checksum: frame says 0x{got:04X}, content gives 0x{want:04X}")
    return Frame(sync=text[0], cid=body[0], payload=body[1:])


class _Reader:
    """Little-endian field reader over a payload; a short payload is a :class:`SeatracDecodeError`."""

    __slots__ = ("data", "pos", "what")

    def __init__(self, data: bytes, what: str) -> None:
        self.data, self.pos, self.what = data, 0, what

    def take(self, fmt: str, field: str) -> Any:
        size = struct.calcsize("<" + fmt)
        if self.pos + size > len(self.data):
            raise SeatracDecodeError(
                f"{self.what}: payload too short at {field} "
                f"(needs {self.pos + size} bytes, has {len(self.data)})"
            )
        values = struct.unpack_from("<" + fmt, self.data, self.pos)
        self.pos += size
        return values if len(values) > 1 else values[0]

    def done(self) -> None:
        if self.pos != len(self.data):
            raise SeatracDecodeError(f"{self.what}: {len(self.data) - self.pos} unexpected trailing bytes")


def _int(value: float, scale: float, lo: int, hi: int, field: str) -> int:
    if not math.isfinite(value):
        raise ConfigError(f"ACOFIX {field} must be finite, got {value}")
    raw = round(value * scale)
    if not lo <= raw <= hi:
        raise ConfigError(f"ACOFIX {field} = {value} does not fit the field ({lo / scale} to {hi / scale})")
    return raw


# ---------------------------------------------------------------------------------------- PING messages


@dataclass(frozen=True, slots=True, kw_only=True)
class PingSend:
    """The CID_PING_SEND command: ping ``beacon_id`` with an acoustic request of ``msg_type``."""

    beacon_id: int
    msg_type: int = MsgType.MSG_REQU


@dataclass(frozen=True, slots=True, kw_only=True)
class PingSendStatus:
    """The beacon's response to CID_PING_SEND: ``status`` (CST_OK: the ping is being sent)."""

    status: int
    beacon_id: int

    @property
    def ok(self) -> bool:
        return self.status == Cst.OK


@dataclass(frozen=True, slots=True, kw_only=True)
class PingError:
    """CID_PING_ERROR: the ping to ``beacon_id`` failed with ``status`` (e.g. XCVR_RESP_TIMEOUT)."""

    status: int
    beacon_id: int


@dataclass(frozen=True, slots=True, kw_only=True)
class AcoRange:
    """ACOFIX_T range fields: round-trip count (16 kHz ticks), one-way time (s), distance (m)."""

    count: int
    time_s: float
    dist_m: float


@dataclass(frozen=True, slots=True, kw_only=True)
class AcoUsbl:
    """ACOFIX_T USBL fields: per-channel RSSI (dB), signal azimuth and elevation (deg), fit error."""

    rssi_db: tuple[float, ...]
    azimuth_deg: float
    elevation_deg: float
    fit_error: float

    @property
    def channels(self) -> int:
        return len(self.rssi_db)


@dataclass(frozen=True, slots=True, kw_only=True)
class AcoPosition:
    """ACOFIX_T position fields: the remote beacon relative to the local one, metres (depth down)."""

    easting_m: float
    northing_m: float
    depth_m: float


@dataclass(frozen=True, slots=True, kw_only=True)
class AcoFix:
    """ACOFIX_T, the acoustic fix of CID_PING_RESP (units: degrees, metres, m/s, dB).

    ``range``, ``usbl`` and ``position`` are present exactly when the RANGE_VALID, USBL_VALID and
    POSITION_VALID flag bits are set; ``flags`` keeps the other bits (POSITION_ENHANCED,
    POSITION_FLT_ERROR) as received.
    """

    dest_id: int
    src_id: int
    flags: int
    msg_type: int
    yaw_deg: float
    pitch_deg: float
    roll_deg: float
    depth_local_m: float
    vos_mps: float
    rssi_db: float
    range: AcoRange | None = None
    usbl: AcoUsbl | None = None
    position: AcoPosition | None = None

    def __post_init__(self) -> None:
        for bit, part, name in (
            (RANGE_VALID, self.range, "range"),
            (USBL_VALID, self.usbl, "USBL"),
            (POSITION_VALID, self.position, "position"),
        ):
            if bool(self.flags & bit) != (part is not None):
                raise ConfigError(f"ACOFIX flags 0x{self.flags:02X} disagree with the {name} fields")


def encode_ping_send(beacon_id: int, msg_type: int = MsgType.MSG_REQU) -> bytes:
    """The CID_PING_SEND command frame for ``beacon_id`` (1 to 15); MSG_REQU asks for a USBL fix."""
    if beacon_id not in BEACON_IDS:
        raise ConfigError(f"SeaTrac beacon id must be 1 to 15, got {beacon_id}")
    if msg_type not in (MsgType.MSG_REQ, MsgType.MSG_REQU, MsgType.MSG_REQX):
        raise ConfigError(f"a PING is sent as MSG_REQ, MSG_REQU or MSG_REQX, not message type {msg_type}")
    return encode_frame(Cid.PING_SEND, bytes([beacon_id, msg_type]), sync="#")


def decode_ping_send(payload: bytes) -> PingSend:
    """The CID_PING_SEND command's payload (what a beacon receives)."""
    r = _Reader(payload, "CID_PING_SEND command")
    beacon, msg_type = r.take("BB", "DEST_ID, MSG_TYPE")
    r.done()
    return PingSend(beacon_id=beacon, msg_type=msg_type)


def encode_ping_send_status(status: int, beacon_id: int) -> bytes:
    """The beacon's response frame to CID_PING_SEND."""
    return encode_frame(Cid.PING_SEND, bytes([status & 0xFF, beacon_id & 0xFF]), sync="$")


def decode_ping_send_status(payload: bytes) -> PingSendStatus:
    """The CID_PING_SEND response payload: status, beacon id."""
    r = _Reader(payload, "CID_PING_SEND response")
    status, beacon = r.take("BB", "STATUS, BEACON_ID")
    r.done()
    return PingSendStatus(status=status, beacon_id=beacon)


def encode_ping_error(status: int, beacon_id: int) -> bytes:
    """A CID_PING_ERROR status frame."""
    return encode_frame(Cid.PING_ERROR, bytes([status & 0xFF, beacon_id & 0xFF]), sync="$")


def decode_ping_error(payload: bytes) -> PingError:
    """The CID_PING_ERROR payload: status, beacon id."""
    r = _Reader(payload, "CID_PING_ERROR")
    status, beacon = r.take("BB", "STATUS, BEACON_ID")
    r.done()
    return PingError(status=status, beacon_id=beacon)


def encode_acofix(fix: AcoFix) -> bytes:
    """ACOFIX_T bytes of ``fix`` (values rounded to the fields' resolutions; out of range: ConfigError)."""
    out = bytearray(
        struct.pack(
            "<BBBBhhhHHh",
            fix.dest_id,
            fix.src_id,
            fix.flags,
            fix.msg_type,
            _int(fix.yaw_deg, 10, -32768, 32767, "yaw"),
            _int(fix.pitch_deg, 10, -32768, 32767, "pitch"),
            _int(fix.roll_deg, 10, -32768, 32767, "roll"),
            _int(fix.depth_local_m, 10, 0, 65535, "local depth"),
            _int(fix.vos_mps, 10, 0, 65535, "VOS"),
            _int(fix.rssi_db, 10, -32768, 32767, "RSSI"),
        )
    )
    if fix.range is not None:
        rg = fix.range
        out += struct.pack(
            "<IiH",
            rg.count,
            _int(rg.time_s, RANGE_TIME_PER_S, -(2**31), 2**31 - 1, "range time"),
            _int(rg.dist_m, 10, 0, 65535, "range distance"),
        )
    if fix.usbl is not None:
        u = fix.usbl
        out += struct.pack("<B", u.channels)
        out += struct.pack(f"<{u.channels}h", *(_int(v, 10, -32768, 32767, "USBL RSSI") for v in u.rssi_db))
        out += struct.pack(
            "<hhh",
            _int(u.azimuth_deg, 10, -32768, 32767, "azimuth"),
            _int(u.elevation_deg, 10, -32768, 32767, "elevation"),
            _int(u.fit_error, 100, -32768, 32767, "fit error"),
        )
    if fix.position is not None:
        p = fix.position
        out += struct.pack(
            "<hhh",
            _int(p.easting_m, 10, -32768, 32767, "easting"),
            _int(p.northing_m, 10, -32768, 32767, "northing"),
            _int(p.depth_m, 10, -32768, 32767, "position depth"),
        )
    return bytes(out)


def decode_acofix(payload: bytes, what: str = "ACOFIX") -> AcoFix:
    """Decode ACOFIX_T; the optional parts follow the flag bits (a short payload names the field)."""
    r = _Reader(payload, what)
    dest, src, flags, msg_type = r.take("BBBB", "DEST_ID..MSG_TYPE")
    yaw, pitch, roll = r.take("hhh", "ATTITUDE")
    depth, vos, rssi = r.take("HHh", "DEPTH_LOCAL, VOS, RSSI")
    rng = usbl = pos = None
    if flags & RANGE_VALID:
        count, t, dist = r.take("IiH", "RANGE fields")
        rng = AcoRange(count=count, time_s=t / RANGE_TIME_PER_S, dist_m=dist / 10)
    if flags & USBL_VALID:
        n = r.take("B", "USBL_CHANNELS")
        rssis = r.take(f"{n}h", "USBL_RSSI") if n else ()
        rssis = (rssis,) if isinstance(rssis, int) else rssis
        az, el, fit = r.take("hhh", "USBL_AZIMUTH..USBL_FIT_ERROR")
        usbl = AcoUsbl(
            rssi_db=tuple(v / 10 for v in rssis),
            azimuth_deg=az / 10,
            elevation_deg=el / 10,
            fit_error=fit / 100,
        )
    if flags & POSITION_VALID:
        e, n_, d = r.take("hhh", "POSITION fields")
        pos = AcoPosition(easting_m=e / 10, northing_m=n_ / 10, depth_m=d / 10)
    r.done()
    return AcoFix(
        dest_id=dest,
        src_id=src,
        flags=flags,
        msg_type=msg_type,
        yaw_deg=yaw / 10,
        pitch_deg=pitch / 10,
        roll_deg=roll / 10,
        depth_local_m=depth / 10,
        vos_mps=vos / 10,
        rssi_db=rssi / 10,
        range=rng,
        usbl=usbl,
        position=pos,
    )


def encode_ping_resp(fix: AcoFix) -> bytes:
    """A CID_PING_RESP status frame carrying ``fix``."""
    return encode_frame(Cid.PING_RESP, encode_acofix(fix), sync="$")


@dataclass(frozen=True, slots=True, kw_only=True)
class OtherMessage:
    """A well-formed frame whose CID this module does not interpret."""

    cid: int
    payload: bytes


Message = PingSendStatus | AcoFix | PingError | OtherMessage


def decode_message(line: bytes | str) -> Message:
    """Decode a beacon-to-host line (``$...``) into its PING message (or :class:`OtherMessage`)."""
    frame = decode_frame(line, sync="$")
    if frame.cid == Cid.PING_SEND:
        return decode_ping_send_status(frame.payload)
    if frame.cid == Cid.PING_RESP:
        return decode_acofix(frame.payload, "CID_PING_RESP")
    if frame.cid == Cid.PING_ERROR:
        return decode_ping_error(frame.payload)
    return OtherMessage(cid=frame.cid, payload=frame.payload)


def range_from_fix(fix: AcoFix, sound_speed_mps: float) -> float | None:
    """Range in metres, ``sound_speed_mps * RANGE_TIME`` (one-way time; see the module docstring)."""
    if fix.range is None:
        return None
    return sound_speed_mps * fix.range.time_s


# ---------------------------------------------------------------------------------------------- pinger


class SeatracPinger:
    """Pings SeaTrac beacons in turn over a serial port and yields one :class:`RangeRecord` per ping.

    Parameters
    ----------
    port : str
        A pyserial URL or device path (``/dev/ttyUSB0``, a pseudo-terminal, ``socket://host:port``).
    beacons : sequence of int
        Beacon ids (1 to 15) pinged in this order, round and round.
    sound_speed_mps : float
        Sound speed applied to RANGE_TIME (the journal's), m/s.
    msg_type : MsgType
        MSG_REQU (range and USBL angles; the default), MSG_REQ (range only) or MSG_REQX.
    timeout_s : float
        Longest wait for one ping's outcome (send status, then response or error), host clock,
        seconds; past it the ping is recorded with status ``no response``.
    baud : int
        Serial speed (the guide's default 115200, 8 data bits, no parity, 2 stop bits).
    clock : callable
        UTC Unix time source for the records (``time.time``).

    Each record's ``t_unix_s`` is the midpoint between the command's transmission and the reply's
    arrival on the host clock (the epoch a two-way range belongs to). Status values: ``ok``;
    ``timeout`` (CID_PING_ERROR with XCVR_RESP_TIMEOUT: no acoustic reply, a dropout); ``no response``
    (the serial link stayed silent past ``timeout_s``); otherwise the guide's status name in lower case
    (``xcvr_busy``, ``xcvr_resp_wrong``, ...). Undecodable lines are recorded in ``qc`` (source = the
    port, line = the count of lines read) and skipped.
    """

    def __init__(
        self,
        port: str,
        *,
        beacons: Sequence[int],
        sound_speed_mps: float = 1500.0,
        msg_type: int = MsgType.MSG_REQU,
        timeout_s: float = 3.0,
        baud: int = 115200,
        clock: Callable[[], float] = time.time,
        qc: QcReport | None = None,
    ) -> None:
        if not beacons:
            raise ConfigError("SeaTrac: give at least one beacon id to ping")
        for b in beacons:
            encode_ping_send(int(b), msg_type)  # validates the id and the message type
        if not 1300.0 <= sound_speed_mps <= 1700.0:
            raise ConfigError(f"sound speed {sound_speed_mps} m/s is outside [1300, 1700]")
        if not 0.0 < timeout_s <= 600.0:
            raise ConfigError(f"SeaTrac ping timeout must be in (0, 600] s, got {timeout_s}")
        self.port = port
        self.beacons = tuple(int(b) for b in beacons)
        self.sound_speed_mps = float(sound_speed_mps)
        self.msg_type = int(msg_type)
        self.timeout_s = float(timeout_s)
        self.clock = clock
        self.qc = QcReport() if qc is None else qc
        self._lines = 0
        self._buffer = bytearray()
        try:
            import serial
        except ImportError:  # pragma: no cover - pyserial is a dependency
            raise DataError("SeaTrac: pyserial is not installed (pip install pyserial)") from None
        self._serial_error = serial.SerialException
        try:
            self._serial = serial.serial_for_url(
                port, baudrate=baud, bytesize=8, parity="N", stopbits=2, timeout=0.05, write_timeout=1.0
            )
        except (serial.SerialException, OSError, ValueError) as exc:
            raise DataError(f"SeaTrac {port}: cannot open the serial port ({exc})") from None

    def __enter__(self) -> SeatracPinger:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the serial port."""
        with contextlib.suppress(self._serial_error, OSError):
            self._serial.close()

    def _readline(self, deadline: float) -> bytes | None:
        """The next complete line before ``deadline`` (monotonic seconds), or None."""
        while True:
            cut = self._buffer.find(b"\n")
            if cut >= 0:
                line = bytes(self._buffer[: cut + 1])
                del self._buffer[: cut + 1]
                self._lines += 1
                return line
            if time.monotonic() >= deadline:
                return None
            try:
                chunk = self._serial.read(max(1, self._serial.in_waiting))
            except (self._serial_error, OSError) as exc:
                raise DataError(f"SeaTrac {self.port}: serial read failed ({exc})") from None
            self._buffer += chunk
            if len(self._buffer) > 65536:  # no line end in 64 KiB: line noise, not a SeaTrac
                self.qc.add(self.port, self._lines + 1, "truncated sentence", "64 KiB without a line end")
                self._buffer.clear()

    def _next_message(self, deadline: float) -> Message | None:
        while (line := self._readline(deadline)) is not None:
            if not line.strip():
                continue
            self.qc.lines_read += 1
            try:
                return decode_message(line)
            except SeatracDecodeError as exc:
                self.qc.add(self.port, self._lines, "bad frame", str(exc))
        return None

    def ping(self, beacon_id: int, timeout_s: float | None = None) -> RangeRecord:
        """Ping one beacon and wait for its range, error or silence.

        The wait is at most ``timeout_s`` (default: the pinger's ``timeout_s``, and never longer).
        """
        frame = encode_ping_send(beacon_id, self.msg_type)
        self._buffer.clear()
        try:
            self._serial.reset_input_buffer()
            t_sent = self.clock()
            self._serial.write(frame)
            self._serial.flush()
        except (self._serial_error, OSError) as exc:
            raise DataError(f"SeaTrac {self.port}: serial write failed ({exc})") from None
        wait_s = self.timeout_s if timeout_s is None else min(max(0.0, timeout_s), self.timeout_s)
        deadline = time.monotonic() + wait_s
        acknowledged = False

        def failed(status: str, message: str) -> RangeRecord:
            t = self.clock()
            return RangeRecord(
                t_unix_s=0.5 * (t_sent + t),
                beacon=beacon_id,
                range_m=None,
                status=status,
                message=f"{self.port}: beacon {beacon_id}: {message}",
                source=self.port,
                line=self._lines,
            )

        while (msg := self._next_message(deadline)) is not None:
            if isinstance(msg, PingSendStatus):
                if msg.status != Cst.OK:
                    name = status_name(msg.status)
                    return failed(name.lower(), f"ping not sent ({name})")
                acknowledged = True
            elif isinstance(msg, PingError) and msg.beacon_id == beacon_id:
                name = status_name(msg.status)
                if msg.status == Cst.XCVR_RESP_TIMEOUT:
                    return failed("timeout", f"no acoustic reply within the beacon's range timeout ({name})")
                return failed(name.lower(), f"ping failed ({name})")
            elif isinstance(msg, AcoFix) and msg.src_id == beacon_id and acknowledged:
                # (a response before this ping's send status is a late answer to an earlier ping, of
                # this process or of one killed mid-ping: its range belongs to another time)
                t = self.clock()
                rng = range_from_fix(msg, self.sound_speed_mps)
                if rng is None:
                    return failed("no range", "CID_PING_RESP without RANGE_VALID")
                az = el = None
                if msg.usbl is not None:
                    az, el = msg.usbl.azimuth_deg, msg.usbl.elevation_deg
                self.qc.records_kept += 1
                return RangeRecord(
                    t_unix_s=0.5 * (t_sent + t),
                    beacon=beacon_id,
                    range_m=rng,
                    travel_time_s=msg.range.time_s if msg.range is not None else None,
                    azimuth_deg=az,
                    elevation_deg=el,
                    status="ok",
                    source=self.port,
                    line=self._lines,
                )
        what = "after the send status" if acknowledged else "not even the send status"
        return failed("no response", f"nothing within {wait_s:g} s ({what})")

    def records(self, n_cycles: int | None = None) -> Iterator[RangeRecord]:
        """Ping every beacon in turn, ``n_cycles`` times round (forever if None)."""
        cycle = 0
        while n_cycles is None or cycle < n_cycles:
            for b in self.beacons:
                yield self.ping(b)
            cycle += 1
