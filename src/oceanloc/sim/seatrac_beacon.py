"""A SeaTrac USBL beacon simulated behind a pseudo-terminal, speaking the documented serial protocol.

No SeaTrac simulator exists, so the live-survey tests need one. :class:`SeatracBeaconSimulator` opens a
pseudo-terminal pair (``os.openpty``); the client opens :attr:`~SeatracBeaconSimulator.port` (the
slave device) with pyserial exactly as it would open ``/dev/ttyUSB0``. A thread reads ``#`` commands
from the master side and answers as a beacon does (Developer Guide, section 8.1):

- ``CID_PING_SEND`` to a beacon id: at once the send status (``CST_OK``; ``CST_XCVR_BUSY`` while a ping
  is in flight; ``CST_CMD_PARAM_INVALID`` for id 0); then, after the acoustic delay
  ``2 * range / c + turnaround`` (times ``time_scale``, to run faster than real time), a
  ``CID_PING_RESP`` whose ACOFIX carries the range (RANGE_TIME = range / c, RANGE_DIST, VOS) and,
  for MSG_REQU/MSG_REQX, the USBL azimuth and elevation and the relative position; or, for a
  dropout or a beacon id with no transponder, a ``CID_PING_ERROR`` with ``CST_XCVR_RESP_TIMEOUT``
  after the range timeout.
- The range is half the two-way path from the vehicle's true position (a callable of time you pass in,
  ENU metres) at the ping, to the hidden transponder, and back to the vehicle's position when the reply
  arrives (a moving vehicle; the client stamps the range at the middle of the two), plus Gaussian noise;
  with probability ``p_multipath`` it is longer by a uniform draw in ``multipath_extra_m`` (a reflected path).
- Malformed commands get no answer (as the beacon's command processor drops them) and are counted.

Geometry conventions of the simulated USBL head (aligned with north, level, yaw 0): azimuth degrees
clockwise from north, elevation degrees above the horizontal (negative: below), position easting,
northing and depth (down) of the transponder relative to the head, metres.

All draws come from the one seeded ``np.random.Generator`` given, in the order the pings arrive.
"""

from __future__ import annotations

import contextlib
import dataclasses
import heapq
import math
import os
import select
import threading
import time
import tty
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from oceanloc.errors import ConfigError, DataError
from oceanloc.io.seatrac import (
    POSITION_VALID,
    RANGE_VALID,
    USBL_VALID,
    AcoFix,
    AcoPosition,
    AcoRange,
    AcoUsbl,
    Cid,
    Cst,
    MsgType,
    SeatracDecodeError,
    decode_frame,
    decode_ping_send,
    encode_ping_error,
    encode_ping_resp,
    encode_ping_send_status,
)


