"""The boat simulator's dialect checked by MAVSDK (an implementation that is not ours) as the ground station.

MAVSDK recognises ArduPilot from the heartbeat and maps Rover's custom modes to its own flight modes
(HOLD -> HOLD, AUTO -> MISSION); it uploads and downloads missions with its own mission protocol code and
reads GLOBAL_POSITION_INT as its position. Arming is refused by the simulator: MAVSDK must report the
denial it receives.
"""

from __future__ import annotations

import socket
import time

import pytest

mavsdk_core = pytest.importorskip("mavsdk.mavsdk", reason="MAVSDK (PyPI mavsdk) is not installed")
from mavsdk.component_type import ComponentType  # noqa: E402
from mavsdk.plugins.action.action import Action, ActionError, ActionResult  # noqa: E402
from mavsdk.plugins.mission_raw.mission_raw import MissionItem, MissionRaw  # noqa: E402
from mavsdk.plugins.telemetry.telemetry import FlightMode, Telemetry  # noqa: E402

from oceanloc.sim.boat import MODE_AUTO, MODE_HOLD, BoatSimulator, mavlink  # noqa: E402

LAT0, LON0 = 32.70, -117.25


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(predicate, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return bool(predicate())


@pytest.fixture
def mavsdk_gcs_and_boat():
    port = free_udp_port()
    sdk = mavsdk_core.Mavsdk(
        mavsdk_core.Configuration.create_with_component_type(ComponentType.GROUND_STATION)
    )
    assert int(sdk.add_any_connection(f"udpin://127.0.0.1:{port}")) == 0
    sim = BoatSimulator(f"udpout:127.0.0.1:{port}", start_lat_deg=LAT0, start_lon_deg=LON0, time_scale=10.0)
    sim.start()
    try:
        system = sdk.first_autopilot(5.0)
        assert system is not None
        yield sim, system
    finally:
        sim.stop()
        sdk.destroy()
    assert sim.error is None


def test_mavsdk_sees_the_boat_in_hold_at_its_position(mavsdk_gcs_and_boat):
    sim, system = mavsdk_gcs_and_boat
    telemetry = Telemetry(system)
    assert wait_until(lambda: telemetry.flight_mode() == FlightMode.HOLD, 2.0)
    assert wait_until(lambda: abs(telemetry.position().latitude_deg - LAT0) < 1e-6, 2.0)
    position = telemetry.position()
    truth = sim.truth()
    assert (position.latitude_deg, position.longitude_deg) == pytest.approx(
        (truth.lat_deg, truth.lon_deg), abs=1e-7
    )
    assert wait_until(
        lambda: telemetry.armed() is True, 2.0
    )  # MAV_MODE_FLAG_SAFETY_ARMED, set by the operator


def test_mavsdk_uploads_downloads_and_starts_a_mission_on_the_boat(mavsdk_gcs_and_boat):
    sim, system = mavsdk_gcs_and_boat
    mission = MissionRaw(system)
    telemetry = Telemetry(system)
    points = [(LAT0, LON0), (LAT0 + 0.0002, LON0), (LAT0 + 0.0002, LON0 + 0.0002)]
    items = [
        MissionItem(
            seq=k, frame=mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, command=mavlink.MAV_CMD_NAV_WAYPOINT,
            current=int(k == 0), autocontinue=1, x=round(lat * 1e7), y=round(lon * 1e7), z=0.0,
            mission_type=0,
        )
        for k, (lat, lon) in enumerate(points)
    ]  # fmt: skip
    mission.upload_mission(items)  # raises MissionRawError unless the upload succeeded
    assert [(it.seq, it.x, it.y) for it in sim.mission] == [(it.seq, it.x, it.y) for it in items]
    downloaded = mission.download_mission()
    assert [(it.seq, it.x, it.y, it.command) for it in downloaded] == [
        (it.seq, it.x, it.y, it.command) for it in items
    ]
    mission.start_mission()  # DO_SET_MODE AUTO (Rover's number, by MAVSDK's own table) and MISSION_START
    assert sim.mode == MODE_AUTO
    assert wait_until(lambda: telemetry.flight_mode() == FlightMode.MISSION, 2.0)
    # two 22 m legs at 5 m/s: the mission ends (HOLD) after about 10 simulated seconds
    assert wait_until(lambda: sim.mode == MODE_HOLD, 6.0)
    assert sim.reached == [1, 2]


def test_mavsdk_reports_the_arming_refusal_and_holds_by_rover_mode(mavsdk_gcs_and_boat):
    sim, system = mavsdk_gcs_and_boat
    action = Action(system)
    with pytest.raises(ActionError) as info:
        action.arm()
    assert info.value.result == ActionResult.COMMAND_DENIED
    action.hold()  # MAVSDK picks Rover's HOLD (4) for an ArduPilot boat
    assert sim.mode == MODE_HOLD
    assert mavlink.MAV_CMD_COMPONENT_ARM_DISARM in sim.commands
