"""Byte transports that yield lines: UDP datagrams, a TCP client, a serial port (pyserial URL).

Each has ``read_line(timeout_s) -> bytes | None`` (None when no whole line arrived in time) and
``close()``, and raises only :class:`~oceanloc.errors.DataError` (cannot open, receive failed, the other
end closed). A line longer than :data:`MAX_LINE_BYTES` is cut there and returned as is, for the caller
to record (NMEA sentences are at most 82 characters, gpsd's JSON reports a few kilobytes).
"""

from __future__ import annotations

import contextlib
import socket
import time
from collections import deque
from collections.abc import Iterator
from typing import Protocol

from oceanloc.errors import DataError
from oceanloc.io.qc import QcReport, decode_line

MAX_LINE_BYTES = 65536
"""A line longer than this is cut (and then recorded as truncated by the stream reading it)."""


class StreamTimeoutError(DataError):
    """Nothing valid arrived from a stream within the idle timeout."""


class LineSource(Protocol):
    """Raw lines from a transport; ``read_line`` returns None when no whole line came within the timeout."""

    name: str

    def read_line(self, timeout_s: float) -> bytes | None: ...

    def close(self) -> None: ...


class _Buffered:
    """Splits received bytes into lines; over-long lines are cut and flagged."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._buffer = bytearray()
        self._lines: deque[bytes] = deque()

    def _feed(self, data: bytes, *, end_of_message: bool = False) -> None:
        self._buffer += data
        *whole, rest = bytes(self._buffer).split(b"\n")
        self._lines += whole
        self._buffer = bytearray(rest)
        if end_of_message and self._buffer:  # a datagram ends its last line
            self._lines.append(bytes(self._buffer))
            self._buffer.clear()
        if len(self._buffer) > MAX_LINE_BYTES:
            self._lines.append(bytes(self._buffer[:MAX_LINE_BYTES]))
            self._buffer.clear()

    def _pop(self) -> bytes | None:
        return self._lines.popleft() if self._lines else None

    def _read_socket_line(self, sock: socket.socket, timeout_s: float, *, datagrams: bool) -> bytes | None:
        """The next whole line from ``sock`` within ``timeout_s`` (a datagram ends its last line; a
        stream's end is a :class:`DataError`)."""
        deadline = time.monotonic() + timeout_s
        what = "UDP receive" if datagrams else "receive"
        while (line := self._pop()) is None:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            sock.settimeout(left)
            try:
                data = sock.recv(65535 if datagrams else 65536)
            except TimeoutError:
                return None
            except OSError as exc:
                raise DataError(f"{self.name}: {what} failed ({exc})") from None
            if not data and not datagrams:
                raise DataError(f"{self.name}: connection closed by the other end")
            self._feed(data, end_of_message=datagrams)
        return line


class UdpLineSource(_Buffered):
    """Lines from UDP datagrams received on ``host:port`` (port 0: any free port, see ``address``)."""

    def __init__(self, host: str, port: int, name: str = "") -> None:
        super().__init__(name or f"udp://{host}:{port}")
        try:
            self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            self._sock.bind((host, port))
        except OSError as exc:
            raise DataError(f"{self.name}: cannot listen for UDP ({exc})") from None
        self.address: tuple[str, int] = self._sock.getsockname()[:2]

    def read_line(self, timeout_s: float) -> bytes | None:
        return self._read_socket_line(self._sock, timeout_s, datagrams=True)

    def close(self) -> None:
        self._sock.close()


class TcpLineSource(_Buffered):
    """Lines from a TCP server at ``host:port`` (the client connects; EOF is a :class:`DataError`)."""

    def __init__(self, host: str, port: int, name: str = "", connect_timeout_s: float = 5.0) -> None:
        super().__init__(name or f"tcp://{host}:{port}")
        try:
            self._sock = socket.create_connection((host, port), timeout=connect_timeout_s)
        except OSError as exc:
            raise DataError(f"{self.name}: cannot connect ({exc})") from None

    def send(self, data: bytes) -> None:
        try:
            self._sock.sendall(data)
        except OSError as exc:
            raise DataError(f"{self.name}: send failed ({exc})") from None

    def read_line(self, timeout_s: float) -> bytes | None:
        return self._read_socket_line(self._sock, timeout_s, datagrams=False)

    def close(self) -> None:
        self._sock.close()


class SerialLineSource(_Buffered):
    """Lines from a serial port or any pyserial URL (``/dev/ttyUSB0``, a pseudo-terminal, ``socket://``)."""

    def __init__(self, url: str, baud: int = 115200, name: str = "") -> None:
        super().__init__(name or f"serial://{url}")
        try:
            import serial
        except ImportError:  # pragma: no cover - pyserial is a dependency
            raise DataError(f"{self.name}: pyserial is not installed (pip install pyserial)") from None
        self._error = serial.SerialException
        try:
            self._serial = serial.serial_for_url(url, baudrate=baud, timeout=0.05)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise DataError(f"{self.name}: cannot open the serial port ({exc})") from None

    def read_line(self, timeout_s: float) -> bytes | None:
        deadline = time.monotonic() + timeout_s
        while (line := self._pop()) is None:
            if time.monotonic() >= deadline:
                return None
            try:
                data = self._serial.read(max(1, self._serial.in_waiting))
            except (self._error, OSError) as exc:
                raise DataError(f"{self.name}: serial read failed ({exc})") from None
            self._feed(data)
        return line

    def close(self) -> None:
        with contextlib.suppress(self._error, OSError):
            self._serial.close()


class LineStream:
    """Lines from a source through a per-line parser (``_parse``), with the stream's QC report and line count.

    ``read(timeout_s)`` returns the next record or None at the timeout; ``records(idle_timeout_s)``
    raises :class:`StreamTimeoutError` after that long without a record.
    """

    def __init__(self, source: LineSource, qc: QcReport | None) -> None:
        self.source = source
        self.name = source.name
        self.qc = QcReport() if qc is None else qc
        self.line = 0

    def _parse(self, text: str) -> object | None:  # pragma: no cover - overridden
        raise NotImplementedError

    def read(self, timeout_s: float) -> object | None:
        """The next valid record, or None if none came within ``timeout_s`` seconds."""
        deadline = time.monotonic() + timeout_s
        while True:
            raw = self.source.read_line(max(0.0, deadline - time.monotonic()))
            if raw is None:
                return None
            self.line += 1
            text = None
            if len(raw) >= MAX_LINE_BYTES:
                self.qc.lines_read += 1
                self.qc.add(self.name, self.line, "truncated sentence", f"line over {MAX_LINE_BYTES} bytes")
            else:
                text = decode_line(raw, self.line, self.qc, self.name)
            record = None if text is None else self._parse(text)
            if record is not None:
                return record
            if time.monotonic() >= deadline:  # a flood of bad lines must not hold the caller past the timeout
                return None

    def records(self, idle_timeout_s: float) -> Iterator[object]:
        """Records as they come; :class:`StreamTimeoutError` after ``idle_timeout_s`` without one."""
        while True:
            record = self.read(idle_timeout_s)
            if record is None:
                raise StreamTimeoutError(f"{self.name}: nothing valid for {idle_timeout_s:g} s")
            yield record

    def close(self) -> None:
        self.source.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
