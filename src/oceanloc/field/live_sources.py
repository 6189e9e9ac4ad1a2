"""The live survey's inputs, each read in its own thread into one queue the survey loop takes from.

A SeaTrac ping blocks for up to its timeout and gpsd may go quiet, so no source may hold up another or
the loop: each stream runs in a :class:`SourcePump` thread that puts what it reads on a shared
``queue.Queue`` as :class:`Arrival` items (the record and the monotonic time it arrived, from which the
loop measures its latency), and the loop alone writes to the journal (one SQLite connection, one
thread). A source that fails (gpsd restarted, a serial port unplugged) is reported as an ``error``
arrival and reopened after ``reopen_s``; the loop's watchdog decides what a silent source means.

Position sources: the NMEA and gpsd streams of :mod:`oceanloc.io.streams`, or the vehicle's own MAVLink
telemetry (:class:`~oceanloc.io.mavlink_vehicle.MavlinkVehicle`'s fixes, spec ``mavlink``), whose
headings come with each fix. Range sources: range-line streams and the SeaTrac pinger, which pings its
beacons in turn, at most one ping per ``ping_interval_s``.
"""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from oceanloc.errors import ConfigError, DataError
from oceanloc.io.mavlink_vehicle import MavlinkVehicle
from oceanloc.io.nmea import GpsFix, Heading
from oceanloc.io.qc import QcReport
from oceanloc.io.streams import (
    POSITION_SCHEMES,
    RANGE_SCHEMES,
    open_position_stream,
    open_range_stream,
    parse_spec,
)
from oceanloc.io.usbl import RangeRecord

ArrivalKind = Literal["fix", "heading", "range", "error"]


@dataclass(frozen=True, slots=True, kw_only=True)
class Arrival:
    """One item from a source: a fix, heading or range record, or an error message.

    ``t_mono_s`` is the monotonic clock when the pump got it (the start of the loop's latency).
    """

    kind: ArrivalKind
    source: str
    t_mono_s: float
    record: GpsFix | Heading | RangeRecord | None = None
    message: str = ""


class SourcePump:
    """Reads one stream in a daemon thread and puts each record on ``out`` (see the module docstring).

    Parameters
    ----------
    name : str
        ``position`` or ``ranges``.
    opener : callable
        Opens the stream (called again after a failure); the stream has ``read(timeout_s)`` and ``close()``.
    out : queue.Queue
    min_interval_s : float
        Least time between two reads that returned a record (a SeaTrac ping cycle), seconds.
    reopen_s : float
        Wait before reopening a stream that failed, seconds.
    """

    def __init__(
        self,
        name: str,
        opener: Callable[[], object],
        out: queue.Queue,
        *,
        min_interval_s: float = 0.0,
        reopen_s: float = 1.0,
    ) -> None:
        self.name = name
        self._opener = opener
        self._out = out
        self._min_interval_s = float(min_interval_s)
        self._reopen_s = float(reopen_s)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._stream: object | None = None
        self.qc = QcReport()
        self.last_record_mono_s = -float("inf")
        """Monotonic time of the last good record (a fix, heading or successful range), for the watchdog:
        it counts when the pump got it, not when the loop took it off the queue."""

    def start(self) -> SourcePump:
        self._thread = threading.Thread(target=self._run, name=f"source-{self.name}", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout_s: float = 3.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
        self._close()

    def _close(self) -> None:
        stream, self._stream = self._stream, None
        if stream is not None:
            with contextlib.suppress(OSError, DataError):
                stream.close()  # type: ignore[attr-defined]

    def _put(self, kind: ArrivalKind, record: object = None, message: str = "") -> None:
        self._out.put(
            Arrival(kind=kind, source=self.name, t_mono_s=time.monotonic(), record=record, message=message)
        )

    def _run(self) -> None:
        last = -float("inf")
        while not self._stop.is_set():
            try:
                if self._stream is None:
                    self._stream = self._opener()
                    qc = getattr(self._stream, "qc", None)
                    if isinstance(qc, QcReport):
                        self.qc = qc
                wait = last + self._min_interval_s - time.monotonic()
                if wait > 0 and self._stop.wait(wait):
                    return
                rec = self._stream.read(0.25)  # type: ignore[attr-defined]
            except DataError as exc:
                self._close()
                self._put("error", message=str(exc))
                if self._stop.wait(self._reopen_s):
                    return
                continue
            if rec is None:
                continue
            last = time.monotonic()
            if not isinstance(rec, RangeRecord) or rec.ok:
                self.last_record_mono_s = last
            if isinstance(rec, GpsFix):
                self._put("fix", rec)
            elif isinstance(rec, Heading):
                self._put("heading", rec)
            elif isinstance(rec, RangeRecord):
                self._put("range", rec)


class _VehicleFixes:
    """The vehicle's telemetry as a position stream: each MAVLink fix, then its heading when known."""

    def __init__(self, vehicle: MavlinkVehicle) -> None:
        self.vehicle = vehicle
        self.qc = vehicle.qc
        self._pending: Heading | None = None

    def read(self, timeout_s: float) -> GpsFix | Heading | None:
        if self._pending is not None:
            out, self._pending = self._pending, None
            return out
        for fix in self.vehicle.fixes(timeout_s):
            if fix.heading_deg == fix.heading_deg:  # not NaN
                self._pending = Heading(t_unix_s=fix.t_unix_s, heading_deg=fix.heading_deg, source="mavlink")
            return GpsFix(t_unix_s=fix.t_unix_s, lat_deg=fix.lat_deg, lon_deg=fix.lon_deg, h_m=fix.h_m,
                          source="mavlink")  # fmt: skip
        return None

    def close(self) -> None:
        """The vehicle link is the loop's; it closes it."""


def position_opener(spec: str, vehicle: MavlinkVehicle | None) -> Callable[[], object]:
    """The opener of the position source ``spec`` (``mavlink``: the vehicle's telemetry)."""
    if spec.strip().lower() in ("mavlink", "vehicle"):
        if vehicle is None:
            raise ConfigError("--position mavlink needs --vehicle (the autopilot's telemetry is the source)")
        return lambda: _VehicleFixes(vehicle)
    parse_spec(spec, allowed=POSITION_SCHEMES, what="position source")
    return lambda: open_position_stream(spec)


def range_opener(
    spec: str, *, sound_speed_mps: float, beacons: tuple[int, ...] | None
) -> Callable[[], object]:
    """The opener of the range source ``spec`` (checked now, opened by the pump)."""
    parse_spec(spec, allowed=RANGE_SCHEMES, what="range source")
    return lambda: open_range_stream(spec, sound_speed_mps=sound_speed_mps, beacons=beacons or None)
