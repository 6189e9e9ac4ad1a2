"""The boat simulator: its motion model (pure) and its MAVLink dialect, checked with raw pymavlink."""

from __future__ import annotations

import math
import socket
import time

import pytest

from oceanloc.errors import ConfigError
from oceanloc.sim.boat import (
    MODE_GUIDED,
    MODE_HOLD,
    BoatParams,
    BoatSimulator,
    BoatState,
    mavlink,
    mavutil,
    step_boat,
)


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run(state, target, params, seconds, dt=0.05, **kw):
    trace = [state]
    for _ in range(round(seconds / dt)):
        state = step_boat(state, target, params, dt, **kw)
        trace.append(state)
    return trace


def test_boat_reaches_a_target_at_cruise_speed_and_stops_inside_the_waypoint_radius():
    params = BoatParams()
    trace = run(BoatState(), (0.0, 200.0), params, 60.0)
    top = max(s.speed_mps for s in trace)
    assert top == pytest.approx(5.0, abs=1e-9)  # CRUISE_SPEED
    end = trace[-1]
    assert math.hypot(end.east_m, end.north_m - 200.0) < params.loiter_radius_m
    assert end.speed_mps == 0.0
    # 200 m at 5 m/s plus accelerating and braking at 2 m/s^2 (1.25 s each way): reached in about 42.5 s
    t_reach = next(s.t_s for s in trace if math.hypot(s.east_m, s.north_m - 200.0) < params.wp_radius_m)
    assert 40.0 < t_reach < 45.0


def test_turn_rate_never_exceeds_the_limits():
    params = BoatParams()
    trace = run(BoatState(heading_rad=0.0), (-50.0, -50.0), params, 30.0)  # target behind: a hard turn
    for s in trace[1:]:
        limit = math.radians(params.turn_rate_max_dps)
        if s.speed_mps > 0:
            limit = min(limit, params.turn_max_g * 9.80665 / s.speed_mps)
        assert abs(s.yaw_rate_rps) <= limit + 1e-12
        assert s.speed_mps * abs(s.yaw_rate_rps) <= 0.6 * 9.80665 + 1e-9  # lateral acceleration, m/s^2
    assert max(abs(s.yaw_rate_rps) for s in trace) == pytest.approx(math.radians(120.0))  # ATC_STR_RAT_MAX


def test_without_thrust_the_boat_drifts_with_the_current():
    params = BoatParams(current_enu_mps=(0.3, -0.1))
    end = run(BoatState(), None, params, 100.0)[-1]
    assert end.east_m == pytest.approx(30.0, abs=1e-6)
    assert end.north_m == pytest.approx(-10.0, abs=1e-6)


def test_station_keeping_against_a_current_stays_inside_the_waypoint_radius():
    params = BoatParams(current_enu_mps=(0.5, 0.0))
    trace = run(BoatState(), (0.0, 50.0), params, 120.0)
    late = [math.hypot(s.east_m, s.north_m - 50.0) for s in trace if s.t_s > 40.0]
    assert max(late) < params.wp_radius_m


@pytest.mark.parametrize(
    ("endpoint", "reason"),
    [
        ("udpout:10.0.0.1:14550", "only talks on 127.0.0.1"),
        ("udp:127.0.0.1:14550", "expected one of"),
        ("udpout:127.0.0.1:0", "port must be"),
    ],
)
def test_endpoints_off_loopback_or_malformed_are_refused(endpoint, reason):
    with pytest.raises(ConfigError, match=reason):
        BoatSimulator(endpoint)


def test_negative_cruise_speed_is_refused():
    with pytest.raises(ConfigError, match="cruise_speed_mps must be a positive number"):
        BoatParams(cruise_speed_mps=-1.0)


