"""``survey run --mission``: the planned sites go to the boat as a mission flown in AUTO, and at the end the
boat is sent back (``--return-to``); in process, with the boat simulator's telemetry as the position
source and the SeaTrac beacon simulator."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from oceanloc.config.survey import PlannerSettings
from oceanloc.field.geofence import WatchdogConfig
from oceanloc.field.live_sources import position_opener, range_opener
from oceanloc.field.live_survey import LiveOptions, StopRule, run_live_survey
from oceanloc.field.survey.journal import Journal
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.io.mavlink_vehicle import MavlinkVehicle
from oceanloc.sim.boat import MODE_AUTO, MODE_GUIDED
from tests.field._live_rig import LAT0, LON0, live_rig

TRANSPONDERS = {3: (40.0, 25.0, -30.0)}


def test_mission_mode_uploads_the_planned_sites_and_flies_them_in_auto(tmp_path: Path):
    path = tmp_path / "j.db"
    settings = JournalSettings(
        planner=PlannerSettings(kind="lookahead", horizon=2), speed_mps=20.0, period_s=2.0,
        max_yaw_rate_rad_s=math.radians(200.0), beacons=(3,), sigma_range_m=0.3, sigma_gps_m=0.0,
        prior_sigma_enu_m=(20.0, 20.0, 10.0), drops=((3, LAT0 + 2.0e-4, LON0 + 4.0e-4, 28.0),), max_gap_s=1.0,
    )  # fmt: skip
    Journal.start(path, settings.to_meta()).close()
    modes = []
    with live_rig(TRANSPONDERS, gpsd=False) as rig:
        vehicle = MavlinkVehicle(rig.vehicle_spec, gcs_heartbeat_hz=20.0)
        try:
            assert vehicle.connect(5.0).ok
            opts = LiveOptions(
                stop=StopRule(max_sites=4), command="mission", fence_radius_m=200.0, ping_interval_s=0.1,
                return_to=(LAT0, LON0),
                watchdog=WatchdogConfig(position_timeout_s=2.0, ranges_timeout_s=5.0, vehicle_timeout_s=2.0),
            )  # fmt: skip
            result = run_live_survey(
                path, position=position_opener("mavlink", vehicle),
                ranges=range_opener(rig.ranges_spec, sound_speed_mps=1500.0, beacons=(3,)), vehicle=vehicle,
                options=opts, on_epoch=lambda e: modes.append(rig.boat.mode),
            )  # fmt: skip
            mission = rig.boat.mission
            final_mode, target = rig.boat.mode, rig.boat.target_en_m
        finally:
            vehicle.close()
    assert result.status == "sites" and result.sites == 4, result.message
    assert MODE_AUTO in modes  # flown in AUTO between uploads
    # the site budget spent, the boat is sent back to the start (--return-to) in GUIDED
    assert final_mode == MODE_GUIDED and target is not None and math.hypot(*target) < 0.05
    assert result.returned is not None and result.returned.ok
    # the last upload: home then the two planned sites of the look-ahead (k = 2)
    assert len(mission) == 3
    with Journal.open(path) as j:
        commands = [e.body for e in j.events("command") if e.body["status"] is not None]
    assert len(commands) == 4 and {c["status"] for c in commands} == {"accepted"}
    assert np.all(np.isfinite([c["latency_ms"] for c in commands]))
