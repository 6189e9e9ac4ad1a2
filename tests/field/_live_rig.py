"""A survey boat on loopback for the live-survey tests: the boat simulator (ArduPilot Rover's MAVLink
dialect), the real gpsd fed the boat's NMEA through a pseudo-terminal, and the SeaTrac beacon simulator
answering pings from hidden transponders, all faster than real time by ``time_scale``.

Times: every simulator runs ``time_scale`` times faster than the wall clock, and every record carries
the host's wall-clock time (the NMEA the feeder writes is stamped with it; the SeaTrac pinger stamps
ranges with it), so the journal's seconds are wall seconds and the boat covers ``time_scale`` times
its cruise speed per journal second.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import tty
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pynmea2
import pytest

from oceanloc.geo.projection import LocalProjection
from oceanloc.models.measurements import range_jacobian
from oceanloc.sim.boat import BoatParams, BoatSimulator
from oceanloc.sim.seatrac_beacon import BeaconSimConfig, SeatracBeaconSimulator

LOOPBACK = "127.0.0.1"
LAT0, LON0 = 32.70, -117.25
NEEDS_GPSD = pytest.mark.skipif(
    shutil.which("gpsd") is None, reason="gpsd is not installed (apt-get install gpsd gpsd-clients)"
)


def free_port(kind: int = socket.SOCK_DGRAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind((LOOPBACK, 0))
        return s.getsockname()[1]


def _minutes(value: float, width: int) -> str:
    """Degrees as NMEA's DDMM.MMMMMMM (7 decimals of minutes, 2 mm: an RTK receiver's output)."""
    a = abs(value)
    return f"{int(a):0{width}d}{(a % 1) * 60:010.7f}"


def gga(t: dt.datetime, lat: float, lon: float, h: float) -> str:
    fields = (
        t.strftime("%H%M%S.%f")[:9], _minutes(lat, 2), "N" if lat >= 0 else "S", _minutes(lon, 3),
        "E" if lon >= 0 else "W", "4", "12", "0.7", f"{h:.3f}", "M", "0.0", "M", "", "",
    )  # fmt: skip
    return str(pynmea2.GGA("GP", "GGA", fields))


class NmeaFeeder(threading.Thread):
    """Writes the boat's true position (GGA), heading (HDT) and date (ZDA) into gpsd's pty, 10 Hz wall."""

    def __init__(
        self, fd: int, boat: BoatSimulator, proj: LocalProjection, noise_m: float, seed: int
    ) -> None:
        super().__init__(daemon=True, name="nmea-feeder")
        self.fd, self.boat, self.proj = fd, boat, proj
        self.noise_m = noise_m
        self.rng = np.random.default_rng(seed)
        self.stop = threading.Event()

    def run(self) -> None:
        while not self.stop.is_set():
            truth = self.boat.truth()
            now = time.time()
            # NMEA carries centiseconds: stamp the fix at the centisecond and move the position there
            t_stamp = math.floor(now * 100.0) / 100.0
            t = dt.datetime.fromtimestamp(t_stamp, dt.UTC)
            back = (now - t_stamp) * self.boat.time_scale  # simulated seconds
            e = truth.east_m - truth.vel_enu_mps[0] * back
            n = truth.north_m - truth.vel_enu_mps[1] * back
            if self.noise_m:
                e, n = np.array([e, n]) + self.rng.normal(0.0, self.noise_m, 2)
            lon, lat = self.proj.to_lonlat(e, n)
            lines = [
                gga(t, float(lat), float(lon), 0.0),
                str(pynmea2.HDT("GP", "HDT", (f"{truth.heading_deg % 360.0:.1f}", "T"))),
                str(pynmea2.ZDA("GP", "ZDA", (t.strftime("%H%M%S.%f")[:9], f"{t.day:02d}", f"{t.month:02d}",
                                              f"{t.year:04d}", "00", "00"))),
            ]  # fmt: skip
            try:
                os.write(self.fd, ("\r\n".join(lines) + "\r\n").encode())
            except OSError:
                return
            self.stop.wait(0.1)


SITL_ENV = "OCEANLOC_SITL"
SITL_PARAMS = """FRAME_CLASS 2
CRUISE_SPEED 5
WP_RADIUS 3
ARMING_REQUIRE 0
ARMING_CHECK 0
FS_GCS_ENABLE 1
FS_ACTION 2
FS_TIMEOUT 5
SR1_POSITION 20
SR1_EXTRA1 20
"""


@dataclass(frozen=True)
class SitlTruth:
    """What the rig needs of the boat's state, from SITL's second serial port."""

    east_m: float
    north_m: float
    heading_deg: float
    vel_enu_mps: tuple[float, float]


class SitlBoat:
    """ArduPilot SITL's ``motorboat`` as the rig's boat (``OCEANLOC_SITL`` names an ``ardurover`` binary).

    oceanloc gets SITL's serial0 (``udpclient`` to the rig's vehicle port); the rig reads serial1 for the
    boat's position (GLOBAL_POSITION_INT at 20 Hz, from SITL's simulated GPS and EKF), from which the
    beacon simulator's ranges and gpsd's NMEA are made, and its mode (HEARTBEAT). SITL boots in MANUAL;
    the rig, as the operator, switches it to HOLD once its EKF is ready, before the survey starts.
    """

    def __init__(self, binary: str, folder: Path, vehicle_port: int, time_scale: float) -> None:
        from oceanloc.io._mavlink import mavutil

        self.time_scale = time_scale
        self.proj = LocalProjection(lat0_deg=LAT0, lon0_deg=LON0)
        truth_port = free_port()
        params = folder / "oceanloc-boat.parm"
        params.write_text(SITL_PARAMS)
        self._log = (folder / "sitl.log").open("w")
        self.proc = subprocess.Popen(
            [binary, "-w", "--model", "motorboat", "--speedup", f"{time_scale:g}", "--home",
             f"{LAT0},{LON0},0,0", "--defaults", str(params),
             "--serial0", f"udpclient:{LOOPBACK}:{vehicle_port}",
             "--serial1", f"udpclient:{LOOPBACK}:{truth_port}"],
            cwd=folder, stdout=self._log, stderr=subprocess.STDOUT,
        )  # fmt: skip
        self.conn = mavutil.mavlink_connection(f"udpin:{LOOPBACK}:{truth_port}", dialect="ardupilotmega")
        self._truth = SitlTruth(east_m=0.0, north_m=0.0, heading_deg=0.0, vel_enu_mps=(0.0, 0.0))
        self._mode = -1
        self._have_fix = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="sitl-truth")
        self._thread.start()
        self.received: dict[str, int] = {}

    def _run(self) -> None:
        while not self._stop.is_set():
            msg = self.conn.recv_match(type=["GLOBAL_POSITION_INT", "HEARTBEAT"], blocking=True, timeout=0.2)
            if msg is None:
                continue
            if msg.get_type() == "HEARTBEAT" and msg.get_srcComponent() == 1:
                self._mode = int(msg.custom_mode)
            elif msg.get_type() == "GLOBAL_POSITION_INT":
                e, n = self.proj.to_local(msg.lon / 1e7, msg.lat / 1e7)
                hdg = msg.hdg / 100.0 if msg.hdg != 65535 else self._truth.heading_deg
                self._truth = SitlTruth(east_m=float(e), north_m=float(n), heading_deg=hdg,
                                        vel_enu_mps=(msg.vy / 100.0, msg.vx / 100.0))  # fmt: skip
                self._have_fix.set()

    def ready(self, timeout_s: float = 90.0) -> None:
        """Wait for SITL's position, then put it in HOLD (asked until its EKF accepts)."""
        if not self._have_fix.wait(timeout_s):
            pytest.fail("SITL gave no position (see sitl.log)")
        deadline = time.monotonic() + timeout_s
        while self._mode != 4 and time.monotonic() < deadline:
            self.conn.set_mode(4)
            time.sleep(1.0)
        if self._mode != 4:
            pytest.fail("SITL did not take HOLD (see sitl.log)")

    def truth(self) -> SitlTruth:
        return self._truth

    @property
    def mode(self) -> int:
        return self._mode

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2.0)
        self.conn.close()
        self.proc.terminate()
        try:
            self.proc.wait(5.0)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        self._log.close()