@dataclass(frozen=True, slots=True, kw_only=True)
class BeaconSimConfig:
    """What the simulated water and beacons do.

    Attributes
    ----------
    transponders_enu_m : mapping of beacon id to (3,) ENU metres
        The hidden transponder positions (ids 1 to 15).
    sound_speed_mps : float
        The water's sound speed (the simulated beacon's VOS), m/s.
    sigma_range_m : float
        Standard deviation of the Gaussian range noise, metres.
    p_dropout : float
        Probability that a ping gets no reply (CID_PING_ERROR, XCVR_RESP_TIMEOUT).
    p_multipath : float
        Probability that a reply came by a longer, reflected path.
    multipath_extra_m : (float, float)
        Range of the extra path length of a multipath reply, metres (uniform).
    turnaround_s : float
        The remote beacon's response delay, seconds (compensated in RANGE_TIME, as the beacon does).
    range_timeout_m : float
        The beacon's range timeout as a distance: a timeout error comes after ``2 * this / c``.
    time_scale : float
        Multiplies every acoustic delay (0.01: a hundred times faster than real time).
    local_id : int
        The simulated head's own beacon id (the DEST_ID of its fixes).
    usbl_channels : int
        USBL receiver channels reported with each fix.
    """

    transponders_enu_m: Mapping[int, tuple[float, float, float]]
    sound_speed_mps: float = 1500.0
    sigma_range_m: float = 0.1
    p_dropout: float = 0.05
    p_multipath: float = 0.03
    multipath_extra_m: tuple[float, float] = (2.0, 6.0)
    turnaround_s: float = 0.01
    range_timeout_m: float = 1000.0
    time_scale: float = 1.0
    local_id: int = 15
    usbl_channels: int = 4

    def __post_init__(self) -> None:
        for b, p in self.transponders_enu_m.items():
            if not 1 <= int(b) <= 15:
                raise ConfigError(f"beacon simulator: transponder id {b} is not 1 to 15")
            if len(p) != 3 or not all(math.isfinite(float(v)) for v in p):
                raise ConfigError(f"beacon simulator: transponder {b} position must be 3 finite numbers")
        if not 1300.0 <= self.sound_speed_mps <= 1700.0:
            raise ConfigError(f"beacon simulator: sound speed {self.sound_speed_mps} outside [1300, 1700]")
        for name in ("p_dropout", "p_multipath"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ConfigError(f"beacon simulator: {name} must be in [0, 1]")
        if self.sigma_range_m < 0 or self.time_scale <= 0 or self.range_timeout_m <= 0:
            raise ConfigError("beacon simulator: sigma >= 0, time_scale > 0 and range_timeout_m > 0 required")


@dataclass(frozen=True, slots=True, kw_only=True)
class SimulatedPing:
    """What the simulator did with one ping (for tests to compare against the client's records)."""

    t_mono_s: float
    beacon: int
    outcome: str
    true_range_m: float | None = None
    reported_range_m: float | None = None

    def to_record(self) -> dict:
        return {
            "t_mono_s": self.t_mono_s,
            "beacon": self.beacon,
            "outcome": self.outcome,
            "true_range_m": self.true_range_m,
            "reported_range_m": self.reported_range_m,
        }


class SeatracBeaconSimulator:
    """A simulated SeaTrac head and its transponders on a pseudo-terminal (a context manager).

    Parameters
    ----------
    config : BeaconSimConfig
    vehicle_position : callable
        ``vehicle_position(t_mono_s) -> (3,) ENU metres`` of the head at monotonic time ``t_mono_s``.
    rng : np.random.Generator
        The one source of noise, dropouts and multipath draws.

    Attributes
    ----------
    port : str
        The slave device path (``/dev/pts/N``) to open with pyserial; set by :meth:`start`.
    pings : list of SimulatedPing
        Every ping handled, in order.
    bad_commands : int
        Malformed command lines received (no answer is sent to them).
    """

    def __init__(
        self,
        config: BeaconSimConfig,
        vehicle_position: Callable[[float], np.ndarray],
        rng: np.random.Generator,
    ) -> None:
        self.config = config
        self.vehicle_position = vehicle_position
        self.rng = rng
        self.port = ""
        self.pings: list[SimulatedPing] = []
        self.bad_commands = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._master = self._slave = -1
        self._busy_until = -math.inf
        self._queue: list[tuple[float, int, bytes]] = []
        self._seq = 0
        self.error: BaseException | None = None
        self.silent = False
        """While True the head answers nothing (a cable pulled, a modem powered off)."""

    def __enter__(self) -> SeatracBeaconSimulator:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def start(self) -> str:
        """Open the pseudo-terminal pair and start answering; returns :attr:`port`."""
        if self._thread is not None:
            raise DataError("beacon simulator already started")
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no CR/LF translation: the bytes as a serial line carries them
        self.port = os.ttyname(self._slave)
        self._thread = threading.Thread(target=self._run, name="seatrac-beacon-sim", daemon=True)
        self._thread.start()
        return self.port

    def stop(self, timeout_s: float = 2.0) -> None:
        """Stop the thread (within ``timeout_s``) and close the pseudo-terminal."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
            if self._thread.is_alive():  # pragma: no cover - the loop wakes every 10 ms
                raise DataError(f"beacon simulator thread did not stop within {timeout_s} s")
            self._thread = None
        for fd in (self._master, self._slave):
            if fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._master = self._slave = -1

    # ------------------------------------------------------------------------------------------ the loop

    def _schedule(self, due: float, frame: bytes | Callable[[], bytes]) -> None:
        heapq.heappush(self._queue, (due, self._seq, frame))
        self._seq += 1

    def _run(self) -> None:
        buffer = bytearray()
        try:
            while not self._stop.is_set():
                now = time.monotonic()
                while self._queue and self._queue[0][0] <= now:
                    _, _, frame = heapq.heappop(self._queue)
                    os.write(self._master, frame() if callable(frame) else frame)
                wait = 0.01 if not self._queue else min(0.01, max(0.0, self._queue[0][0] - now))
                ready, _, _ = select.select([self._master], [], [], wait)
                if not ready:
                    continue
                try:
                    chunk = os.read(self._master, 4096)
                except OSError:  # the slave side was closed by everyone: keep waiting for a new client
                    time.sleep(0.01)
                    continue
                buffer += chunk
                while (cut := buffer.find(b"\n")) >= 0:
                    line = bytes(buffer[:cut]).strip()
                    del buffer[: cut + 1]
                    if line:
                        self._handle(line)
        except BaseException as exc:  # pragma: no cover - surfaced to the test through .error
            self.error = exc

    def _handle(self, line: bytes) -> None:
        if self.silent:
            return
        try:
            frame = decode_frame(line, sync="#")
            if frame.cid != Cid.PING_SEND:
                return  # other commands: not simulated
            cmd = decode_ping_send(frame.payload)
        except SeatracDecodeError:
            self.bad_commands += 1
            return
        now = time.monotonic()
        cfg = self.config
        if not 1 <= cmd.beacon_id <= 15 or cmd.msg_type not in (
            MsgType.MSG_REQ,
            MsgType.MSG_REQU,
            MsgType.MSG_REQX,
        ):
            self._schedule(now, encode_ping_send_status(Cst.CMD_PARAM_INVALID, cmd.beacon_id))
            return
        if now < self._busy_until:
            self._schedule(now, encode_ping_send_status(Cst.XCVR_BUSY, cmd.beacon_id))
            self.pings.append(SimulatedPing(t_mono_s=now, beacon=cmd.beacon_id, outcome="busy"))
            return
        self._schedule(now, encode_ping_send_status(Cst.OK, cmd.beacon_id))
        timeout_delay = cfg.time_scale * 2.0 * cfg.range_timeout_m / cfg.sound_speed_mps
        target = cfg.transponders_enu_m.get(cmd.beacon_id)
        vehicle = np.asarray(self.vehicle_position(now), dtype=float)
        true_range = None if target is None else float(np.linalg.norm(np.asarray(target, float) - vehicle))
        dropout = bool(self.rng.random() < cfg.p_dropout)
        multipath = bool(self.rng.random() < cfg.p_multipath)
        noise = float(self.rng.normal(0.0, cfg.sigma_range_m))
        extra = float(self.rng.uniform(*cfg.multipath_extra_m))
        if true_range is None or dropout or true_range > cfg.range_timeout_m:
            self._busy_until = now + timeout_delay
            self._schedule(self._busy_until, encode_ping_error(Cst.XCVR_RESP_TIMEOUT, cmd.beacon_id))
            self.pings.append(
                SimulatedPing(t_mono_s=now, beacon=cmd.beacon_id, outcome="dropout", true_range_m=true_range)
            )
            return
        delay = cfg.time_scale * (2.0 * true_range / cfg.sound_speed_mps + cfg.turnaround_s)
        self._busy_until = now + delay
        index = len(self.pings)
        self.pings.append(
            SimulatedPing(t_mono_s=now, beacon=cmd.beacon_id, outcome="multipath" if multipath else "ok")
        )
        send_position, beacon_id, msg_type = vehicle, cmd.beacon_id, cmd.msg_type

        def reply() -> bytes:
            # The two-way path: out from the head where it was at the send, back to where it is now.
            back = np.asarray(self.vehicle_position(time.monotonic()), dtype=float)
            tgt = np.asarray(target, float)
            two_way = 0.5 * float(np.linalg.norm(tgt - send_position) + np.linalg.norm(tgt - back))
            measured = max(0.0, two_way + noise + (extra if multipath else 0.0))
            self.pings[index] = dataclasses.replace(
                self.pings[index], true_range_m=two_way, reported_range_m=measured
            )
            return encode_ping_resp(self._fix(beacon_id, msg_type, back, tgt, measured))

        self._schedule(self._busy_until, reply)

    def _fix(
        self, beacon: int, msg_type: int, vehicle: np.ndarray, target: np.ndarray, range_m: float
    ) -> AcoFix:
        cfg = self.config
        c = cfg.sound_speed_mps
        flags = RANGE_VALID
        usbl = position = None
        d = target - vehicle
        if msg_type in (MsgType.MSG_REQU, MsgType.MSG_REQX):
            horizontal = math.hypot(d[0], d[1])
            az = math.degrees(math.atan2(d[0], d[1])) % 360.0
            el = math.degrees(math.atan2(d[2], horizontal))
            usbl = AcoUsbl(
                rssi_db=tuple(-60.0 for _ in range(cfg.usbl_channels)),
                azimuth_deg=round(az, 1) % 360.0,
                elevation_deg=round(el, 1),
                fit_error=0.5,
            )
            flags |= USBL_VALID
            if max(abs(d[0]), abs(d[1]), abs(d[2])) < 3276.0:
                position = AcoPosition(
                    easting_m=round(float(d[0]), 1),
                    northing_m=round(float(d[1]), 1),
                    depth_m=round(float(-target[2]), 1),
                )
                flags |= POSITION_VALID
        resp = {MsgType.MSG_REQ: MsgType.MSG_RESP, MsgType.MSG_REQU: MsgType.MSG_RESPU}.get(
            msg_type, MsgType.MSG_RESPX
        )
        return AcoFix(
            dest_id=cfg.local_id,
            src_id=beacon,
            flags=flags,
            msg_type=resp,
            yaw_deg=0.0,
            pitch_deg=0.0,
            roll_deg=0.0,
            depth_local_m=round(max(0.0, float(-vehicle[2])), 1),
            vos_mps=round(c, 1),
            rssi_db=-60.0,
            range=AcoRange(
                count=round((2.0 * range_m / c + cfg.turnaround_s) * 16_000.0),
                time_s=round(range_m / c, 7),
                dist_m=min(6553.5, round(range_m, 1)),
            ),
            usbl=usbl,
            position=position,
        )
