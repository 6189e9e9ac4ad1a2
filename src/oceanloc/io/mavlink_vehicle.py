"""The vehicle adapter: an ArduPilot Rover boat over MAVLink (pymavlink), as a ground station talks to it.

A connection is named by a URL-like spec:

- ``udp://HOST:PORT``: listen on HOST:PORT for an autopilot that sends there (the ground-station side of
  SITL's ``udpclient`` output or a telemetry radio bridge; 14550 by custom);
- ``udpout://HOST:PORT``: send to an autopilot listening on HOST:PORT;
- ``tcp://HOST:PORT``: connect to an autopilot's TCP server (SITL serves 5760);
- ``serial:///dev/ttyACM0?baud=57600``: a serial port (USB or radio), through pyserial.

What it does, following ArduPilot's "Rover Commands in Guided Mode" page and the MAVLink protocols:

- heartbeats: sends a ground-station HEARTBEAT at 1 Hz; watches the vehicle's, and reports the link lost
  when none came within ``heartbeat_timeout_s`` (:meth:`MavlinkVehicle.link`);
- modes: Rover's custom modes (:data:`ROVER_MODES`), changed with ``MAV_CMD_DO_SET_MODE`` and confirmed by
  ``COMMAND_ACK`` (resent on a timeout, up to ``command_retries`` times), then by the next heartbeat;
- :meth:`MavlinkVehicle.goto`: in GUIDED, ``SET_POSITION_TARGET_GLOBAL_INT`` with the "use position" type
  mask (0x0DFC), confirmed when the vehicle's ``POSITION_TARGET_GLOBAL_INT`` echoes the target;
- :meth:`MavlinkVehicle.upload_mission`: the mission protocol (``MISSION_COUNT``, answered
  ``MISSION_REQUEST_INT``/``MISSION_REQUEST`` -> ``MISSION_ITEM_INT``, ``MISSION_ACK``), resending on a
  timeout; item 0 is home, as ArduPilot expects;
- :meth:`MavlinkVehicle.hold`: HOLD mode;
- telemetry as a position-and-heading source: each ``GLOBAL_POSITION_INT`` becomes a :class:`VehicleFix`
  with the heading from the latest ``ATTITUDE`` yaw (or ``VFR_HUD`` heading, or the message's own
  ``hdg``), after the same line-level QC as the file readers (:class:`oceanloc.io.qc.QcReport`).

oceanloc never arms the vehicle: arming is the operator's, there is no method that arms, and nothing here
sends ``MAV_CMD_COMPONENT_ARM_DISARM``.
"""

from __future__ import annotations

import math
import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Literal
from urllib.parse import parse_qs, urlsplit

from oceanloc.errors import ConfigError
from oceanloc.io._mavlink import mavlink, mavutil
from oceanloc.io.missions import MissionItem, waypoint
from oceanloc.io.qc import QcReport

_INT_FRAMES = {
    mavlink.MAV_FRAME_GLOBAL: mavlink.MAV_FRAME_GLOBAL_INT,
    mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT: mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT: mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
}
"""``MISSION_ITEM_INT`` carries integer latitude/longitude in the ``_INT`` twin of each global frame."""

ROVER_MODES: dict[str, int] = {"MANUAL": 0, "HOLD": 4, "LOITER": 5, "AUTO": 10, "GUIDED": 15}
"""ArduPilot Rover custom modes (``HEARTBEAT.custom_mode``) this adapter uses, name -> number."""
_MODE_NAMES = {v: k for k, v in ROVER_MODES.items()}

USE_POSITION_TYPE_MASK = 0x0DFC
"""``type_mask`` of a position-only SET_POSITION_TARGET_* (ArduPilot's "Use Position", 3580)."""

MAX_SPEED_MPS = 25.0
"""Fixes implying a faster move from the previous fix (beyond 10 m of noise) are gross outliers."""

Status = Literal[
    "accepted", "rejected", "timeout", "link_lost", "not_in_mode", "unconfirmed", "connected", "sent"
]


@dataclass(frozen=True, slots=True, kw_only=True)
class VehicleSpec:
    """A parsed connection spec; :attr:`device` is the pymavlink connection string."""

    spec: str
    kind: Literal["udp", "udpout", "tcp", "serial"]
    device: str
    baud: int = 57600