def test_dialect_heartbeat_mode_change_and_arming_refusal_with_raw_pymavlink():
    port = free_udp_port()
    gcs = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=255, dialect="ardupilotmega")
    sim = BoatSimulator(f"udpout:127.0.0.1:{port}", time_scale=5.0).start()
    try:
        hb = gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=3.0)
        assert hb is not None
        assert hb.type == mavlink.MAV_TYPE_SURFACE_BOAT
        assert hb.autopilot == mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
        assert hb.custom_mode == MODE_HOLD
        assert hb.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED
        assert gcs.target_system == 1
        gcs.mav.command_long_send(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, MODE_GUIDED, 0, 0, 0, 0, 0)
        ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=3.0)
        assert (ack.command, ack.result) == (mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_RESULT_ACCEPTED)
        gcs.mav.set_mode_send(1, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 42)
        ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=3.0)
        assert (ack.command, ack.result) == (11, mavlink.MAV_RESULT_FAILED)
        gcs.mav.command_long_send(1, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0)
        ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=3.0)
        assert (ack.command, ack.result) == (mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_RESULT_DENIED)
        deadline = time.monotonic() + 3.0
        while sim.mode != MODE_GUIDED and time.monotonic() < deadline:
            time.sleep(0.01)
        assert sim.mode == MODE_GUIDED
        names = set()
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline:
            m = gcs.recv_match(blocking=True, timeout=0.2)
            if m is not None:
                names.add(m.get_type())
        assert {"GLOBAL_POSITION_INT", "ATTITUDE", "VFR_HUD", "SYS_STATUS", "SIM_STATE"} <= names
    finally:
        sim.stop()
        gcs.close()
    assert sim.error is None
    assert sim.commands == [
        mavlink.MAV_CMD_DO_SET_MODE,
        mavlink.MAV_CMD_COMPONENT_ARM_DISARM,
    ]


def test_truth_reports_the_start_and_the_simulated_clock_runs_at_the_time_scale():
    port = free_udp_port()
    sim = BoatSimulator(f"udpout:127.0.0.1:{port}", start_lat_deg=10.0, start_lon_deg=20.0, time_scale=20.0)
    t0 = time.monotonic()
    with sim:
        time.sleep(0.5)
        truth = sim.truth()
        wall = time.monotonic() - t0
    assert truth.lat_deg == pytest.approx(10.0, abs=1e-9)
    assert truth.lon_deg == pytest.approx(20.0, abs=1e-9)
    # Never ahead of the time scale, and running. How far behind it falls depends on the machine's load,
    # which a test does not assert (the rate itself is in `make bench`, live).
    assert 0.0 < truth.t_s <= 20.0 * wall
    assert truth.to_record()["mode"] == "HOLD"


def test_unknown_telemetry_rate_is_refused():
    with pytest.raises(ConfigError, match="no telemetry rate for GPS_RAW_INT: one of HEARTBEAT"):
        BoatSimulator("udpout:127.0.0.1:14550", rates_hz={"GPS_RAW_INT": 1.0})


def test_guided_goto_as_a_mission_item_with_current_2_only_in_guided():
    port = free_udp_port()
    gcs = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=255, dialect="ardupilotmega")
    sim = BoatSimulator(f"udpout:127.0.0.1:{port}", time_scale=10.0).start()
    lat, lon = 32.70 + 30.0 / 110_900.0, -117.25

    def goto_item():
        gcs.mav.mission_item_int_send(
            1, 1, 0, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, mavlink.MAV_CMD_NAV_WAYPOINT, 2, 1,
            0, 0, 0, 0, round(lat * 1e7), round(lon * 1e7), 0, 0,
        )  # fmt: skip
        return gcs.recv_match(type="MISSION_ACK", blocking=True, timeout=3.0)

    try:
        assert gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=3.0) is not None
        assert goto_item().type == mavlink.MAV_MISSION_ERROR  # in HOLD
        gcs.mav.command_long_send(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, MODE_GUIDED, 0, 0, 0, 0, 0)
        assert gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=3.0).result == 0
        assert goto_item().type == mavlink.MAV_MISSION_ACCEPTED
        deadline = time.monotonic() + 3.0
        while (
            math.hypot(sim.truth().east_m, sim.truth().north_m - 30.0) > 3.0 and time.monotonic() < deadline
        ):
            time.sleep(0.02)
        assert math.hypot(sim.truth().east_m, sim.truth().north_m - 30.0) <= 3.0
    finally:
        sim.stop()
        gcs.close()