@dataclass
class Rig:
    """The running simulators and the specs oceanloc connects to."""

    boat: BoatSimulator | SitlBoat
    beacons: SeatracBeaconSimulator
    proj: LocalProjection
    vehicle_spec: str
    position_spec: str
    ranges_spec: str
    transponders_enu_m: dict[int, tuple[float, float, float]]
    time_scale: float

    def truth_enu(self) -> np.ndarray:
        t = self.boat.truth()
        return np.array([t.east_m, t.north_m, 0.0])


@contextlib.contextmanager
def live_rig(
    transponders_enu_m: dict[int, tuple[float, float, float]],
    *,
    time_scale: float = 10.0,
    sigma_range_m: float = 0.1,
    p_dropout: float = 0.05,
    p_multipath: float = 0.03,
    gps_noise_m: float = 0.02,
    seed: int = 0,
    gpsd: bool = True,
    fs_gcs: bool = True,
    sitl_folder: Path | None = None,
    cruise_speed_mps: float = 1.0,
):
    """Boat + gpsd (or the vehicle's telemetry when ``gpsd`` is False) + beacons, torn down on exit.

    With ``sitl_folder`` the boat is ArduPilot SITL (:class:`SitlBoat`, binary from ``OCEANLOC_SITL``)."""
    vport = free_port()
    # a BlueBoat's slow survey speed of 1 m/s (ArduPilot's motorboat default is 5 m/s; at ten times real
    # time a slow boat keeps the host's timing jitter, times the wall-clock speed, small), 3 m radius
    params = BoatParams(cruise_speed_mps=cruise_speed_mps)
    boat: BoatSimulator | SitlBoat
    if sitl_folder is not None:
        boat = SitlBoat(os.environ[SITL_ENV], sitl_folder, vport, time_scale)
    else:
        boat = BoatSimulator(
            f"udpout:{LOOPBACK}:{vport}", start_lat_deg=LAT0, start_lon_deg=LON0, params=params,
            time_scale=time_scale, fs_gcs_enable=fs_gcs, fs_timeout_s=5.0, seed=seed,
        )  # fmt: skip
    proj = LocalProjection(lat0_deg=LAT0, lon0_deg=LON0)
    cfg = BeaconSimConfig(
        transponders_enu_m=transponders_enu_m, sigma_range_m=sigma_range_m, time_scale=1.0 / time_scale,
        p_dropout=p_dropout, p_multipath=p_multipath,
    )  # fmt: skip

    def head(_t: float) -> np.ndarray:
        t = boat.truth()
        return np.array([t.east_m, t.north_m, 0.0])

    sim = SeatracBeaconSimulator(cfg, head, np.random.default_rng(seed + 1))
    stack = contextlib.ExitStack()
    try:
        if isinstance(boat, SitlBoat):
            stack.callback(boat.stop)
            boat.ready()
        else:
            boat.start()
            stack.callback(boat.stop)
        port = sim.start()
        stack.callback(sim.stop)
        beacon_ids = ",".join(str(b) for b in sorted(transponders_enu_m))
        ranges_spec = f"seatrac://{port}?beacons={beacon_ids}&timeout=2"
        position_spec = "mavlink"
        if gpsd:
            master, slave = os.openpty()
            tty.setraw(slave)
            gport = free_port(socket.SOCK_STREAM)
            proc = subprocess.Popen(
                ["gpsd", "-N", "-n", "-b", "-S", str(gport), os.ttyname(slave)],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            )  # fmt: skip
            stack.callback(_end, proc, master, slave)
            feeder = NmeaFeeder(master, boat, proj, gps_noise_m, seed + 2)
            feeder.start()
            stack.callback(feeder.stop.set)
            wait_listening(gport, proc)
            position_spec = f"gpsd://{LOOPBACK}:{gport}"
        yield Rig(
            boat=boat, beacons=sim, proj=proj, vehicle_spec=f"udp://{LOOPBACK}:{vport}",
            position_spec=position_spec, ranges_spec=ranges_spec,
            transponders_enu_m=dict(transponders_enu_m), time_scale=time_scale,
        )  # fmt: skip
    finally:
        stack.close()