def parse_vehicle_spec(spec: str) -> VehicleSpec:
    """Parse ``udp://``, ``udpout://``, ``tcp://`` or ``serial://`` (see the module docstring).

    Raises
    ------
    ConfigError
        Naming the spec and what is wrong with it.
    """
    parts = urlsplit(spec)
    kind = parts.scheme.lower()
    if kind in ("udp", "udpout", "tcp"):
        try:
            host, port = parts.hostname, parts.port
        except ValueError:
            host, port = None, None
        if not host or port is None or not 0 < port < 65536:
            raise ConfigError(f"vehicle spec {spec!r}: expected {kind}://HOST:PORT with a port in 1..65535")
        prefix = {"udp": "udpin", "udpout": "udpout", "tcp": "tcp"}[kind]
        return VehicleSpec(spec=spec, kind=kind, device=f"{prefix}:{host}:{port}")
    if kind == "serial":
        if not parts.path:
            raise ConfigError(f"vehicle spec {spec!r}: expected serial:///dev/PORT?baud=N")
        query = parse_qs(parts.query)
        unknown = sorted(set(query) - {"baud"})
        if unknown:
            raise ConfigError(f"vehicle spec {spec!r}: unknown option {unknown[0]!r} (only baud)")
        baud_text = query.get("baud", ["57600"])[-1]
        if not baud_text.isdigit() or int(baud_text) <= 0:
            raise ConfigError(f"vehicle spec {spec!r}: baud must be a positive integer, got {baud_text!r}")
        return VehicleSpec(spec=spec, kind="serial", device=parts.path, baud=int(baud_text))
    raise ConfigError(f"vehicle spec {spec!r}: expected udp://, udpout://, tcp:// or serial://")


