"""The adapter against ArduPilot's own Rover software-in-the-loop, when a build is at hand.

Set OCEANLOC_SITL to an ``ardurover`` SITL binary (built from ArduPilot with ``./waf rover``) to run it;
otherwise it is skipped. The boat is ArduPilot's ``motorboat`` model, started 10x faster than real time
with the parameters written below (a boat frame, the defaults the boat simulator mimics, and
``ARMING_REQUIRE 0`` so that the operator's configuration, not oceanloc, has the motors live). The test
talks to SITL's serial0 over UDP on loopback only. Nothing of ArduPilot is stored in this repository.
"""

from __future__ import annotations

import math
import os
import socket
import subprocess
import time
from pathlib import Path

import pytest

from oceanloc.io.mavlink_vehicle import MavlinkVehicle, mavlink

SITL_ENV = "OCEANLOC_SITL"
LAT0, LON0 = 32.70, -117.25
M_PER_DEG_LAT = 110_900.0
PARAMS = """FRAME_CLASS 2
CRUISE_SPEED 5
WP_RADIUS 3
ARMING_REQUIRE 0
ARMING_CHECK 0
FS_GCS_ENABLE 0
"""

pytestmark = pytest.mark.skipif(
    not os.environ.get(SITL_ENV), reason=f"set {SITL_ENV} to an ArduPilot ardurover SITL binary to run this"
)


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def offset(north_m: float, east_m: float) -> tuple[float, float]:
    return LAT0 + north_m / M_PER_DEG_LAT, LON0 + east_m / (M_PER_DEG_LAT * math.cos(math.radians(LAT0)))


def distance_m(fix, lat, lon) -> float:
    dn = (fix.lat_deg - lat) * M_PER_DEG_LAT
    de = (fix.lon_deg - lon) * M_PER_DEG_LAT * math.cos(math.radians(LAT0))
    return math.hypot(dn, de)


def wait_until(predicate, timeout_s: float, poll_s: float = 0.05) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(poll_s)
    return bool(predicate())


@pytest.fixture
def sitl(tmp_path: Path):
    binary = Path(os.environ[SITL_ENV])
    if not binary.is_file():
        pytest.fail(f"{SITL_ENV}={binary}: no such file")
    port = free_udp_port()
    params = tmp_path / "oceanloc-boat.parm"
    params.write_text(PARAMS)
    command = [
        str(binary), "-w", "--model", "motorboat", "--speedup", "10", "--home", f"{LAT0},{LON0},0,0",
        "--defaults", str(params), "--serial0", f"udpclient:127.0.0.1:{port}",
    ]  # fmt: skip
    log = (tmp_path / "sitl.log").open("w")
    proc = subprocess.Popen(command, cwd=tmp_path, stdout=log, stderr=subprocess.STDOUT)
    vehicle = MavlinkVehicle(f"udp://127.0.0.1:{port}", heartbeat_timeout_s=3.0, command_timeout_s=1.0)
    try:
        connected = vehicle.connect(wait_heartbeat_s=30.0)
        if connected.status != "connected":
            pytest.fail(f"SITL gave no heartbeat in 30 s (log: {tmp_path / 'sitl.log'})")
        yield proc, vehicle
    finally:
        vehicle.close()
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(5.0)
            except subprocess.TimeoutExpired:
                proc.kill()
        log.close()


def test_sitl_boat_goes_to_a_guided_site_holds_runs_a_mission_and_the_link_loss_is_seen(sitl):
    proc, vehicle = sitl
    assert wait_until(lambda: vehicle.latest_fix() is not None, 60.0), "no position from SITL (EKF not ready)"
    assert wait_until(lambda: vehicle.link().armed, 30.0), (
        "SITL not armed: the parameters set ARMING_REQUIRE 0"
    )
    # the EKF may refuse GUIDED for a while after boot: ask until it is accepted
    assert wait_until(lambda: vehicle.set_mode("GUIDED").ok, 60.0, poll_s=1.0)
    lat, lon = offset(40.0, 30.0)
    assert vehicle.goto(lat, lon).status in ("accepted", "unconfirmed")
    assert wait_until(lambda: distance_m(vehicle.latest_fix(), lat, lon) < 3.0 + 2.0, 30.0)
    assert vehicle.hold().ok
    waypoints = [offset(0.0, 30.0), offset(0.0, 0.0)]
    up = vehicle.upload_mission(waypoints)
    assert up.ok, up.message
    assert vehicle.start_mission().ok
    assert wait_until(lambda: vehicle.reached[-1:] == [2], 40.0), f"reached {vehicle.reached}"
    assert mavlink.MAV_CMD_COMPONENT_ARM_DISARM not in [
        int(name.split(":")[1]) for name in vehicle.sent if name.startswith("COMMAND_LONG:")
    ]
    proc.terminate()
    proc.wait(5.0)
    t0 = time.monotonic()
    assert wait_until(lambda: not vehicle.link().alive, 5.0)
    assert time.monotonic() - t0 <= vehicle.heartbeat_timeout_s + 0.5
