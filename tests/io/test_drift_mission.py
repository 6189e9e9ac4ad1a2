"""Drift plans to the vehicle (issue 26, section 3): MAVLink mission items, QGroundControl ``.plan`` files
validated against QGroundControl's documented format, the plain-text mission, KML; and the mission flown
by the boat simulator over MAVLink, drifting with the current during the holds."""

from __future__ import annotations

import json
import math
import socket
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from oceanloc.geo.projection import LocalProjection
from oceanloc.io._mavlink import mavlink
from oceanloc.io.missions import (
    drift_mission,
    qgc_plan,
    read_waypoints_text,
    waypoints_text,
    write_qgc_plan,
)
from oceanloc.io.paths import write_path_kml
from oceanloc.models.paths import DriftPath

jsonschema = pytest.importorskip("jsonschema")
SCHEMA = json.loads((Path(__file__).parent / "data" / "qgc_plan.schema.json").read_text())
PROJ = LocalProjection(lat0_deg=32.70, lon0_deg=-117.25)


def plan_path() -> DriftPath:
    """Drift 600 s east, fly 400 m north, drift 300 s, fly 200 m north-east, drift 120 s into the goal."""
    pts, times, flight = [[0.0, 0.0]], [0.0], []
    for k in range(1, 11):
        pts.append([30.0 * k, 0.0])
        times.append(60.0 * k)
        flight.append(False)
    pts.append([300.0, 400.0])
    times.append(640.0)
    flight.append(True)
    for k in range(1, 6):
        pts.append([300.0 + 15.0 * k, 400.0])
        times.append(640.0 + 60.0 * k)
        flight.append(False)
    pts.append([515.0, 541.0])
    times.append(965.0)
    flight.append(True)
    for k in range(1, 3):
        pts.append([515.0 + 20.0 * k, 541.0])
        times.append(965.0 + 60.0 * k)
        flight.append(False)
    return DriftPath(points_m=np.array(pts), times_s=np.array(times), flight=np.array(flight))


def test_boat_mission_holds_for_each_drift_and_drives_each_leg():
    items = drift_mission(plan_path(), PROJ, vehicle="boat")
    commands = [it.command for it in items]
    wp, delay = mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_NAV_DELAY
    assert commands == [wp, delay, wp, delay, wp, delay]
    assert [it.params[0] for it in items if it.command == delay] == [600.0, 300.0, 120.0]
    assert all(it.frame == mavlink.MAV_FRAME_MISSION for it in items if it.command == delay)
    lon, lat = PROJ.to_lonlat(np.array([300.0, 515.0]), np.array([400.0, 541.0]))
    legs = [it for it in items[1:] if it.command == wp]
    np.testing.assert_allclose([(it.lat_deg, it.lon_deg) for it in legs], np.column_stack([lat, lon]))
    assert (items[0].lat_deg, items[0].lon_deg) == pytest.approx((32.70, -117.25))


def test_aquaquad_mission_takes_off_flies_lands_and_drifts():
    items = drift_mission(plan_path(), PROJ, vehicle="aquaquad", altitude_m=15.0)
    c = mavlink
    assert [it.command for it in items] == [
        c.MAV_CMD_NAV_WAYPOINT,
        c.MAV_CMD_NAV_DELAY,
        c.MAV_CMD_NAV_TAKEOFF,
        c.MAV_CMD_NAV_WAYPOINT,
        c.MAV_CMD_NAV_LAND,
        c.MAV_CMD_NAV_DELAY,
        c.MAV_CMD_NAV_TAKEOFF,
        c.MAV_CMD_NAV_WAYPOINT,
        c.MAV_CMD_NAV_LAND,
        c.MAV_CMD_NAV_DELAY,
    ]
    assert items[3].alt_m == 15.0 and items[4].alt_m == 0.0


def test_loiter_items_are_the_alternative_to_holds():
    items = drift_mission(plan_path(), PROJ, drift_item="loiter")
    loiters = [it for it in items if it.command == mavlink.MAV_CMD_NAV_LOITER_TIME]
    assert len(loiters) == 3 and loiters[0].params[0] == 600.0
    assert loiters[0].params[2] == pytest.approx(300.0)  # the drift's extent as the loiter radius


@pytest.mark.parametrize("vehicle", ["boat", "aquaquad"])
def test_qgroundcontrol_plan_is_valid_against_the_documented_format(tmp_path, vehicle):
    items = drift_mission(plan_path(), PROJ, vehicle=vehicle)
    plan = qgc_plan(items, vehicle=vehicle, cruise_speed_mps=2.5)
    path = write_qgc_plan(tmp_path / "drift.plan", plan)
    loaded = json.loads(path.read_text())
    jsonschema.validate(loaded, SCHEMA)
    mission = loaded["mission"]
    assert mission["firmwareType"] == mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
    expected = mavlink.MAV_TYPE_SURFACE_BOAT if vehicle == "boat" else mavlink.MAV_TYPE_QUADROTOR
    assert mission["vehicleType"] == expected
    assert [it["doJumpId"] for it in mission["items"]] == list(range(1, len(items)))
    assert mission["plannedHomePosition"][:2] == pytest.approx([32.70, -117.25])