def _end(proc: subprocess.Popen, master: int, slave: int) -> None:
    proc.terminate()
    try:
        proc.wait(5)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(5)
    for fd in (master, slave):
        with contextlib.suppress(OSError):
            os.close(fd)


def wait_listening(port: int, proc: subprocess.Popen, timeout_s: float = 10.0) -> None:
    """Until gpsd (``proc``) accepts TCP connections on the loopback ``port``; fails the test, with the
    end of its output where it was captured, if it exits or does not listen in time."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            out = proc.stdout.read() if proc.stdout else ""
            pytest.fail(f"gpsd exited with {proc.returncode}: {out[-500:]}")
        try:
            socket.create_connection((LOOPBACK, port), timeout=0.2).close()
            return
        except OSError:
            time.sleep(0.05)
    pytest.fail(f"gpsd did not listen on {LOOPBACK}:{port} within {timeout_s} s")


def oceanloc(*args: str) -> list[str]:
    return [sys.executable, "-m", "oceanloc", *args]


def drop_options(drops_enu_m: dict[int, tuple[float, float, float]]) -> list[str]:
    """``--drop B:LAT,LON,DEPTH`` for drop positions given as east, north (m about the start) and depth."""
    proj = LocalProjection(lat0_deg=LAT0, lon0_deg=LON0)
    out = []
    for b, (e, n, depth) in drops_enu_m.items():
        lon, lat = proj.to_lonlat(e, n)
        out += ["--drop", f"{b}:{float(lat):.8f},{float(lon):.8f},{depth:g}"]
    return out


def start_survey(path: Path, drops_enu_m: dict[int, tuple[float, float, float]], *extra: str) -> None:
    """``oceanloc survey start`` for the rig: the look-ahead planner (k = 3) with the boat's speed and turn
    rate in journal seconds (ten times the simulated ones), 0.3 m range sigma (the simulator's 0.1 m
    plus the host's timing jitter times the boat's 10 m per wall-clock second; white GPS error), the
    crew's drop positions as the prior means within 15 m (8 m in depth)."""
    cmd = oceanloc("survey", "start", str(path), "--planner", "lookahead", "-k", "3", "--speed", "10",
                   "--period", "3", "--max-yaw-rate", "200", "--sigma-range", "0.3", "--sigma-gps", "0",
                   "--prior-sigma", "15,15,8", "--max-gap", "1", *drop_options(drops_enu_m),
                   *extra)  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True, text=True)


