"""The MAVLink vehicle adapter against the boat simulator over UDP loopback (and its pure parts alone).

Times: the simulator runs 10x faster than real time; the adapter's timeouts are wall-clock seconds.
"""

from __future__ import annotations

import itertools
import math
import os
import pty
import socket
import threading
import time
import tty

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as dialect

from oceanloc.errors import ConfigError
from oceanloc.io.mavlink_vehicle import (
    ROVER_MODES,
    MavlinkVehicle,
    _FixQc,
    mavlink,
    parse_vehicle_spec,
)
from oceanloc.io.qc import QcReport
from oceanloc.sim.boat import MODE_AUTO, MODE_GUIDED, MODE_HOLD, BoatParams, BoatSimulator

LAT0, LON0 = 32.70, -117.25
M_PER_DEG_LAT = 110_900.0  # near 32.7 N, to place targets a few tens of metres away


def free_port(kind=socket.SOCK_DGRAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def offset(north_m: float, east_m: float) -> tuple[float, float]:
    return LAT0 + north_m / M_PER_DEG_LAT, LON0 + east_m / (M_PER_DEG_LAT * math.cos(math.radians(LAT0)))


def wait_until(predicate, timeout_s: float, poll_s: float = 0.01) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(poll_s)
    return bool(predicate())


def distance_m(truth, lat, lon) -> float:
    dn = (truth.lat_deg - lat) * M_PER_DEG_LAT
    de = (truth.lon_deg - lon) * M_PER_DEG_LAT * math.cos(math.radians(LAT0))
    return math.hypot(dn, de)


@pytest.fixture
def boat_and_vehicle(request):
    options = getattr(request, "param", {})
    port = free_port()
    vehicle = MavlinkVehicle(f"udp://127.0.0.1:{port}", heartbeat_timeout_s=1.0, command_timeout_s=1.0)
    sim = BoatSimulator(
        f"udpout:127.0.0.1:{port}", start_lat_deg=LAT0, start_lon_deg=LON0, time_scale=10.0, **options
    )
    sim.start()
    try:
        assert vehicle.connect(wait_heartbeat_s=3.0).status == "connected"
        yield sim, vehicle
    finally:
        vehicle.close()
        sim.stop()
    assert sim.error is None


# -- specs ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("spec", "kind", "device", "baud"),
    [
        ("udp://127.0.0.1:14550", "udp", "udpin:127.0.0.1:14550", 57600),
        ("udpout://127.0.0.1:14555", "udpout", "udpout:127.0.0.1:14555", 57600),
        ("tcp://127.0.0.1:5760", "tcp", "tcp:127.0.0.1:5760", 57600),
        ("serial:///dev/ttyACM0?baud=115200", "serial", "/dev/ttyACM0", 115200),
        ("serial:///dev/ttyUSB1", "serial", "/dev/ttyUSB1", 57600),
    ],
)
def test_specs_parse_to_pymavlink_devices(spec, kind, device, baud):
    s = parse_vehicle_spec(spec)
    assert (s.kind, s.device, s.baud) == (kind, device, baud)


@pytest.mark.parametrize(
    ("spec", "reason"),
    [
        ("udp://127.0.0.1", "expected udp://HOST:PORT"),
        ("tcp://:5760", "expected tcp://HOST:PORT"),
        ("udp://127.0.0.1:99999", "port in 1..65535"),
        ("serial://", "expected serial:///dev/PORT"),
        ("serial:///dev/ttyACM0?baud=fast", "baud must be a positive integer"),
        ("serial:///dev/ttyACM0?parity=N", "unknown option 'parity'"),
        ("mavlink://x:1", "expected udp://, udpout://, tcp:// or serial://"),
    ],
)
def test_bad_specs_are_refused_with_a_reason(spec, reason):
    with pytest.raises(ConfigError, match=reason):
        parse_vehicle_spec(spec)


def test_the_adapter_has_no_way_to_arm():
    assert [name for name in dir(MavlinkVehicle) if "arm" in name.lower()] == []