@pytest.mark.parametrize(
    "break_it",
    [
        lambda p: p.update(fileType="Mission"),
        lambda p: p["mission"]["items"][0]["params"].pop(),
        lambda p: p["mission"].pop("plannedHomePosition"),
        lambda p: p["mission"].update(items=[]),
        lambda p: p["mission"]["items"][0].update(type="ComplexThing"),
    ],
)
def test_the_schema_rejects_what_qgroundcontrol_would(break_it):
    plan = qgc_plan(drift_mission(plan_path(), PROJ))
    break_it(plan)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(plan, SCHEMA)


def test_plain_text_mission_round_trips():
    items = drift_mission(plan_path(), PROJ, vehicle="aquaquad")
    text = waypoints_text(items)
    assert text.startswith("QGC WPL 110\n0\t1\t")
    back = read_waypoints_text(text)
    assert [it.command for it in back] == [it.command for it in items]
    np.testing.assert_allclose([it.lat_deg for it in back], [it.lat_deg for it in items], atol=1e-8)


def test_kml_has_drift_powered_and_point_layers(tmp_path):
    path = write_path_kml(tmp_path / "plan.kml", plan_path(), PROJ, "drift plan")
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    root = ET.parse(path).getroot()
    folders = {f.find("k:name", ns).text: f for f in root.iter(f"{{{ns['k']}}}Folder")}
    assert set(folders) == {"drift legs", "powered legs", "take-off and landing points"}
    assert len(folders["drift legs"].findall("k:Placemark", ns)) == 3
    assert len(folders["powered legs"].findall("k:Placemark", ns)) == 2
    assert len(folders["take-off and landing points"].findall("k:Placemark", ns)) == 4


# -- to the vehicle: upload to the boat simulator and fly -------------------------------------------------


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_drift_mission_uploads_and_the_boat_drifts_during_the_holds():
    from oceanloc.io.mavlink_vehicle import MavlinkVehicle
    from oceanloc.sim.boat import MODE_AUTO, MODE_HOLD, BoatParams, BoatSimulator

    # A short plan: drift 4 s, drive 20 m north, drift 4 s, drive 20 m east (the simulator runs 10x).
    path = DriftPath(
        points_m=np.array([[0.0, 0.0], [1.2, 0.0], [1.2, 20.0], [2.4, 20.0], [22.4, 20.0]]),
        times_s=np.array([0.0, 4.0, 8.0, 12.0, 16.0]),
        flight=np.array([False, True, False, True]),
    )
    items = drift_mission(path, PROJ)
    port = _free_port()
    vehicle = MavlinkVehicle(f"udp://127.0.0.1:{port}", heartbeat_timeout_s=1.0, command_timeout_s=1.0)
    sim = BoatSimulator(
        f"udpout:127.0.0.1:{port}",
        start_lat_deg=32.70,
        start_lon_deg=-117.25,
        time_scale=10.0,
        params=BoatParams(current_enu_mps=(0.3, 0.0)),
    )
    sim.start()
    try:
        assert vehicle.connect(wait_heartbeat_s=3.0).status == "connected"
        up = vehicle.upload_mission_items(items)
        assert up.status == "accepted", up.message
        stored = sim.mission
        assert [it.command for it in stored] == [it.command for it in items]
        assert stored[1].param1 == pytest.approx(4.0)
        assert vehicle.start_mission().status == "accepted"
        assert sim.mode == MODE_AUTO
        # In the first hold the boat drifts east with the current, its motors stopped.
        deadline = time.monotonic() + 5.0
        while sim.truth().mission_seq < 2 and time.monotonic() < deadline:
            time.sleep(0.01)
        deadline = time.monotonic() + 30.0
        while sim.mode != MODE_HOLD and time.monotonic() < deadline:
            time.sleep(0.05)
        assert sim.mode == MODE_HOLD
        assert sim.reached == [1, 2, 3, 4]
        end = sim.truth()
        lon, lat = PROJ.to_lonlat(22.4, 20.0)
        east = (end.lon_deg - lon) * math.cos(math.radians(32.7)) * 111_320.0
        north = (end.lat_deg - lat) * 110_900.0
        assert math.hypot(east, north) < BoatParams().wp_radius_m + 2.0
    finally:
        vehicle.close()
        sim.stop()
    assert sim.error is None
