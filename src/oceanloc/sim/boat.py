"""A boat that speaks ArduPilot Rover's MAVLink dialect, for testing the vehicle adapter on loopback.

What it implements follows ArduPilot's published Rover documentation (the "Rover Commands in Guided Mode"
developer page, the Rover mode list and the parameter list) and the MAVLink common/ardupilotmega message
set; it is written from those descriptions with pymavlink, not from ArduPilot's sources:

- HEARTBEAT at 1 Hz: ``MAV_TYPE_SURFACE_BOAT``, ``MAV_AUTOPILOT_ARDUPILOTMEGA``, Rover's custom modes
  MANUAL 0, HOLD 4, LOITER 5, AUTO 10, GUIDED 15 in ``custom_mode``, ``MAV_MODE_FLAG_SAFETY_ARMED`` when
  armed. Arming is the operator's: the simulator starts armed or disarmed as told and answers
  ``MAV_CMD_COMPONENT_ARM_DISARM`` with ``MAV_RESULT_DENIED`` (and records that it came).
- Mode changes by ``COMMAND_LONG``/``COMMAND_INT`` ``MAV_CMD_DO_SET_MODE`` (param2 = custom mode) or the
  ``SET_MODE`` message, each answered by ``COMMAND_ACK`` (for ``SET_MODE`` with ``command = 11``, the
  message id, as ArduPilot does). Entering AUTO without a mission fails (``MAV_RESULT_FAILED`` and the
  notice "No Mission. Can't set AUTO."); ``MAV_CMD_MISSION_START`` enters AUTO (at item param1 if given).
- GUIDED: ``SET_POSITION_TARGET_GLOBAL_INT`` (frames ``GLOBAL_INT``, ``GLOBAL_RELATIVE_ALT_INT``,
  ``GLOBAL_TERRAIN_ALT_INT``; position bits of ``type_mask`` not ignored) and ``MISSION_ITEM_INT`` with
  ``current = 2`` set the destination; ignored in other modes, as documented. The accepted target is
  echoed in ``POSITION_TARGET_GLOBAL_INT`` at 2 Hz. At the destination a boat loiters (holds station).
- Missions (MAVLink mission protocol, mission type 0): upload ``MISSION_COUNT`` -> ``MISSION_REQUEST_INT``
  per item (re-requested after a timeout) -> ``MISSION_ITEM_INT`` -> ``MISSION_ACK``; download
  ``MISSION_REQUEST_LIST``; ``MISSION_CLEAR_ALL``; ``MISSION_SET_CURRENT``. Item 0 is home (ArduPilot
  overwrites it and starts AUTO at item 1). In AUTO each ``MAV_CMD_NAV_WAYPOINT`` is driven to and
  ``MISSION_ITEM_REACHED`` sent within the waypoint radius; a ``MAV_CMD_NAV_DELAY`` stops the motors for
  ``param1`` seconds (the boat drifts, as in HOLD), then the mission goes on; other commands are skipped;
  ``MISSION_CURRENT`` at 1 Hz and on change. At the end of the mission the boat switches to HOLD
  (``MIS_DONE_BEHAVE = 0``, Hold).
- HOLD and MANUAL (no RC input here): no thrust; the boat slows and drifts with the current, as the Rover
  documentation warns boats do in Hold. LOITER holds station where it was entered.
- Telemetry at set rates (simulated time): GLOBAL_POSITION_INT 5 Hz, ATTITUDE 10 Hz, VFR_HUD 4 Hz,
  SYS_STATUS 1 Hz, SIM_STATE 5 Hz (the true state, as ArduPilot's SITL sends it), MISSION_CURRENT 1 Hz;
  ``MAV_CMD_SET_MESSAGE_INTERVAL`` changes them, ``MAV_CMD_REQUEST_MESSAGE`` and
  ``MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES`` answer AUTOPILOT_VERSION.

Motion (:func:`step_boat`): the defaults are those ArduPilot's SITL motorboat frame starts with (its
``rover.parm`` then ``motorboat.parm`` default-parameter files): ``CRUISE_SPEED`` 5 m/s, ``WP_RADIUS``
3 m, ``FRAME_CLASS`` 2 (boat). The turn rate is limited by ``ATC_STR_RAT_MAX`` (120 deg/s in the parameter
list) and by a lateral acceleration of ``ATC_TURN_MAX_G`` (0.6 g), whichever is smaller at the speed;
speed changes by at most ``ATC_ACCEL_MAX``. A uniform current adds to the velocity through the water.

The simulator runs in a thread, faster than real time by ``time_scale`` (telemetry rates are in
simulated time, as SITL's ``--speedup`` does), on a UDP or TCP endpoint on 127.0.0.1 only, and stops
cleanly. :meth:`BoatSimulator.truth` gives its true position to other simulators (acoustic beacons).
"""

from __future__ import annotations

import math
import threading
import time
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection
from oceanloc.io._mavlink import mavlink, mavutil
from oceanloc.units import GRAVITY_MPS2