# -- QC of positions -----------------------------------------------------------------------------


def position(t_ms, lat, lon, alt_mm=0, hdg=65535):
    return mavlink.MAVLink_global_position_int_message(
        t_ms, round(lat * 1e7), round(lon * 1e7), alt_mm, 0, 0, 0, 0, hdg
    )


def test_position_qc_skips_no_fix_duplicates_and_jumps_and_names_each():
    qc = QcReport()
    check = _FixQc("udp://test", qc, max_speed_mps=25.0).check
    assert check(position(0, 0.0, 0.0)) is None  # no position yet
    assert check(position(1000, LAT0, LON0, alt_mm=1500)) == pytest.approx((LAT0, LON0, 1.5))
    assert check(position(1000, LAT0, LON0)) is None  # same time again
    assert check(position(2000, LAT0 + 0.01, LON0)) is None  # 1.1 km in 1 s
    assert check(position(2200, LAT0 + 8e-5, LON0)) is not None  # 8.9 m in 0.2 s: within 5 m + 10 m of noise
    assert check(position(500, LAT0, LON0)) is not None  # a reboot: kept, noted
    assert qc.counts() == {
        "invalid fix": 1,
        "duplicate record": 1,
        "gross outlier": 1,
        "time going backwards": 1,
    }
    assert qc.lines_read == 6
    assert qc.records_kept == 3
    assert [i.line for i in qc.issues] == [1, 3, 4, 6]


def test_position_qc_takes_a_new_reference_after_five_outliers_in_a_row():
    qc = QcReport()
    check = _FixQc("udp://test", qc, max_speed_mps=25.0).check
    assert check(position(0, LAT0, LON0)) is not None
    moved = [check(position(200 * k, LAT0 + 0.01, LON0)) for k in range(1, 7)]  # a 1.1 km step, then steady
    assert [m is not None for m in moved] == [False, False, False, False, True, True]
    assert qc.counts() == {"gross outlier": 5}
    assert qc.issues[-1].detail == "5 in a row: new reference; kept"


# -- against the boat simulator ------------------------------------------------------------------


def test_connect_reports_mode_and_the_operators_arming(boat_and_vehicle):
    _, vehicle = boat_and_vehicle
    st = vehicle.link()
    assert st.alive
    assert st.mode == ROVER_MODES["HOLD"]
    assert st.mode_name == "HOLD"
    assert st.armed
    assert st.heartbeat_age_s < 1.0


