"""Link loss end to end on loopback: the boat simulator's own GCS failsafe, the adapter and the watchdog.

Cutting the radio link stops the boat twice over: the autopilot's GCS failsafe (FS_GCS_ENABLE, FS_ACTION
Hold) holds it on its side, and oceanloc's watchdog sees the vehicle link quiet and asks for HOLD, then
asks again when the link is back, since the first request could not have arrived.
"""

from __future__ import annotations

import math
import socket
import time

from oceanloc.field.geofence import WatchdogConfig, watchdog_check, watchdog_heard, watchdog_start
from oceanloc.io.mavlink_vehicle import MavlinkVehicle
from oceanloc.sim.boat import MODE_GUIDED, MODE_HOLD, BoatSimulator

LAT0, LON0 = 32.70, -117.25


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_cut_link_holds_the_boat_by_failsafe_and_the_watchdog_asks_hold_again_when_it_returns():
    port = free_udp_port()
    # time scale 10 and our heartbeat at 10 Hz wall: one per simulated second; FS_TIMEOUT 3 simulated s
    sim = BoatSimulator(
        f"udpout:127.0.0.1:{port}", start_lat_deg=LAT0, start_lon_deg=LON0, time_scale=10.0,
        fs_gcs_enable=True, fs_timeout_s=3.0,
    )  # fmt: skip
    vehicle = MavlinkVehicle(f"udp://127.0.0.1:{port}", heartbeat_timeout_s=1.0, gcs_heartbeat_hz=10.0)
    cfg = WatchdogConfig(position_timeout_s=1.0, ranges_timeout_s=30.0, vehicle_timeout_s=1.0)
    sim.start()
    try:
        assert vehicle.connect(3.0).ok
        assert vehicle.goto(LAT0 + 0.01, LON0).ok  # 1.1 km north: underway for a while
        time.sleep(0.5)  # 5 simulated seconds at 10 x: no failsafe while the heartbeats come
        assert sim.mode == MODE_GUIDED
        assert sim.failsafe_times_s == []
        state = watchdog_start(time.monotonic())
        sim.cut_link(True)
        t_cut_sim, t_cut = sim.truth().t_s, time.monotonic()
        verdicts = []
        while time.monotonic() - t_cut < 3.0:
            now = time.monotonic()
            link = vehicle.link()
            if link.alive:
                state = watchdog_heard(state, "vehicle", now)
            fix = vehicle.latest_fix()
            if fix is not None:  # heard when it arrived (its host time, moved to the monotonic clock)
                state = watchdog_heard(state, "position", now - (time.time() - fix.t_unix_s))
            state = watchdog_heard(state, "ranges", now)  # the acoustic stream is not under test here
            verdict = watchdog_check(state, now, cfg)
            verdicts.append((now - t_cut, verdict))
            state = verdict.state
            time.sleep(0.02)
        # the boat held by itself, on its own failsafe
        assert sim.mode == MODE_HOLD
        assert len(sim.failsafe_times_s) == 1
        # FS_TIMEOUT after the last heartbeat, which came within one interval (1 simulated s) of the cut
        assert 2.0 <= sim.failsafe_times_s[0] - t_cut_sim <= 3.0 + 2.0
        first_hold = next(t for t, v in verdicts if v.action == "hold")
        # the watchdog asks for HOLD once the vehicle link or the position is quiet past its timeout (1 s):
        # the last of each came at most 0.1 s (a heartbeat interval) before the cut; slack for a busy machine
        assert 0.85 < first_hold < 2.0
        assert {v.action for t, v in verdicts if t > first_hold} <= {"wait"}
        assert math.hypot(*sim.truth().vel_enu_mps) < 1e-9  # stopped (no current)
        sim.cut_link(False)
        deadline = time.monotonic() + 2.0
        again = None
        while time.monotonic() < deadline and again is None:
            now = time.monotonic()
            if vehicle.link().alive:
                state = watchdog_heard(state, "vehicle", now)
            verdict = watchdog_check(state, now, cfg)
            state = verdict.state
            if verdict.action == "hold":
                again = verdict
            time.sleep(0.02)
        assert again is not None
        assert again.message.endswith("(vehicle link back: HOLD again)")
        assert vehicle.hold().ok
        assert vehicle.link().mode_name == "HOLD"
    finally:
        vehicle.close()
        sim.stop()
    assert sim.error is None