MODE_MANUAL = 0
MODE_HOLD = 4
MODE_LOITER = 5
MODE_AUTO = 10
MODE_GUIDED = 15
ROVER_MODES: dict[int, str] = {
    MODE_MANUAL: "MANUAL",
    MODE_HOLD: "HOLD",
    MODE_LOITER: "LOITER",
    MODE_AUTO: "AUTO",
    MODE_GUIDED: "GUIDED",
}
"""The Rover custom modes (``HEARTBEAT.custom_mode``) this simulator implements, number -> name."""

_GLOBAL_FRAMES = (
    mavlink.MAV_FRAME_GLOBAL,
    mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    mavlink.MAV_FRAME_GLOBAL_INT,
    mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT,
    mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
)
_POSITION_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_X_IGNORE | mavlink.POSITION_TARGET_TYPEMASK_Y_IGNORE
_DEFAULT_RATES_HZ: dict[str, float] = {
    "HEARTBEAT": 1.0,
    "GLOBAL_POSITION_INT": 5.0,
    "ATTITUDE": 10.0,
    "VFR_HUD": 4.0,
    "SYS_STATUS": 1.0,
    "SIM_STATE": 5.0,
    "MISSION_CURRENT": 1.0,
    "POSITION_TARGET_GLOBAL_INT": 2.0,
}
_UPLOAD_RETRY_S = 0.4
_UPLOAD_RETRIES = 5


@dataclass(frozen=True, slots=True, kw_only=True)
class BoatParams:
    """The boat and its autopilot's tuning (ArduPilot parameter names in brackets).

    Attributes
    ----------
    cruise_speed_mps : float
        Speed through the water between waypoints [CRUISE_SPEED], 5 m/s in SITL's rover defaults.
    wp_radius_m : float
        A waypoint is reached within this distance [WP_RADIUS], 3 m in SITL's rover defaults.
    turn_rate_max_dps : float
        Turn-rate limit [ATC_STR_RAT_MAX], degrees per second.
    turn_max_g : float
        Lateral acceleration limit in g [ATC_TURN_MAX_G]; at speed v the turn rate is at most g*this/v.
    accel_max_mps2 : float
        Speed change limit [ATC_ACCEL_MAX], m/s^2.
    loiter_radius_m : float
        Holding station (GUIDED at its destination, LOITER, the last waypoint), the boat lets itself drift
        inside this radius and drives back when outside [LOIT_RADIUS, 2 m].
    heading_gain_per_s : float
        Commanded turn rate per radian of heading error (the steering controller's proportional gain).
    current_enu_mps : tuple of float
        Uniform water current (east, north), m/s, added to the velocity through the water.
    """

    cruise_speed_mps: float = 5.0
    wp_radius_m: float = 3.0
    turn_rate_max_dps: float = 120.0
    turn_max_g: float = 0.6
    accel_max_mps2: float = 2.0
    loiter_radius_m: float = 2.0
    heading_gain_per_s: float = 2.0
    current_enu_mps: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("cruise_speed_mps", "wp_radius_m", "turn_rate_max_dps", "turn_max_g", "accel_max_mps2"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"boat {name} must be a positive number, got {value}")
        if len(self.current_enu_mps) != 2 or not all(math.isfinite(c) for c in self.current_enu_mps):
            raise ConfigError(f"boat current_enu_mps must be two finite numbers, got {self.current_enu_mps}")


@dataclass(frozen=True, slots=True, kw_only=True)
class BoatState:
    """The boat's true kinematic state in the local frame about its start.

    Attributes
    ----------
    t_s : float
        Simulated time since start, seconds.
    east_m, north_m : float
        Position, metres east and north of the start.
    heading_rad : float
        Heading, clockwise from true north, radians in [0, 2 pi).
    speed_mps : float
        Speed through the water along the heading, m/s.
    yaw_rate_rps : float
        Turn rate, rad/s (positive clockwise).
    """

    t_s: float = 0.0
    east_m: float = 0.0
    north_m: float = 0.0
    heading_rad: float = 0.0
    speed_mps: float = 0.0
    yaw_rate_rps: float = 0.0


@dataclass(frozen=True, slots=True, kw_only=True)
class BoatTruth:
    """The true state in geodetic terms, for other simulators (an acoustic beacon's ranges).

    Attributes: ``t_s`` (simulated s), ``lat_deg``, ``lon_deg`` (WGS84), ``east_m``, ``north_m`` (about the
    start), ``heading_deg`` (clockwise from north), ``vel_enu_mps`` (velocity over ground, east and north),
    ``mode`` (Rover custom-mode number), ``armed``, ``mission_seq`` (current mission item).
    """

    t_s: float
    lat_deg: float
    lon_deg: float
    east_m: float
    north_m: float
    heading_deg: float
    vel_enu_mps: tuple[float, float]
    mode: int
    armed: bool
    mission_seq: int

    def to_record(self) -> dict:
        """Plain JSON-ready fields."""
        return {
            "t_s": self.t_s,
            "lat_deg": self.lat_deg,
            "lon_deg": self.lon_deg,
            "east_m": self.east_m,
            "north_m": self.north_m,
            "heading_deg": self.heading_deg,
            "vel_enu_mps": list(self.vel_enu_mps),
            "mode": ROVER_MODES.get(self.mode, str(self.mode)),
            "armed": self.armed,
            "mission_seq": self.mission_seq,
        }