def run_command(rig: Rig, path: Path, *extra: str) -> list[str]:
    hb = f"{max(1.0, 2.0 * rig.time_scale):g}"
    return oceanloc(
        "survey", "run", str(path), "--position", rig.position_spec, "--ranges", rig.ranges_spec,
        "--vehicle", rig.vehicle_spec, "--gcs-heartbeat", hb, *extra,
    )  # fmt: skip


def terminate(proc: subprocess.Popen, sig: int = signal.SIGTERM, timeout_s: float = 20.0) -> int:
    proc.send_signal(sig)
    try:
        return proc.wait(timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.wait(5)


def range_information(
    sensors_enu_m: np.ndarray, target_enu_m: np.ndarray, sigma_m: float, prior_sigma_m: np.ndarray
) -> float:
    """log det of the Fisher information of a point from ranges at ``sensors`` (m, 3), at the truth,
    with the survey's Gaussian prior: sum of h h^T / sigma^2 over the unit lines of sight, plus
    diag(1 / prior_sigma^2) (Garcia et al. 2019, eq. 24)."""
    h = range_jacobian(target_enu_m[None, :], sensors_enu_m)
    info = h.T @ h / sigma_m**2 + np.diag(1.0 / np.square(prior_sigma_m))
    return float(np.linalg.slogdet(info)[1])


def interpolate_track(t_fix: np.ndarray, en_fix: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Track positions at times ``t`` (linear between fixes), (n, 3) with U = 0."""
    e = np.interp(t, t_fix, en_fix[:, 0])
    n = np.interp(t, t_fix, en_fix[:, 1])
    return np.column_stack([e, n, np.zeros_like(e)])


def circle_waypoints(proj: LocalProjection, centre_en: np.ndarray, radius_m: float, n: int = 24):
    angles = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    pts = centre_en[None, :] + radius_m * np.column_stack([np.sin(angles), np.cos(angles)])
    return [_lat_lon(proj, p) for p in np.vstack([pts, pts])]


def lawnmower_waypoints(proj: LocalProjection, centre_en: np.ndarray, half_m: float, spacing_m: float):
    xs = np.arange(-half_m, half_m + 1e-9, spacing_m)
    pts = []
    for i, x in enumerate(xs):
        ys = (-half_m, half_m) if i % 2 == 0 else (half_m, -half_m)
        pts += [centre_en + np.array([x, ys[0]]), centre_en + np.array([x, ys[1]])]
    return [_lat_lon(proj, p) for p in pts]


def _lat_lon(proj: LocalProjection, en: np.ndarray) -> tuple[float, float]:
    lon, lat = proj.to_lonlat(en[0], en[1])
    return float(lat), float(lon)