def test_mode_change_to_guided_is_acknowledged(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    result = vehicle.set_mode("GUIDED")
    assert result.status == "accepted", result.message
    assert result.command == mavlink.MAV_CMD_DO_SET_MODE
    assert result.result_code == mavlink.MAV_RESULT_ACCEPTED
    assert sim.mode == MODE_GUIDED
    assert vehicle.require_mode("GUIDED").ok


def test_auto_without_a_mission_is_rejected_by_the_vehicle(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    result = vehicle.set_mode("AUTO")
    assert result.status == "rejected"
    assert result.message == "mode AUTO: MAV_CMD_DO_SET_MODE: MAV_RESULT_FAILED"
    assert sim.mode == MODE_HOLD


def test_goto_outside_guided_without_switching_is_refused(boat_and_vehicle):
    _, vehicle = boat_and_vehicle
    result = vehicle.goto(*offset(10.0, 0.0), ensure_guided=False)
    assert result.status == "not_in_mode"
    assert result.message == "vehicle is in HOLD, not GUIDED"


def test_goto_drives_the_boat_into_the_waypoint_radius_then_hold_stops_it(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    lat, lon = offset(40.0, 30.0)  # 50 m away
    t0 = sim.truth().t_s
    result = vehicle.goto(lat, lon)
    assert result.status == "accepted", result.message
    assert sim.mode == MODE_GUIDED
    assert wait_until(lambda: distance_m(sim.truth(), lat, lon) < BoatParams().wp_radius_m, 4.0)
    # 50 m at 5 m/s after turning 37 deg: 10 s plus accelerating, turning and braking; well under 16 s
    elapsed = sim.truth().t_s - t0
    assert 10.0 < elapsed < 16.0
    fix = vehicle.latest_fix()
    assert fix is not None
    # the telemetry is the truth at its own time: apart by at most 5 m/s times the age of the fix (in
    # simulated time, time_boot_ms), plus the 1e-7 degree rounding
    truth = sim.truth()
    assert distance_m(truth, fix.lat_deg, fix.lon_deg) <= 5.0 * (truth.t_s - fix.time_boot_ms / 1e3) + 0.05
    # it stays there (station keeping): still inside 3 s (simulated 30 s) later
    time.sleep(0.5)
    assert distance_m(sim.truth(), lat, lon) < BoatParams().wp_radius_m
    # send it further, then HOLD while it is underway: it stops within 5 / 2 = 2.5 simulated seconds
    far = offset(200.0, 30.0)
    assert vehicle.goto(*far).status == "accepted"
    assert wait_until(lambda: math.hypot(*sim.truth().vel_enu_mps) > 4.5, 4.0)
    hold = vehicle.hold()
    assert hold.status == "accepted", hold.message
    t_hold = sim.truth().t_s
    assert wait_until(lambda: math.hypot(*sim.truth().vel_enu_mps) < 1e-9, 2.0)
    assert sim.truth().t_s - t_hold < 5.0  # 2.5 s braking; the rest is polling on a loaded machine
    stopped = sim.truth()
    time.sleep(0.3)
    assert distance_m(sim.truth(), stopped.lat_deg, stopped.lon_deg) < 1e-3
    assert sim.mode == MODE_HOLD


def test_fixes_carry_the_heading_from_attitude(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    assert vehicle.goto(*offset(0.0, 80.0)).ok  # due east
    time.sleep(1.0)  # 10 simulated seconds: turned and underway
    fixes, t_end = [], time.monotonic() + 0.5
    for fix in vehicle.fixes(timeout_s=0.5):
        fixes.append(fix)
        if time.monotonic() > t_end:
            break
    assert len(fixes) > 20  # 5 Hz simulated = 50 Hz wall: about 1.5 s of them (fewer if the machine is busy)
    last = fixes[-1]
    assert last.heading_source == "ATTITUDE"
    assert last.heading_deg == pytest.approx(sim.truth().heading_deg % 360.0, abs=3.0)
    assert last.heading_deg == pytest.approx(90.0, abs=5.0)
    assert all(b.time_boot_ms > a.time_boot_ms for a, b in itertools.pairwise(fixes))
    assert vehicle.qc.counts() == {}


def test_mission_upload_then_auto_visits_every_item(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    waypoints = [offset(30.0, 0.0), offset(30.0, 30.0), offset(0.0, 30.0)]
    deadline = time.monotonic() + 5.0  # home is the latest fix: wait for the first (a busy machine is slow)
    while vehicle.latest_fix() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    up = vehicle.upload_mission(waypoints)
    assert up.status == "accepted", up.message
    assert (up.n_items, up.resends) == (4, 0)
    stored = sim.mission
    assert [it.seq for it in stored] == [0, 1, 2, 3]
    assert [(it.x, it.y) for it in stored[1:]] == [(round(a * 1e7), round(b * 1e7)) for a, b in waypoints]
    assert all(it.command == mavlink.MAV_CMD_NAV_WAYPOINT for it in stored)
    assert vehicle.start_mission().status == "accepted"
    assert sim.mode == MODE_AUTO
    # 3 legs of 30 m at 5 m/s: 18 s plus turns; the mission ends in HOLD (MIS_DONE_BEHAVE 0)
    assert wait_until(lambda: sim.mode == MODE_HOLD, 8.0)
    assert sim.reached == [1, 2, 3]
    assert wait_until(lambda: vehicle.reached == [1, 2, 3], 1.0)
    assert distance_m(sim.truth(), *waypoints[-1]) < BoatParams().wp_radius_m + 1.0  # coasting to a stop


@pytest.mark.parametrize(
    "boat_and_vehicle", [{"ignore_items_once": frozenset({2}), "request_retry_s": 30.0}], indirect=True
)
def test_mission_upload_resends_an_item_the_vehicle_missed(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    # the simulator does not re-request (30 s): only the adapter's own resend after 1 s completes it
    up = vehicle.upload_mission([offset(10.0, 0.0), offset(20.0, 0.0)])
    assert up.status == "accepted", up.message
    assert up.resends >= 1
    assert len(sim.mission) == 3
    assert vehicle.sent.count("MISSION_ITEM_INT") >= 4  # items 0, 1, 2 and item 2 again


def test_link_loss_is_detected_within_the_timeout_when_the_boat_goes_silent(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    assert vehicle.link().alive
    sim.stop()
    t0 = time.monotonic()
    assert wait_until(lambda: not vehicle.link().alive, 3.0)
    # silence began at most one heartbeat interval (0.1 s wall at 10x) before the stop; 0.5 s of slack for
    # a loaded machine (2 cores shared)
    assert time.monotonic() - t0 < vehicle.heartbeat_timeout_s + 0.5
    result = vehicle.set_mode("HOLD")
    assert result.status == "link_lost"


def test_a_cut_link_times_out_commands_and_recovers(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    sim.cut_link(True)
    assert wait_until(lambda: not vehicle.link().alive, 2.0)
    sim.cut_link(False)
    assert wait_until(lambda: vehicle.link().alive, 2.0)
    assert vehicle.set_mode("GUIDED").ok


def test_nothing_sent_in_a_whole_session_arms_the_vehicle(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    assert vehicle.goto(*offset(10.0, 10.0)).ok
    assert vehicle.upload_mission([offset(5.0, 5.0)]).ok
    assert vehicle.start_mission().ok
    assert vehicle.hold().ok
    assert mavlink.MAV_CMD_COMPONENT_ARM_DISARM not in sim.commands
    assert not any(name == f"COMMAND_LONG:{mavlink.MAV_CMD_COMPONENT_ARM_DISARM}" for name in vehicle.sent)
    assert sim.commands.count(mavlink.MAV_CMD_DO_SET_MODE) == 3


def test_tcp_spec_reaches_a_boat_serving_tcp():
    port = free_port(socket.SOCK_STREAM)
    sim = BoatSimulator(f"tcpin:127.0.0.1:{port}", time_scale=10.0).start()
    vehicle = MavlinkVehicle(f"tcp://127.0.0.1:{port}")
    try:
        assert vehicle.connect(wait_heartbeat_s=3.0).status == "connected"
        assert vehicle.set_mode("GUIDED").ok
    finally:
        vehicle.close()
        sim.stop()


def test_no_heartbeat_gives_a_timeout_result():
    vehicle = MavlinkVehicle(f"udp://127.0.0.1:{free_port()}")
    try:
        result = vehicle.connect(wait_heartbeat_s=0.3)
    finally:
        vehicle.close()
    assert result.status == "timeout"
    assert result.message.endswith("no heartbeat within 0.3 s")


def test_serial_spec_talks_mavlink_over_a_pseudo_terminal():
    """A serial link (pyserial under pymavlink) on a pty: the far end plays the autopilot by hand."""
    master, slave = pty.openpty()
    tty.setraw(slave)
    name = os.ttyname(slave)

    class PtyWriter:
        def write(self, data: bytes) -> None:
            os.write(master, data)

    autopilot = dialect.MAVLink(PtyWriter(), srcSystem=7, srcComponent=1)
    vehicle = MavlinkVehicle(f"serial://{name}?baud=57600")
    try:
        result_box = []
        t = threading.Thread(target=lambda: result_box.append(vehicle.connect(wait_heartbeat_s=3.0)))
        t.start()
        for _ in range(20):
            autopilot.heartbeat_send(
                mavlink.MAV_TYPE_SURFACE_BOAT,
                mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                ROVER_MODES["GUIDED"],
                mavlink.MAV_STATE_STANDBY,
            )
            time.sleep(0.05)
            if result_box:
                break
        t.join(4.0)
        assert result_box[0].status == "connected"
        st = vehicle.link()
        assert (st.mode_name, st.armed) == ("GUIDED", False)
        # our ground-station heartbeat reaches the autopilot side of the line
        parser = dialect.MAVLink(None)
        parser.robust_parsing = True
        seen = set()
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline and "HEARTBEAT" not in seen:
            for msg in parser.parse_buffer(os.read(master, 4096)) or []:
                seen.add(msg.get_type())
        assert "HEARTBEAT" in seen
    finally:
        vehicle.close()
        os.close(master)
        os.close(slave)


@pytest.mark.parametrize(
    "boat_and_vehicle", [{"rates_hz": {"POSITION_TARGET_GLOBAL_INT": 0.0}}], indirect=True
)
def test_goto_without_the_target_echo_is_unconfirmed_but_sent(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    lat, lon = offset(20.0, 0.0)
    result = vehicle.goto(lat, lon)
    assert result.status == "unconfirmed"
    assert result.message == f"goto {lat:.7f}, {lon:.7f} sent; the vehicle did not echo the target"
    assert vehicle.sent.count("SET_POSITION_TARGET_GLOBAL_INT") == vehicle.command_retries + 1
    assert wait_until(lambda: distance_m(sim.truth(), lat, lon) < BoatParams().wp_radius_m, 4.0)


@pytest.mark.parametrize("boat_and_vehicle", [{"gps_noise_m": 2.0, "seed": 7}], indirect=True)
def test_noisy_fixes_pass_qc_and_scatter_as_the_noise(boat_and_vehicle):
    sim, vehicle = boat_and_vehicle
    fixes, t_end = [], time.monotonic() + 4.0
    for fix in vehicle.fixes(timeout_s=0.5):
        fixes.append(fix)
        if len(fixes) >= 200 or time.monotonic() > t_end:
            break
    n = len(fixes)
    assert n >= 60
    north = np.array([(f.lat_deg - LAT0) * M_PER_DEG_LAT for f in fixes])
    # std of n normal draws: standard error sigma / sqrt(2 n) <= 0.18 m at n >= 60; 4 standard errors
    assert north.std(ddof=1) == pytest.approx(2.0, abs=4 * 2.0 / math.sqrt(2 * n))
    assert abs(north.mean()) < 4 * 2.0 / math.sqrt(n)  # the truth does not move: HOLD, no current
    assert sim.truth().north_m == 0.0
    assert vehicle.qc.counts().get("gross outlier", 0) == 0


def test_a_missing_serial_port_is_a_clear_error():
    vehicle = MavlinkVehicle("serial:///dev/oceanloc-no-such-port?baud=57600")
    with pytest.raises(
        ConfigError, match="vehicle serial:///dev/oceanloc-no-such-port\\?baud=57600: cannot open"
    ):
        vehicle.connect(wait_heartbeat_s=0.1)
    vehicle.close()


@pytest.mark.parametrize(
    ("options", "reason"),
    [
        ({"heartbeat_timeout_s": 0.0}, "heartbeat_timeout_s must be a positive number of seconds, got 0.0"),
        ({"command_retries": -1}, "command_retries must be 0 or more, got -1"),
        ({"gcs_heartbeat_hz": math.inf}, "gcs_heartbeat_hz must be a positive number, got inf"),
    ],
)
def test_bad_adapter_options_are_refused(options, reason):
    with pytest.raises(ConfigError, match=reason):
        MavlinkVehicle("udp://127.0.0.1:14550", **options)


def test_unknown_mode_names_are_refused_before_anything_is_sent():
    vehicle = MavlinkVehicle("udp://127.0.0.1:14550")
    with pytest.raises(ConfigError, match="mode 'ACRO': expected one of MANUAL, HOLD, LOITER, AUTO, GUIDED"):
        vehicle.set_mode("ACRO")
    assert vehicle.sent == []