def _wrap_pi(angle_rad: float) -> float:
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def step_boat(
    state: BoatState,
    target_en_m: tuple[float, float] | None,
    params: BoatParams,
    dt_s: float,
    *,
    stop_at_target: bool = True,
) -> BoatState:
    """Advance the boat by ``dt_s`` seconds towards ``target_en_m`` (east, north; None: no thrust).

    The steering asks for a turn rate proportional to the heading error towards the target, limited to
    ``min(turn_rate_max, turn_max_g * g / v)``; the speed command is the cruise speed times
    ``max(cos(heading error), 0.2)`` (slow while pointing away), and, when stopping at the target, at most
    ``sqrt(2 a d)`` (braking at ``accel_max`` over the distance ``d`` left). Speed follows the command at
    ``accel_max``. When stopping, inside ``loiter_radius`` there is no thrust (the boat coasts to a stop and
    drifts). The velocity over ground is the velocity through the water plus the current.
    """
    de = dn = dist = 0.0
    if target_en_m is not None:
        de = target_en_m[0] - state.east_m
        dn = target_en_m[1] - state.north_m
        dist = math.hypot(de, dn)
    if target_en_m is None or (stop_at_target and dist < params.loiter_radius_m):
        v_cmd, r_cmd = 0.0, 0.0
    else:
        err = _wrap_pi(math.atan2(de, dn) - state.heading_rad) if dist > 1e-9 else 0.0
        v_cmd = params.cruise_speed_mps * max(math.cos(err), 0.2)
        if stop_at_target:
            v_cmd = min(v_cmd, math.sqrt(2.0 * params.accel_max_mps2 * dist))
        r_cmd = params.heading_gain_per_s * err
    dv = float(np.clip(v_cmd - state.speed_mps, -params.accel_max_mps2 * dt_s, params.accel_max_mps2 * dt_s))
    speed = state.speed_mps + dv
    r_max = math.radians(params.turn_rate_max_dps)
    if speed > 1e-6:
        r_max = min(r_max, params.turn_max_g * GRAVITY_MPS2 / speed)
    r = float(np.clip(r_cmd, -r_max, r_max))
    heading = (state.heading_rad + r * dt_s) % (2.0 * math.pi)
    mid = state.heading_rad + 0.5 * r * dt_s
    v_mid = 0.5 * (state.speed_mps + speed)
    ce, cn = params.current_enu_mps
    return BoatState(
        t_s=state.t_s + dt_s,
        east_m=state.east_m + (v_mid * math.sin(mid) + ce) * dt_s,
        north_m=state.north_m + (v_mid * math.cos(mid) + cn) * dt_s,
        heading_rad=heading,
        speed_mps=speed,
        yaw_rate_rps=r,
    )


@dataclass(slots=True)
class _Upload:
    count: int
    items: list = field(default_factory=list)
    last_request_wall: float = 0.0
    retries: int = 0
    peer: tuple[int, int] = (255, 0)


