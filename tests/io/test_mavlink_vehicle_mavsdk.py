"""The adapter against MAVSDK (an implementation that is not ours) in its vehicle role, on UDP loopback.

MAVSDK 4.x's MissionRawServer plays the vehicle side of the mission protocol: it requests each item of our
upload, parses it and acknowledges; its ActionServer answers our DO_SET_MODE. MAVSDK's server side knows
PX4's flight modes only (custom_mode = main << 16 | sub << 24), so it answers Rover mode numbers with
MAV_RESULT_TEMPORARILY_REJECTED: that checks that we parse an independent COMMAND_ACK and report the
refusal, not that a Rover mode change succeeds (the boat simulator and SITL tests check that).
"""

from __future__ import annotations

import socket
import threading
import time

import pytest

mavsdk_core = pytest.importorskip("mavsdk.mavsdk", reason="MAVSDK (PyPI mavsdk) is not installed")
from mavsdk.component_type import ComponentType  # noqa: E402
from mavsdk.plugins.action_server.action_server import ActionServer, AllowableFlightModes  # noqa: E402
from mavsdk.plugins.mission_raw_server.mission_raw_server import (  # noqa: E402
    MissionRawServer,
    MissionRawServerResult,
)

from oceanloc.io.mavlink_vehicle import MavlinkVehicle, mavlink  # noqa: E402

HOME = (32.70, -117.25)
WAYPOINTS = [(32.70 + 0.0003 * k, -117.25 + 0.0002 * (k % 3)) for k in range(1, 13)]


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def mavsdk_vehicle():
    """MAVSDK as an autopilot sending to our adapter listening on a loopback port."""
    port = free_udp_port()
    vehicle = MavlinkVehicle(f"udp://127.0.0.1:{port}", heartbeat_timeout_s=2.0, command_timeout_s=1.0)
    sdk = mavsdk_core.Mavsdk(mavsdk_core.Configuration.create_with_component_type(ComponentType.AUTOPILOT))
    assert int(sdk.add_any_connection(f"udpout://127.0.0.1:{port}")) == 0  # ConnectionResult.SUCCESS
    component = sdk.server_component()
    missions = MissionRawServer(component)
    actions = ActionServer(component)
    received: list = []
    got = threading.Event()

    def on_mission(result, plan, _user):
        received.append((result, plan))
        got.set()

    missions.subscribe_incoming_mission(on_mission)
    modes: list = []
    actions.subscribe_flight_mode_change(lambda result, mode, _user: modes.append((result, mode)))
    actions.set_allowable_flight_modes(AllowableFlightModes(can_auto_mode=True, can_guided_mode=True))
    try:
        assert vehicle.connect(wait_heartbeat_s=5.0).status == "connected"
        yield vehicle, missions, received, got, modes
    finally:
        vehicle.close()
        sdk.destroy()


def test_mavsdk_receives_our_mission_item_by_item_as_sent(mavsdk_vehicle):
    vehicle, _, received, got, _ = mavsdk_vehicle
    t0 = time.monotonic()
    up = vehicle.upload_mission(WAYPOINTS, home=HOME)
    elapsed = time.monotonic() - t0
    assert up.status == "accepted", up.message
    assert (up.n_items, up.resends, up.result_code) == (13, 0, mavlink.MAV_MISSION_ACCEPTED)
    assert elapsed < 2.0
    assert got.wait(2.0)
    result, plan = received[-1]
    assert result == MissionRawServerResult.SUCCESS
    items = plan.mission_items
    assert [it.seq for it in items] == list(range(13))
    assert [(it.x, it.y) for it in items] == [(round(a * 1e7), round(b * 1e7)) for a, b in [HOME, *WAYPOINTS]]
    assert {it.command for it in items} == {mavlink.MAV_CMD_NAV_WAYPOINT}
    assert {it.frame for it in items} == {mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT}
    assert {it.autocontinue for it in items} == {1}
    assert {it.mission_type for it in items} == {mavlink.MAV_MISSION_TYPE_MISSION}
    assert all(it.z == 0.0 for it in items)


def test_a_second_upload_replaces_the_first_at_mavsdk(mavsdk_vehicle):
    vehicle, _, received, got, _ = mavsdk_vehicle
    assert vehicle.upload_mission(WAYPOINTS, home=HOME).ok
    assert got.wait(2.0)
    got.clear()
    assert vehicle.upload_mission(WAYPOINTS[:2], home=HOME).ok
    assert got.wait(2.0)
    assert len(received[-1][1].mission_items) == 3


def test_mavsdk_reports_item_progress_back_to_us(mavsdk_vehicle):
    vehicle, missions, _, got, _ = mavsdk_vehicle
    assert vehicle.upload_mission(WAYPOINTS[:3], home=HOME).ok
    assert got.wait(2.0)
    missions.set_current_item_complete()  # the vehicle side says: item reached
    deadline = time.monotonic() + 2.0
    while not vehicle.reached and time.monotonic() < deadline:
        time.sleep(0.02)
    assert vehicle.reached[:1] == [0]


def test_mode_change_is_answered_by_mavsdk_and_reported_as_refused(mavsdk_vehicle):
    vehicle, _, _, _, modes = mavsdk_vehicle
    result = vehicle.set_mode("GUIDED")
    assert result.status == "rejected"
    assert result.result_code == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    assert result.message == "mode GUIDED: MAV_CMD_DO_SET_MODE: MAV_RESULT_TEMPORARILY_REJECTED"
    # MAVSDK saw each request we sent (one, unless a loaded machine delayed its answer past our timeout)
    sends = vehicle.sent.count(f"COMMAND_LONG:{mavlink.MAV_CMD_DO_SET_MODE}")
    assert 1 <= sends <= vehicle.command_retries + 1
    deadline = time.monotonic() + 2.0
    while len(modes) < sends and time.monotonic() < deadline:
        time.sleep(0.02)
    assert len(modes) == sends
    assert not any(name.endswith(f":{mavlink.MAV_CMD_COMPONENT_ARM_DISARM}") for name in vehicle.sent)