@dataclass(frozen=True, slots=True, kw_only=True)
class CommandResult:
    """The outcome of a command to the vehicle.

    Attributes
    ----------
    status : str
        ``accepted``, ``rejected`` (the vehicle said no), ``timeout`` (no answer after the retries),
        ``link_lost``, ``not_in_mode`` (e.g. a goto outside GUIDED), ``unconfirmed`` (sent; the vehicle
        did not echo it) or ``connected``.
    message : str
        One line for the operator.
    command : int
        MAVLink command or message id concerned (0 if none).
    result_code : int
        The vehicle's ``MAV_RESULT``/``MAV_MISSION_RESULT`` (-1 if none came).
    """

    status: Status
    message: str
    command: int = 0
    result_code: int = -1

    @property
    def ok(self) -> bool:
        return self.status in ("accepted", "connected")

    def to_record(self) -> dict:
        return {
            "status": self.status,
            "message": self.message,
            "command": self.command,
            "result_code": self.result_code,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class MissionUploadResult:
    """The outcome of a mission upload: status as :class:`CommandResult`, items sent and resends."""

    status: Status
    message: str
    n_items: int
    resends: int
    result_code: int = -1

    @property
    def ok(self) -> bool:
        return self.status == "accepted"

    def to_record(self) -> dict:
        return {
            "status": self.status,
            "message": self.message,
            "n_items": self.n_items,
            "resends": self.resends,
            "result_code": self.result_code,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class LinkStatus:
    """The vehicle link as last heard.

    Attributes
    ----------
    alive : bool
        A heartbeat came within the timeout.
    heartbeat_age_s : float
        Seconds since the last heartbeat (inf before the first).
    mode : int
        Rover custom mode (-1 before the first heartbeat); ``mode_name`` its name.
    armed : bool
        The vehicle reports itself armed (by its operator).
    """

    alive: bool
    heartbeat_age_s: float
    mode: int
    mode_name: str
    armed: bool

    def to_record(self) -> dict:
        age = self.heartbeat_age_s if math.isfinite(self.heartbeat_age_s) else None
        return {
            "alive": self.alive,
            "heartbeat_age_s": age,
            "mode": self.mode_name,
            "armed": self.armed,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class VehicleFix:
    """One position-and-heading fix from the autopilot.

    Attributes
    ----------
    t_unix_s : float
        Host time when the fix arrived, Unix seconds (MAVLink positions carry only time since boot).
    time_boot_ms : int
        The autopilot's time since boot, milliseconds.
    lat_deg, lon_deg : float
        WGS84 position, degrees.
    h_m : float
        Height as the autopilot reports it (GLOBAL_POSITION_INT ``alt``: above mean sea level), metres.
    heading_deg : float
        Heading, clockwise from north, degrees [0, 360); NaN when none is known.
    heading_source : str
        ``ATTITUDE``, ``VFR_HUD``, ``GLOBAL_POSITION_INT`` or ``none``.
    """

    t_unix_s: float
    time_boot_ms: int
    lat_deg: float
    lon_deg: float
    h_m: float
    heading_deg: float
    heading_source: str

    def to_record(self) -> dict:
        return {
            "t_unix_s": self.t_unix_s,
            "time_boot_ms": self.time_boot_ms,
            "lat_deg": self.lat_deg,
            "lon_deg": self.lon_deg,
            "h_m": self.h_m,
            "heading_deg": self.heading_deg if math.isfinite(self.heading_deg) else None,
            "heading_source": self.heading_source,
        }


def _result_name(enum: str, code: int) -> str:
    entry = mavlink.enums.get(enum, {}).get(code)
    return entry.name if entry is not None else str(code)


class _FixQc:
    """Line-level QC of GLOBAL_POSITION_INT, as the file readers do it (reasons of io.qc.REASONS).

    A fix is a gross outlier when it lies farther from the last kept fix than ``max_speed * dt`` plus
    ``jump_allowance_m`` (the GNSS noise of two fixes, so that noisy fixes at 5 Hz are not thrown out).
    After ``reset_after`` outliers in a row the position really moved (a GNSS re-acquisition): the fix is
    kept, noted, and becomes the new reference.
    """

    def __init__(
        self,
        source: str,
        qc: QcReport,
        max_speed_mps: float,
        jump_allowance_m: float = 10.0,
        reset_after: int = 5,
    ) -> None:
        self.source, self.qc, self.max_speed_mps = source, qc, max_speed_mps
        self.jump_allowance_m, self.reset_after = jump_allowance_m, reset_after
        self.last: tuple[int, float, float] | None = None  # time_boot_ms, lat, lon
        self.number = 0
        self.outliers_in_a_row = 0

    def check(self, msg) -> tuple[float, float, float] | None:
        self.number += 1
        self.qc.lines_read += 1
        lat, lon, h = msg.lat * 1e-7, msg.lon * 1e-7, msg.alt * 1e-3
        if msg.lat == 0 and msg.lon == 0:
            return self._skip("invalid fix", "lat = lon = 0 (no position yet)")
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            return self._skip("invalid fix", f"lat {lat:.7f}, lon {lon:.7f} out of range")
        if self.last is not None:
            t0, lat0, lon0 = self.last
            dt_s = (msg.time_boot_ms - t0) * 1e-3
            if dt_s == 0.0:
                return self._skip("duplicate record", f"time_boot_ms {msg.time_boot_ms}")
            if dt_s < 0.0:
                self.last = None  # the autopilot rebooted (or the clock stepped): restart from this fix
                self.qc.add(self.source, self.number, "time going backwards", f"{dt_s:+.3f} s; kept")
            else:
                north = math.radians(lat - lat0) * 6_371_000.0
                east = math.radians(lon - lon0) * 6_371_000.0 * math.cos(math.radians(lat0))
                jump = math.hypot(north, east)
                if jump > self.max_speed_mps * dt_s + self.jump_allowance_m:
                    self.outliers_in_a_row += 1
                    if self.outliers_in_a_row < self.reset_after:
                        return self._skip("gross outlier", f"{jump:.0f} m in {dt_s:.1f} s")
                    self.qc.add(
                        self.source,
                        self.number,
                        "gross outlier",
                        f"{self.reset_after} in a row: new reference; kept",
                    )
        self.outliers_in_a_row = 0
        self.last = (msg.time_boot_ms, lat, lon)
        self.qc.records_kept += 1
        return lat, lon, h

    def _skip(self, reason: str, detail: str) -> None:
        self.qc.add(self.source, self.number, reason, detail)
        return None


class MavlinkVehicle:
    """A Rover boat over MAVLink; see the module docstring. Use as a context manager or call close().

    Parameters
    ----------
    spec : str
        Connection spec (:func:`parse_vehicle_spec`).
    heartbeat_timeout_s : float
        The link is lost when no vehicle heartbeat came for this long (wall-clock seconds).
    command_timeout_s : float
        Wait for each acknowledgement this long before resending.
    command_retries : int
        Resends after the first try.
    max_speed_mps : float
        QC: a fix implying a faster move is a gross outlier.
    gcs_heartbeat_hz : float
        Rate of our ground-station heartbeat (1 Hz; faster against a simulator run faster than real time,
        whose GCS failsafe counts simulated seconds).
    source_system, source_component : int
        Our MAVLink ids (a ground station: 255, ``MAV_COMP_ID_MISSIONPLANNER``).
    clock : callable
        Monotonic clock for the timeouts (tests may pass their own).
    """

    def __init__(
        self,
        spec: str,
        *,
        heartbeat_timeout_s: float = 3.0,
        command_timeout_s: float = 1.0,
        command_retries: int = 2,
        max_speed_mps: float = MAX_SPEED_MPS,
        gcs_heartbeat_hz: float = 1.0,
        source_system: int = 255,
        source_component: int = mavlink.MAV_COMP_ID_MISSIONPLANNER,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.spec = parse_vehicle_spec(spec)
        for name, value in (
            ("heartbeat_timeout_s", heartbeat_timeout_s),
            ("command_timeout_s", command_timeout_s),
        ):
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"{name} must be a positive number of seconds, got {value}")
        if command_retries < 0:
            raise ConfigError(f"command_retries must be 0 or more, got {command_retries}")
        self.heartbeat_timeout_s = float(heartbeat_timeout_s)
        self.command_timeout_s = float(command_timeout_s)
        self.command_retries = int(command_retries)
        if not (math.isfinite(gcs_heartbeat_hz) and gcs_heartbeat_hz > 0.0):
            raise ConfigError(f"gcs_heartbeat_hz must be a positive number, got {gcs_heartbeat_hz}")
        self._gcs_heartbeat_s = 1.0 / float(gcs_heartbeat_hz)
        self._source = (int(source_system), int(source_component))
        self._clock = clock
        self.qc = QcReport()
        self._fix_qc = _FixQc(spec, self.qc, max_speed_mps)
        self._conn = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._send_lock = threading.Lock()
        self._state_lock = threading.Lock()
        self._waiters: list[tuple[Callable[[object], bool], queue.Queue]] = []
        self._target: tuple[int, int] | None = None  # system, component of the autopilot
        self._last_hb = -math.inf
        self._mode = -1
        self._armed = False
        self._heading: dict[str, tuple[float, float]] = {}  # source -> (wall time, heading_deg)
        self._fixes: deque[VehicleFix] = deque(maxlen=10_000)
        self._fix_ready = threading.Condition(self._state_lock)
        self._latest_fix: VehicleFix | None = None
        self._position_target: tuple[int, int] | None = None
        self.reached: list[int] = []
        """Mission items the vehicle reported reached (MISSION_ITEM_REACHED), in order."""
        self.mission_current = -1
        """The vehicle's current mission item (MISSION_CURRENT)."""
        self.status_texts: deque[str] = deque(maxlen=100)
        """The vehicle's recent STATUSTEXT lines."""
        self.sent: list[str] = []
        """Names of the messages sent (with the command id for COMMAND_LONG), for audits and tests."""

    # -- connection -------------------------------------------------------------------------------

    def connect(self, wait_heartbeat_s: float = 5.0) -> CommandResult:
        """Open the link, start the reader, and wait for the vehicle's first heartbeat."""
        if self._conn is None:
            s = self.spec
            kwargs = {"baud": s.baud} if s.kind == "serial" else {}
            try:
                self._conn = mavutil.mavlink_connection(
                    s.device,
                    source_system=self._source[0],
                    source_component=self._source[1],
                    dialect="ardupilotmega",
                    **kwargs,
                )
            except (OSError, ValueError) as exc:
                raise ConfigError(f"vehicle {s.spec}: cannot open ({exc})") from None
            self._stop.clear()
            self._thread = threading.Thread(target=self._run, name="mavlink-vehicle", daemon=True)
            self._thread.start()
        deadline = self._clock() + wait_heartbeat_s
        while self._clock() < deadline:
            if self.link().alive:
                return CommandResult(status="connected", message=f"vehicle {self.spec.spec}: heartbeat")
            time.sleep(0.02)
        return CommandResult(
            status="timeout", message=f"vehicle {self.spec.spec}: no heartbeat within {wait_heartbeat_s:g} s"
        )

    def close(self) -> None:
        """Stop the reader and close the link (idempotent)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)
            self._thread = None
        if self._conn is not None:
            self._conn.close()
            self._conn = None

    def __enter__(self) -> MavlinkVehicle:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def link(self) -> LinkStatus:
        """The link's state now."""
        with self._state_lock:
            age = self._clock() - self._last_hb
            mode, armed = self._mode, self._armed
        return LinkStatus(
            alive=age <= self.heartbeat_timeout_s,
            heartbeat_age_s=age,
            mode=mode,
            mode_name=_MODE_NAMES.get(mode, "unknown" if mode < 0 else str(mode)),
            armed=armed,
        )

    # -- modes ------------------------------------------------------------------------------------

    def require_mode(self, mode: str) -> CommandResult:
        """``accepted`` if the vehicle is in ``mode`` now, else ``not_in_mode`` (or ``link_lost``)."""
        number = _mode_number(mode)
        st = self.link()
        if not st.alive:
            return CommandResult(
                status="link_lost", message=f"vehicle link lost ({st.heartbeat_age_s:.1f} s)"
            )
        if st.mode != number:
            return CommandResult(
                status="not_in_mode", message=f"vehicle is in {st.mode_name}, not {mode.upper()}"
            )
        return CommandResult(status="accepted", message=f"vehicle is in {mode.upper()}")

    def set_mode(self, mode: str) -> CommandResult:
        """Change the Rover mode with ``MAV_CMD_DO_SET_MODE`` and wait for its acknowledgement."""
        number = _mode_number(mode)
        result = self._command_long(
            mavlink.MAV_CMD_DO_SET_MODE, (mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, number, 0, 0, 0, 0, 0)
        )
        if not result.ok:
            return CommandResult(
                status=result.status,
                message=f"mode {mode.upper()}: {result.message}",
                command=result.command,
                result_code=result.result_code,
            )
        # the acknowledgement comes after the change; the next heartbeat shows it
        deadline = self._clock() + self.heartbeat_timeout_s
        while self._clock() < deadline and self.link().mode != number:
            time.sleep(0.01)
        if self.link().mode != number:
            return CommandResult(
                status="unconfirmed",
                message=f"mode {mode.upper()} acknowledged; heartbeat still shows {self.link().mode_name}",
                command=result.command,
                result_code=result.result_code,
            )
        return CommandResult(
            status="accepted",
            message=f"mode {mode.upper()}",
            command=result.command,
            result_code=result.result_code,
        )

    def hold(self) -> CommandResult:
        """Stop the vehicle: HOLD mode (a boat then drifts; LOITER holds station)."""
        return self.set_mode("HOLD")

    # -- guided -----------------------------------------------------------------------------------

    def goto(self, lat_deg: float, lon_deg: float, *, ensure_guided: bool = True) -> CommandResult:
        """Send the vehicle to a point in GUIDED mode.

        With ``ensure_guided`` the mode is changed to GUIDED first when it is not; otherwise a vehicle in
        another mode gives ``not_in_mode`` (ArduPilot ignores position targets outside GUIDED). The target
        is resent up to ``command_retries`` times until the vehicle echoes it in POSITION_TARGET_GLOBAL_INT
        (``accepted``); without an echo the result is ``unconfirmed``.
        """
        if not (
            math.isfinite(lat_deg)
            and math.isfinite(lon_deg)
            and -90 <= lat_deg <= 90
            and -180 <= lon_deg <= 180
        ):
            raise ConfigError(f"goto target {lat_deg}, {lon_deg}: latitude or longitude out of range")
        st = self.require_mode("GUIDED")
        if st.status == "not_in_mode" and ensure_guided:
            st = self.set_mode("GUIDED")
        if not st.ok:
            return st
        lat_i, lon_i = round(lat_deg * 1e7), round(lon_deg * 1e7)
        with self._state_lock:
            self._position_target = None
        for _ in range(self.command_retries + 1):
            self._send(
                "SET_POSITION_TARGET_GLOBAL_INT",
                lambda mav, sys_, comp: mav.set_position_target_global_int_send(
                    0, sys_, comp, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, USE_POSITION_TYPE_MASK,
                    lat_i, lon_i, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                ),
            )  # fmt: skip
            deadline = self._clock() + self.command_timeout_s
            while self._clock() < deadline:
                with self._state_lock:
                    echo = self._position_target
                if echo is not None and abs(echo[0] - lat_i) <= 1 and abs(echo[1] - lon_i) <= 1:
                    return CommandResult(
                        status="accepted",
                        message=f"goto {lat_deg:.7f}, {lon_deg:.7f}",
                        command=mavlink.MAVLINK_MSG_ID_SET_POSITION_TARGET_GLOBAL_INT,
                    )
                time.sleep(0.01)
        return CommandResult(
            status="unconfirmed",
            message=f"goto {lat_deg:.7f}, {lon_deg:.7f} sent; the vehicle did not echo the target",
            command=mavlink.MAVLINK_MSG_ID_SET_POSITION_TARGET_GLOBAL_INT,
        )

    def send_goto(self, lat_deg: float, lon_deg: float) -> CommandResult:
        """Send a GUIDED position target once and return at once (``sent``), for a loop that re-targets
        the vehicle at every range and must not wait for the echo; :meth:`target_echoed` tells later
        whether the vehicle took it. Outside GUIDED it is ``not_in_mode`` and nothing is sent."""
        if not (math.isfinite(lat_deg) and math.isfinite(lon_deg) and -90 <= lat_deg <= 90):
            raise ConfigError(f"goto target {lat_deg}, {lon_deg}: latitude or longitude out of range")
        st = self.require_mode("GUIDED")
        if not st.ok:
            return st
        lat_i, lon_i = round(lat_deg * 1e7), round(lon_deg * 1e7)
        self._send(
            "SET_POSITION_TARGET_GLOBAL_INT",
            lambda mav, sys_, comp: mav.set_position_target_global_int_send(
                0, sys_, comp, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, USE_POSITION_TYPE_MASK,
                lat_i, lon_i, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            ),
        )  # fmt: skip
        return CommandResult(
            status="sent",
            message=f"goto {lat_deg:.7f}, {lon_deg:.7f} sent",
            command=mavlink.MAVLINK_MSG_ID_SET_POSITION_TARGET_GLOBAL_INT,
        )

    def target_echoed(self, lat_deg: float, lon_deg: float) -> bool:
        """Whether the vehicle's latest POSITION_TARGET_GLOBAL_INT is that point (to 1e-7 deg)."""
        with self._state_lock:
            echo = self._position_target
        return (
            echo is not None
            and abs(echo[0] - round(lat_deg * 1e7)) <= 1
            and abs(echo[1] - round(lon_deg * 1e7)) <= 1
        )

    # -- missions ---------------------------------------------------------------------------------

    def upload_mission(
        self, waypoints_lat_lon_deg: Sequence[tuple[float, float]], *, home: tuple[float, float] | None = None
    ) -> MissionUploadResult:
        """Upload waypoints as a mission (``MAV_CMD_NAV_WAYPOINT`` items, item 0 home).

        ``home`` defaults to the latest fix. Each step waits ``command_timeout_s`` for the vehicle's next
        request and resends what it sent last, up to ``command_retries`` times in a row.
        """
        if home is None:
            fix = self.latest_fix()
            if fix is None:
                return MissionUploadResult(
                    status="rejected", message="mission: no position yet for home", n_items=0, resends=0
                )
            home = (fix.lat_deg, fix.lon_deg)
        return self.upload_mission_items([waypoint(lat, lon) for lat, lon in [home, *waypoints_lat_lon_deg]])

    def upload_mission_items(self, items: Sequence[MissionItem]) -> MissionUploadResult:
        """Upload mission items (:class:`~oceanloc.io.missions.MissionItem`, item 0 home): waypoints, holds,
        take-offs, landings (a drift plan's mission, :func:`oceanloc.io.missions.drift_mission`)."""
        for it in items:
            lat, lon = it.lat_deg, it.lon_deg
            if not (math.isfinite(lat) and math.isfinite(lon) and -90 <= lat <= 90 and -180 <= lon <= 180):
                raise ConfigError(f"mission waypoint {lat}, {lon}: latitude or longitude out of range")
        points = list(items)
        n = len(points)

        def is_answer(msg) -> bool:
            return msg.get_type() in ("MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK") and getattr(
                msg, "mission_type", 0
            ) in (0, mavlink.MAV_MISSION_TYPE_MISSION)

        def send_count() -> None:
            self._send("MISSION_COUNT", lambda mav, s, c: mav.mission_count_send(s, c, n, 0))

        def send_item(seq: int) -> None:
            it = points[seq]
            frame = _INT_FRAMES.get(it.frame, it.frame)
            p1, p2, p3, p4 = it.params
            self._send(
                "MISSION_ITEM_INT",
                lambda mav, s, c: mav.mission_item_int_send(
                    s, c, seq, frame, it.command, 0, int(it.autocontinue), p1, p2, p3, p4,
                    round(it.lat_deg * 1e7), round(it.lon_deg * 1e7), it.alt_m, 0,
                ),
            )  # fmt: skip

        resends, strikes = 0, 0
        last_sent: Callable[[], None] = send_count
        with self._subscribe(is_answer) as inbox:
            send_count()
            while True:
                try:
                    msg = inbox.get(timeout=self.command_timeout_s)
                except queue.Empty:
                    if not self.link().alive:
                        return MissionUploadResult(
                            status="link_lost",
                            message="mission: vehicle link lost",
                            n_items=n,
                            resends=resends,
                        )
                    if strikes >= self.command_retries:
                        return MissionUploadResult(
                            status="timeout",
                            message=f"mission: no answer after {strikes + 1} tries",
                            n_items=n,
                            resends=resends,
                        )
                    strikes += 1
                    resends += 1
                    last_sent()
                    continue
                if msg.get_type() == "MISSION_ACK":
                    name = _result_name("MAV_MISSION_RESULT", msg.type)
                    if msg.type == mavlink.MAV_MISSION_ACCEPTED:
                        return MissionUploadResult(
                            status="accepted",
                            message=f"mission: {n} items accepted",
                            n_items=n,
                            resends=resends,
                            result_code=msg.type,
                        )
                    return MissionUploadResult(
                        status="rejected",
                        message=f"mission: {name}",
                        n_items=n,
                        resends=resends,
                        result_code=msg.type,
                    )
                seq = int(msg.seq)
                if not 0 <= seq < n:
                    continue
                strikes = 0

                def again(seq: int = seq) -> None:
                    send_item(seq)

                last_sent = again
                send_item(seq)

    def start_mission(self) -> CommandResult:
        """Switch to AUTO: the vehicle drives the uploaded mission."""
        return self.set_mode("AUTO")

    # -- telemetry --------------------------------------------------------------------------------

    def latest_fix(self) -> VehicleFix | None:
        """The most recent fix that passed QC."""
        with self._state_lock:
            return self._latest_fix

    def fixes(self, timeout_s: float = 1.0) -> Iterator[VehicleFix]:
        """Yield fixes as they arrive (those not yet taken); stop after ``timeout_s`` without one."""
        while True:
            with self._fix_ready:
                if not self._fixes:
                    self._fix_ready.wait(timeout_s)
                if not self._fixes:
                    return
                fix = self._fixes.popleft()
            yield fix

    # -- internals --------------------------------------------------------------------------------

    def _send(self, name: str, build: Callable) -> None:
        conn = self._conn
        if conn is None:
            raise RuntimeError("the vehicle is not connected (call connect())")
        sys_, comp = self._target or (1, 1)
        with self._send_lock:
            build(conn.mav, sys_, comp)
        self.sent.append(name)

    def _command_long(self, command: int, params: tuple[float, ...]) -> CommandResult:
        if not self.link().alive:
            return CommandResult(status="link_lost", message="vehicle link lost", command=command)
        name = _result_name("MAV_CMD", command)

        def is_ack(msg) -> bool:
            return msg.get_type() == "COMMAND_ACK" and msg.command == command

        with self._subscribe(is_ack) as inbox:
            for attempt in range(self.command_retries + 1):
                self._send(
                    f"COMMAND_LONG:{command}",
                    lambda mav, s, c, k=attempt: mav.command_long_send(s, c, command, k, *params),
                )
                deadline = self._clock() + self.command_timeout_s
                while True:
                    left = deadline - self._clock()
                    if left <= 0:
                        break
                    try:
                        ack = inbox.get(timeout=left)
                    except queue.Empty:
                        break
                    if ack.result == mavlink.MAV_RESULT_IN_PROGRESS:
                        deadline = self._clock() + self.command_timeout_s
                        continue
                    verdict = _result_name("MAV_RESULT", ack.result)
                    status: Status = "accepted" if ack.result == mavlink.MAV_RESULT_ACCEPTED else "rejected"
                    return CommandResult(
                        status=status,
                        message=f"{name}: {verdict}",
                        command=command,
                        result_code=int(ack.result),
                    )
                if not self.link().alive:
                    return CommandResult(
                        status="link_lost", message=f"{name}: vehicle link lost", command=command
                    )
        tries = self.command_retries + 1
        return CommandResult(
            status="timeout", message=f"{name}: no acknowledgement after {tries} tries", command=command
        )

    class _Subscription:
        def __init__(self, owner: MavlinkVehicle, predicate: Callable[[object], bool]) -> None:
            self.owner, self.entry = owner, (predicate, queue.Queue())

        def __enter__(self) -> queue.Queue:
            with self.owner._state_lock:
                self.owner._waiters.append(self.entry)
            return self.entry[1]

        def __exit__(self, *exc: object) -> None:
            with self.owner._state_lock:
                self.owner._waiters.remove(self.entry)

    def _subscribe(self, predicate: Callable[[object], bool]) -> MavlinkVehicle._Subscription:
        return MavlinkVehicle._Subscription(self, predicate)

    def _run(self) -> None:
        next_hb = 0.0
        while not self._stop.is_set():
            now = self._clock()
            if now >= next_hb:
                next_hb = now + self._gcs_heartbeat_s
                try:
                    with self._send_lock:
                        self._conn.mav.heartbeat_send(
                            mavlink.MAV_TYPE_GCS,
                            mavlink.MAV_AUTOPILOT_INVALID,
                            0,
                            0,
                            mavlink.MAV_STATE_ACTIVE,
                        )
                except OSError:
                    pass
            try:
                msg = self._conn.recv_match(blocking=True, timeout=0.05)
            except (OSError, ValueError):
                msg = None
                time.sleep(0.05)
            if msg is None or msg.get_type() == "BAD_DATA":
                continue
            self._dispatch(msg)

    def _dispatch(self, msg) -> None:
        name = msg.get_type()
        src = (msg.get_srcSystem(), msg.get_srcComponent())
        if name == "HEARTBEAT":
            if msg.autopilot == mavlink.MAV_AUTOPILOT_INVALID or msg.type == mavlink.MAV_TYPE_GCS:
                return
            if self._target is None:
                self._target = src
            if src != self._target:
                return
            with self._state_lock:
                self._last_hb = self._clock()
                self._mode = int(msg.custom_mode)
                self._armed = bool(msg.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
            return
        if self._target is not None and src[0] != self._target[0]:
            return
        with self._state_lock:
            waiters = list(self._waiters)
        for predicate, inbox in waiters:
            if predicate(msg):
                inbox.put(msg)
        now_wall = time.time()
        if name == "ATTITUDE":
            with self._state_lock:
                self._heading["ATTITUDE"] = (now_wall, math.degrees(msg.yaw) % 360.0)
        elif name == "VFR_HUD":
            with self._state_lock:
                self._heading["VFR_HUD"] = (now_wall, float(msg.heading) % 360.0)
        elif name == "GLOBAL_POSITION_INT":
            self._on_position(msg, now_wall)
        elif name == "POSITION_TARGET_GLOBAL_INT":
            with self._state_lock:
                self._position_target = (int(msg.lat_int), int(msg.lon_int))
        elif name == "MISSION_ITEM_REACHED":
            self.reached.append(int(msg.seq))
        elif name == "MISSION_CURRENT":
            self.mission_current = int(msg.seq)
        elif name == "STATUSTEXT":
            self.status_texts.append(str(msg.text))

    def _on_position(self, msg, now_wall: float) -> None:
        checked = self._fix_qc.check(msg)
        if checked is None:
            return
        lat, lon, h = checked
        heading, source = math.nan, "none"
        with self._state_lock:
            for name in ("ATTITUDE", "VFR_HUD"):
                entry = self._heading.get(name)
                if entry is not None and now_wall - entry[0] <= 1.0:
                    heading, source = entry[1], name
                    break
        if source == "none" and msg.hdg != 65535:
            heading, source = msg.hdg / 100.0, "GLOBAL_POSITION_INT"
        fix = VehicleFix(
            t_unix_s=now_wall,
            time_boot_ms=int(msg.time_boot_ms),
            lat_deg=lat,
            lon_deg=lon,
            h_m=h,
            heading_deg=heading,
            heading_source=source,
        )
        with self._fix_ready:
            self._latest_fix = fix
            self._fixes.append(fix)
            self._fix_ready.notify_all()


def _mode_number(mode: str) -> int:
    key = mode.upper()
    if key not in ROVER_MODES:
        raise ConfigError(f"mode {mode!r}: expected one of {', '.join(ROVER_MODES)}")
    return ROVER_MODES[key]