class BoatSimulator:
    """The boat and its autopilot, in a thread, on a MAVLink endpoint on 127.0.0.1.

    Parameters
    ----------
    endpoint : str
        pymavlink connection string on loopback: ``udpout:127.0.0.1:PORT`` (send to a ground station
        listening there, as SITL's ``udpclient`` serial option does), ``udpin:127.0.0.1:PORT`` or
        ``tcpin:127.0.0.1:PORT``.
    start_lat_deg, start_lon_deg : float
        Start position; the local frame's origin.
    params : BoatParams
    time_scale : float
        Simulated seconds per wall-clock second.
    step_s : float
        Integration step, simulated seconds.
    armed : bool
        Whether the operator armed the boat (a disarmed boat does not move under its own power).
    heading_deg : float
        Initial heading, clockwise from north.
    gps_noise_m : float
        Standard deviation of the reported horizontal position's noise per axis, metres (0: exact).
    seed : int
        Seed of the position noise.
    ignore_items_once : frozenset of int
        Mission item sequence numbers whose first arrival is dropped (tests the sender's retries).
    request_retry_s : float
        During an upload, re-request the expected item after this many wall-clock seconds without it.
    rates_hz : mapping of str to float, optional
        Telemetry rates to change from the defaults, by message name (0 stops a message).
    fs_gcs_enable : bool
        The GCS failsafe [FS_GCS_ENABLE, off by default]: once a ground station's heartbeat has been heard,
        none for ``fs_timeout_s`` of simulated time while in GUIDED, AUTO or LOITER switches to HOLD
        [FS_ACTION 2] with a warning. Heartbeats come at wall-clock rates: at a time scale k the ground
        station's interval counts k times over, so ``fs_timeout_s`` must exceed k / its heartbeat rate.
    fs_timeout_s : float
        [FS_TIMEOUT], simulated seconds (1.5 in the Rover parameter list).
    sysid : int
        MAVLink system id (the component is ``MAV_COMP_ID_AUTOPILOT1``).
    """

    def __init__(
        self,
        endpoint: str,
        *,
        start_lat_deg: float = 32.70,
        start_lon_deg: float = -117.25,
        params: BoatParams | None = None,
        time_scale: float = 10.0,
        step_s: float = 0.05,
        armed: bool = True,
        heading_deg: float = 0.0,
        gps_noise_m: float = 0.0,
        seed: int = 0,
        ignore_items_once: frozenset[int] = frozenset(),
        request_retry_s: float = _UPLOAD_RETRY_S,
        rates_hz: Mapping[str, float] | None = None,
        fs_gcs_enable: bool = False,
        fs_timeout_s: float = 1.5,
        sysid: int = 1,
    ) -> None:
        _check_loopback(endpoint)
        if not (math.isfinite(time_scale) and time_scale > 0.0):
            raise ConfigError(f"time_scale must be a positive number, got {time_scale}")
        if not (math.isfinite(step_s) and 0.0 < step_s <= 0.5):
            raise ConfigError(f"step_s must be within (0, 0.5] s, got {step_s}")
        self.endpoint = endpoint
        self.params = params or BoatParams()
        self.time_scale = float(time_scale)
        self.step_s = float(step_s)
        self.sysid = int(sysid)
        self._proj = LocalProjection(lat0_deg=start_lat_deg, lon0_deg=start_lon_deg)
        self._state = BoatState(heading_rad=math.radians(heading_deg) % (2.0 * math.pi))
        self._armed = bool(armed)
        self._mode = MODE_HOLD
        self._target: tuple[float, float] | None = None
        self._mission: list = []
        self._mission_seq = 0
        self._delay_until: float | None = None
        self._upload: _Upload | None = None
        self._ignore_once = set(ignore_items_once)
        self._request_retry_s = float(request_retry_s)
        self._pending_text = ""
        self._fs_gcs_enable = bool(fs_gcs_enable)
        self._fs_timeout_s = float(fs_timeout_s)
        self._last_gcs_heartbeat_s: float | None = None
        self._failsafe_active = False
        self.failsafe_times_s: list[float] = []
        """Simulated times at which the GCS failsafe switched the boat to HOLD."""
        self._rng = np.random.default_rng(seed)
        self._gps_noise_m = float(gps_noise_m)
        unknown = sorted(set(rates_hz or {}) - set(_DEFAULT_RATES_HZ))
        if unknown:
            raise ConfigError(f"no telemetry rate for {unknown[0]}: one of {', '.join(_DEFAULT_RATES_HZ)}")
        self._rates_hz = {**_DEFAULT_RATES_HZ, **(rates_hz or {})}
        self._next_send_s: dict[str, float] = dict.fromkeys(self._rates_hz, 0.0)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._link_cut = threading.Event()
        self._thread: threading.Thread | None = None
        self._conn = None
        self.received: Counter[str] = Counter()
        """Number of messages received, by MAVLink message name."""
        self.commands: list[int] = []
        """Every ``COMMAND_LONG``/``COMMAND_INT`` command id received, in order."""
        self.reached: list[int] = []
        """Mission sequence numbers reached in AUTO, in order."""
        self.error: BaseException | None = None
        """The exception that ended the thread, if one did."""

    # -- life cycle -------------------------------------------------------------------------------

    def start(self) -> BoatSimulator:
        """Open the endpoint and start the thread; returns self."""
        if self._thread is not None:
            raise RuntimeError("the boat simulator is already running")
        self._conn = mavutil.mavlink_connection(
            self.endpoint,
            source_system=self.sysid,
            source_component=mavlink.MAV_COMP_ID_AUTOPILOT1,
            dialect="ardupilotmega",
        )
        self._thread = threading.Thread(target=self._run, name="boat-simulator", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout_s: float = 2.0) -> None:
        """Stop the thread and close the endpoint (idempotent)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
        if self._conn is not None:
            self._conn.close()
            self._conn = None

    def __enter__(self) -> BoatSimulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def set_params(self, **changes: object) -> None:
        """Change the boat's parameters while it runs (e.g. ``current_enu_mps``), thread-safely."""
        with self._lock:
            self.params = replace(self.params, **changes)

    def cut_link(self, cut: bool = True) -> None:
        """Drop (or restore) all traffic both ways while the boat keeps moving: a radio link lost."""
        if cut:
            self._link_cut.set()
        else:
            self._link_cut.clear()

    # -- what other simulators and tests read -----------------------------------------------------

    def truth(self) -> BoatTruth:
        """The true state now (thread-safe)."""
        with self._lock:
            s, mode, armed, seq = self._state, self._mode, self._armed, self._mission_seq
        return self._truth_of(s, mode, armed, seq)

    @property
    def mode(self) -> int:
        """Current Rover custom mode."""
        with self._lock:
            return self._mode

    @property
    def target_en_m(self) -> tuple[float, float] | None:
        """Where the autopilot is steering (east, north metres about the start), None when it is not."""
        with self._lock:
            return self._target

    @property
    def mission(self) -> list:
        """The stored mission's MISSION_ITEM_INT messages (item 0 is home)."""
        with self._lock:
            return list(self._mission)

    def _truth_of(self, s: BoatState, mode: int, armed: bool, seq: int) -> BoatTruth:
        lon, lat = self._proj.to_lonlat(s.east_m, s.north_m)
        ce, cn = self.params.current_enu_mps
        return BoatTruth(
            t_s=s.t_s,
            lat_deg=float(lat),
            lon_deg=float(lon),
            east_m=s.east_m,
            north_m=s.north_m,
            heading_deg=math.degrees(s.heading_rad),
            vel_enu_mps=(
                s.speed_mps * math.sin(s.heading_rad) + ce,
                s.speed_mps * math.cos(s.heading_rad) + cn,
            ),
            mode=mode,
            armed=armed,
            mission_seq=seq,
        )

    # -- the thread -------------------------------------------------------------------------------

    def _run(self) -> None:
        wall0 = time.monotonic()
        try:
            while not self._stop.is_set():
                self._receive_all()
                sim_due = (time.monotonic() - wall0) * self.time_scale
                while self._state.t_s + self.step_s <= sim_due and not self._stop.is_set():
                    self._step()
                    self._send_due()
                self._retry_upload()
                time.sleep(min(0.002, self.step_s / self.time_scale))
        except Exception as exc:  # kept for the test to see; the thread ends
            self.error = exc

    def _step(self) -> None:
        self._check_gcs_failsafe()
        with self._lock:
            armed, mode = self._armed, self._mode
            target = self._target if armed and mode in (MODE_GUIDED, MODE_AUTO, MODE_LOITER) else None
            stop_at = not (mode == MODE_AUTO and self._mission_seq < len(self._mission) - 1)
            self._state = step_boat(self._state, target, self.params, self.step_s, stop_at_target=stop_at)
            if mode == MODE_AUTO and target is not None:
                dist = math.hypot(target[0] - self._state.east_m, target[1] - self._state.north_m)
                if dist <= self.params.wp_radius_m:
                    self._advance_mission_locked()
            elif mode == MODE_AUTO and self._delay_until is not None and self._state.t_s >= self._delay_until:
                self._advance_mission_locked()

    # -- sending ----------------------------------------------------------------------------------

    def _time_boot_ms(self) -> int:
        return int(self._state.t_s * 1000.0) & 0xFFFFFFFF

    def _send_due(self) -> None:
        t = self._state.t_s
        for name, rate in self._rates_hz.items():
            if rate > 0.0 and t >= self._next_send_s[name]:
                self._next_send_s[name] = t + 1.0 / rate
                self._send(name)

    def _send(self, name: str) -> None:
        if self._link_cut.is_set() or self._conn is None:
            return
        with self._lock:
            s, mode, armed, seq, target = (
                self._state,
                self._mode,
                self._armed,
                self._mission_seq,
                self._target,
            )
            n_items = len(self._mission)
        mav = self._conn.mav
        if name == "HEARTBEAT":
            base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            if armed:
                base |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
            if mode in (MODE_GUIDED, MODE_AUTO, MODE_LOITER):
                base |= mavlink.MAV_MODE_FLAG_GUIDED_ENABLED | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
            if mode == MODE_AUTO:
                base |= mavlink.MAV_MODE_FLAG_AUTO_ENABLED
            status = mavlink.MAV_STATE_ACTIVE if armed else mavlink.MAV_STATE_STANDBY
            mav.heartbeat_send(
                mavlink.MAV_TYPE_SURFACE_BOAT, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, base, mode, status
            )
            return
        ce, cn = self.params.current_enu_mps
        ve = s.speed_mps * math.sin(s.heading_rad) + ce
        vn = s.speed_mps * math.cos(s.heading_rad) + cn
        heading_deg = math.degrees(s.heading_rad)
        if name in ("GLOBAL_POSITION_INT", "SIM_STATE"):
            truth = self._truth_of(s, mode, armed, seq)
        if name == "GLOBAL_POSITION_INT":
            lat, lon = truth.lat_deg, truth.lon_deg
            if self._gps_noise_m > 0.0:
                de, dn = self._rng.normal(0.0, self._gps_noise_m, 2)
                lon_n, lat_n = self._proj.to_lonlat(s.east_m + de, s.north_m + dn)
                lat, lon = float(lat_n), float(lon_n)
            mav.global_position_int_send(
                self._time_boot_ms(),
                round(lat * 1e7),
                round(lon * 1e7),
                0,
                0,
                round(vn * 100.0),
                round(ve * 100.0),
                0,
                round(heading_deg * 100.0) % 36000,
            )
        elif name == "ATTITUDE":
            mav.attitude_send(
                self._time_boot_ms(), 0.0, 0.0, _wrap_pi(s.heading_rad), 0.0, 0.0, s.yaw_rate_rps
            )
        elif name == "VFR_HUD":
            mav.vfr_hud_send(
                s.speed_mps, math.hypot(ve, vn), round(heading_deg) % 360,
                round(100.0 * s.speed_mps / (1.5 * self.params.cruise_speed_mps)), 0.0, 0.0,
            )  # fmt: skip
        elif name == "SYS_STATUS":
            sensors = (
                mavlink.MAV_SYS_STATUS_SENSOR_3D_GYRO
                | mavlink.MAV_SYS_STATUS_SENSOR_3D_MAG
                | mavlink.MAV_SYS_STATUS_SENSOR_GPS
            )
            mav.sys_status_send(sensors, sensors, sensors, 100, 16_000, 500, 90, 0, 0, 0, 0, 0, 0)
        elif name == "SIM_STATE":
            mav.sim_state_send(
                1.0, 0.0, 0.0, 0.0, 0.0, 0.0, _wrap_pi(s.heading_rad), 0.0, 0.0, -GRAVITY_MPS2,
                0.0, 0.0, s.yaw_rate_rps, truth.lat_deg, truth.lon_deg, 0.0, 0.0, 0.0, vn, ve, 0.0,
                round(truth.lat_deg * 1e7), round(truth.lon_deg * 1e7),
            )  # fmt: skip
        elif name == "MISSION_CURRENT":
            if mode == MODE_AUTO:
                state = mavlink.MISSION_STATE_ACTIVE
            elif n_items > 1 and seq >= n_items:
                state = mavlink.MISSION_STATE_COMPLETE
            elif n_items > 1:
                state = mavlink.MISSION_STATE_NOT_STARTED
            else:
                state = mavlink.MISSION_STATE_NO_MISSION
            mav.mission_current_send(min(seq, max(n_items - 1, 0)), max(n_items - 1, 0), state)
        elif name == "POSITION_TARGET_GLOBAL_INT" and mode == MODE_GUIDED and target is not None:
            lon_t, lat_t = self._proj.to_lonlat(*target)
            mav.position_target_global_int_send(
                self._time_boot_ms(), mavlink.MAV_FRAME_GLOBAL_INT, 0xFFF & ~_POSITION_IGNORE,
                round(float(lat_t) * 1e7), round(float(lon_t) * 1e7), 0.0,
                0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            )  # fmt: skip

    def _ack(self, command: int, result: int, msg) -> None:
        if self._link_cut.is_set() or self._conn is None:
            return
        self._conn.mav.command_ack_send(command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent())

    def _statustext(self, text: str, severity: int = mavlink.MAV_SEVERITY_INFO) -> None:
        if not self._link_cut.is_set() and self._conn is not None:
            self._conn.mav.statustext_send(severity, text.encode()[:50])

    # -- receiving --------------------------------------------------------------------------------

    def _receive_all(self) -> None:
        conn = self._conn
        if conn is None:
            return
        while True:
            msg = conn.recv_match(blocking=False)
            if msg is None:
                return
            if self._link_cut.is_set():
                continue
            name = msg.get_type()
            if name == "BAD_DATA":
                continue
            self.received[name] += 1
            target = getattr(msg, "target_system", 0)
            if target not in (0, self.sysid):
                continue
            handler = getattr(self, f"_on_{name.lower()}", None)
            if handler is not None:
                handler(msg)

    def _on_command_long(self, msg) -> None:
        self._command(msg, msg.command, (msg.param1, msg.param2, msg.param3, msg.param4))

    def _on_command_int(self, msg) -> None:
        self._command(msg, msg.command, (msg.param1, msg.param2, msg.param3, msg.param4))

    def _command(self, msg, command: int, p: tuple[float, ...]) -> None:
        self.commands.append(int(command))
        if command == mavlink.MAV_CMD_DO_SET_MODE:
            self._ack(command, self._set_mode(int(p[1])), msg)
        elif command == mavlink.MAV_CMD_MISSION_START:
            with self._lock:
                if 0 < int(p[0]) < len(self._mission):
                    self._mission_seq = int(p[0])
            self._ack(command, self._set_mode(MODE_AUTO), msg)
        elif command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            self._statustext("Arming is the operator's: command refused", mavlink.MAV_SEVERITY_WARNING)
            self._ack(command, mavlink.MAV_RESULT_DENIED, msg)
        elif command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
            entry = mavlink.mavlink_map.get(int(p[0]))
            name = entry.msgname if entry is not None else None
            if name in self._rates_hz:
                interval_us = p[1]
                if interval_us == 0:
                    self._rates_hz[name] = _DEFAULT_RATES_HZ[name]
                else:
                    self._rates_hz[name] = 0.0 if interval_us < 0 else 1e6 / interval_us
                self._ack(command, mavlink.MAV_RESULT_ACCEPTED, msg)
            else:
                self._ack(command, mavlink.MAV_RESULT_UNSUPPORTED, msg)
        elif command in (mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES):
            wanted = int(p[0]) if command == mavlink.MAV_CMD_REQUEST_MESSAGE else 148
            entry = mavlink.mavlink_map.get(wanted)
            name = entry.msgname if entry is not None else ""
            if wanted == mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION:
                self._ack(command, mavlink.MAV_RESULT_ACCEPTED, msg)
                self._send_autopilot_version()
            elif name in self._rates_hz:
                self._ack(command, mavlink.MAV_RESULT_ACCEPTED, msg)
                self._send(name)
            else:
                self._ack(command, mavlink.MAV_RESULT_UNSUPPORTED, msg)
        else:
            self._ack(command, mavlink.MAV_RESULT_UNSUPPORTED, msg)

    def _send_autopilot_version(self) -> None:
        if self._link_cut.is_set() or self._conn is None:
            return
        caps = (
            mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_INT
            | mavlink.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
            | mavlink.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT
            | mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
        )
        self._conn.mav.autopilot_version_send(
            caps, 4 << 24 | 6 << 16, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, self.sysid
        )

    def _on_heartbeat(self, msg) -> None:
        if msg.type == mavlink.MAV_TYPE_GCS:
            self._last_gcs_heartbeat_s = self._state.t_s
            self._failsafe_active = False

    def _check_gcs_failsafe(self) -> None:
        last = self._last_gcs_heartbeat_s
        if not self._fs_gcs_enable or last is None or self._failsafe_active:
            return
        if self._state.t_s - last <= self._fs_timeout_s:
            return
        self._failsafe_active = True
        with self._lock:
            autonomous = self._mode in (MODE_GUIDED, MODE_AUTO, MODE_LOITER)
        if autonomous:
            self.failsafe_times_s.append(self._state.t_s)
            self._set_mode(MODE_HOLD)
            self._statustext("Failsafe: GCS heartbeat lost, Hold", mavlink.MAV_SEVERITY_WARNING)

    def _on_set_mode(self, msg) -> None:
        if msg.base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            result = self._set_mode(int(msg.custom_mode))
        else:
            result = mavlink.MAV_RESULT_UNSUPPORTED
        self._ack(mavlink.MAVLINK_MSG_ID_SET_MODE, result, msg)

    def _set_mode(self, mode: int) -> int:
        result = self._set_mode_locked(mode)
        if self._pending_text:
            self._statustext(self._pending_text, mavlink.MAV_SEVERITY_NOTICE)
            self._pending_text = ""
        return result

    def _set_mode_locked(self, mode: int) -> int:
        with self._lock:
            if mode not in ROVER_MODES:
                return mavlink.MAV_RESULT_FAILED
            if mode == MODE_AUTO:
                if len(self._mission) < 2:
                    self._pending_text = "No Mission. Can't set AUTO."
                    return mavlink.MAV_RESULT_FAILED
                if self._mission_seq < 1 or self._mission_seq >= len(self._mission):
                    self._mission_seq = 1
                self._target_from_mission_locked()
            elif mode in (MODE_GUIDED, MODE_LOITER):
                # entering GUIDED stops the boat where it is until a destination comes (as documented)
                self._target = (self._state.east_m, self._state.north_m)
            else:
                self._target = None
            changed = mode != self._mode
            self._mode = mode
        if changed:
            self._statustext(f"Mode {ROVER_MODES[mode]}")
            self._next_send_s["HEARTBEAT"] = 0.0
        return mavlink.MAV_RESULT_ACCEPTED

    def _on_set_position_target_global_int(self, msg) -> None:
        with self._lock:
            if self._mode != MODE_GUIDED:
                return
            if msg.coordinate_frame not in _GLOBAL_FRAMES or msg.type_mask & _POSITION_IGNORE:
                return
            self._target = self._local(msg.lat_int * 1e-7, msg.lon_int * 1e-7)
        self._next_send_s["POSITION_TARGET_GLOBAL_INT"] = 0.0

    def _local(self, lat_deg: float, lon_deg: float) -> tuple[float, float]:
        e, n = self._proj.to_local(lon_deg, lat_deg)
        return float(e), float(n)

    # mission protocol ----------------------------------------------------------------------------------

    def _on_mission_count(self, msg) -> None:
        if getattr(msg, "mission_type", 0) != mavlink.MAV_MISSION_TYPE_MISSION:
            self._mission_ack(msg, mavlink.MAV_MISSION_UNSUPPORTED)
            return
        if msg.count == 0:
            with self._lock:
                self._mission, self._mission_seq = [], 0
            self._mission_ack(msg, mavlink.MAV_MISSION_ACCEPTED)
            return
        self._upload = _Upload(count=int(msg.count), peer=(msg.get_srcSystem(), msg.get_srcComponent()))
        self._request_item()

    def _request_item(self) -> None:
        up = self._upload
        if up is None or self._link_cut.is_set() or self._conn is None:
            return
        up.last_request_wall = time.monotonic()
        self._conn.mav.mission_request_int_send(up.peer[0], up.peer[1], len(up.items))

    def _retry_upload(self) -> None:
        up = self._upload
        if up is None or time.monotonic() - up.last_request_wall < self._request_retry_s:
            return
        if up.retries >= _UPLOAD_RETRIES:
            self._upload = None
            if self._conn is not None and not self._link_cut.is_set():
                self._conn.mav.mission_ack_send(
                    up.peer[0], up.peer[1], mavlink.MAV_MISSION_OPERATION_CANCELLED
                )
            return
        up.retries += 1
        self._request_item()

    def _on_mission_item_int(self, msg) -> None:
        if msg.current == 2:  # a guided-mode "go to" in the form of a mission item
            with self._lock:
                accepted = self._mode == MODE_GUIDED and msg.frame in _GLOBAL_FRAMES
                if accepted:
                    self._target = self._local(msg.x * 1e-7, msg.y * 1e-7)
            self._mission_ack(msg, mavlink.MAV_MISSION_ACCEPTED if accepted else mavlink.MAV_MISSION_ERROR)
            return
        up = self._upload
        if up is None:
            return
        if msg.seq in self._ignore_once:
            self._ignore_once.discard(msg.seq)
            return
        if msg.seq != len(up.items):  # out of sequence: ask again for the one expected
            self._request_item()
            return
        if msg.frame not in (*_GLOBAL_FRAMES, mavlink.MAV_FRAME_MISSION):
            self._upload = None
            self._mission_ack(msg, mavlink.MAV_MISSION_UNSUPPORTED_FRAME)
            return
        up.items.append(msg)
        up.retries = 0
        if len(up.items) < up.count:
            self._request_item()
            return
        self._upload = None
        with self._lock:
            self._mission = list(up.items)
            self._mission_seq = 1 if len(self._mission) > 1 else 0
            if self._mode == MODE_AUTO:
                self._target_from_mission_locked()
        self._mission_ack(msg, mavlink.MAV_MISSION_ACCEPTED)

    def _mission_ack(self, msg, result: int) -> None:
        if not self._link_cut.is_set() and self._conn is not None:
            self._conn.mav.mission_ack_send(msg.get_srcSystem(), msg.get_srcComponent(), result, 0)

    def _on_mission_request_list(self, msg) -> None:
        if self._conn is not None:
            self._conn.mav.mission_count_send(
                msg.get_srcSystem(),
                msg.get_srcComponent(),
                len(self._mission),
                getattr(msg, "mission_type", 0),
            )

    def _on_mission_request_int(self, msg) -> None:
        with self._lock:
            items = list(self._mission)
        if self._conn is None or not 0 <= msg.seq < len(items):
            return
        it = items[msg.seq]
        self._conn.mav.mission_item_int_send(
            msg.get_srcSystem(), msg.get_srcComponent(), it.seq, it.frame, it.command,
            int(it.seq == self._mission_seq), it.autocontinue, it.param1, it.param2, it.param3, it.param4,
            it.x, it.y, it.z, 0,
        )  # fmt: skip

    _on_mission_request = _on_mission_request_int

    def _on_mission_clear_all(self, msg) -> None:
        with self._lock:
            self._mission, self._mission_seq = [], 0
            if self._mode == MODE_AUTO:
                self._mode, self._target = MODE_HOLD, None
        self._mission_ack(msg, mavlink.MAV_MISSION_ACCEPTED)

    def _on_mission_set_current(self, msg) -> None:
        with self._lock:
            if 0 < msg.seq < len(self._mission):
                self._mission_seq = int(msg.seq)
                if self._mode == MODE_AUTO:
                    self._target_from_mission_locked()
        self._next_send_s["MISSION_CURRENT"] = 0.0

    def _target_from_mission_locked(self) -> None:
        """Skip non-navigation items; set the target to the current waypoint (or finish the mission)."""
        self._delay_until = None
        while self._mission_seq < len(self._mission):
            it = self._mission[self._mission_seq]
            if it.command == mavlink.MAV_CMD_NAV_WAYPOINT:
                self._target = self._local(it.x * 1e-7, it.y * 1e-7)
                return
            if it.command == mavlink.MAV_CMD_NAV_DELAY and it.param1 >= 0:
                # Rover's NAV_DELAY: stop (a boat drifts) for param1 seconds, then go on.
                self._target = None
                self._delay_until = self._state.t_s + float(it.param1)
                return
            self._mission_seq += 1
        self._finish_mission_locked()

    def _advance_mission_locked(self) -> None:
        seq = self._mission_seq
        self.reached.append(seq)
        if self._conn is not None and not self._link_cut.is_set():
            self._conn.mav.mission_item_reached_send(seq)
        self._mission_seq += 1
        self._next_send_s["MISSION_CURRENT"] = 0.0
        self._target_from_mission_locked()

    def _finish_mission_locked(self) -> None:
        self._mode, self._target = MODE_HOLD, None
        self._next_send_s["HEARTBEAT"] = 0.0


def _check_loopback(endpoint: str) -> None:
    kinds = ("udpout:", "udpin:", "tcpin:")
    if not endpoint.startswith(kinds):
        raise ConfigError(
            f"boat simulator endpoint {endpoint!r}: expected one of {', '.join(kinds)}HOST:PORT"
        )
    host_port = endpoint.split(":", 1)[1]
    host, _, port = host_port.rpartition(":")
    if host != "127.0.0.1":
        raise ConfigError(f"boat simulator endpoint {endpoint!r}: the simulator only talks on 127.0.0.1")
    if not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(f"boat simulator endpoint {endpoint!r}: port must be 1..65535")
