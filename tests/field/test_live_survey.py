"""The live survey loop's parts: the stop rule, the options' checks, the status line, and the loop itself
in process on loopback UDP sources (NMEA 0183 and range lines) in a dry run."""

from __future__ import annotations

import datetime as dt
import math
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from oceanloc.config.survey import PlannerSettings
from oceanloc.errors import ConfigError
from oceanloc.field.live_sources import position_opener, range_opener
from oceanloc.field.live_survey import LiveOptions, StopRule, check_stop, run_live_survey
from oceanloc.field.survey.estimates import survey_estimates
from oceanloc.field.survey.journal import Journal
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.geo.projection import LocalProjection
from oceanloc.io.nmea import format_gga, format_zda
from oceanloc.report.tables.live import epoch_line, result_lines

LOOPBACK = "127.0.0.1"
LAT0, LON0 = 32.70, -117.25
TARGET = np.array([40.0, 30.0, -50.0])


def _records_journal(tmp_path: Path, n: int = 40) -> tuple[Journal, JournalSettings]:
    """A journal of fixes on a circle of 60 m about the origin and exact ranges to TARGET."""
    settings = JournalSettings(beacons=(1,), sigma_range_m=0.1, prior_sigma_enu_m=(100.0, 100.0, 30.0),
                               prior_depth_m=40.0, origin=None)  # fmt: skip
    j = Journal.start(tmp_path / "j.db", settings.to_meta())
    proj = LocalProjection(lat0_deg=LAT0, lon0_deg=LON0)
    t0 = 1.8e9
    for k in range(n):
        a = 2.0 * math.pi * k / n
        e, nn = 60.0 * math.cos(a), 60.0 * math.sin(a)
        lon, lat = proj.to_lonlat(e, nn)
        j.add_fix(t0 + k, float(lat), float(lon), 0.0)
        j.add_range(t0 + k, 1, float(np.linalg.norm(TARGET - [e, nn, 0.0])))
    return j, settings


def test_the_stop_rule_needs_every_beacon_within_the_goal_and_trusted(tmp_path: Path):
    j, settings = _records_journal(tmp_path)
    est = survey_estimates(j.records(), settings)
    a95 = float(est.ellipses.semi_major_m[0])
    assert est.trusted[0]
    done = check_stop(est, settings, StopRule(goal_m=a95 * 1.01), elapsed_s=0.0, sites=0)
    assert done.done and done.status == "goal" and done.met == (True,)
    assert f"largest {a95:.2f} m" in done.reason
    going = check_stop(est, settings, StopRule(goal_m=a95 * 0.99), elapsed_s=0.0, sites=0)
    assert not going.done and going.met == (False,)
    # a survey beacon not estimated yet keeps the survey going, whatever the others' ellipses
    two = JournalSettings(beacons=(1, 2), sigma_range_m=0.1)
    assert not check_stop(est, two, StopRule(goal_m=a95 * 2.0), elapsed_s=0.0, sites=0).done
    # the budgets
    t = check_stop(est, settings, StopRule(goal_m=1e-3, max_time_s=60.0), elapsed_s=60.0, sites=0)
    assert t.done and t.status == "time"
    s = check_stop(None, settings, StopRule(max_sites=5), elapsed_s=0.0, sites=5)
    assert s.done and s.status == "sites"
    j.close()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({}, "needs a stop rule"),
        ({"goal_m": -1.0}, "goal_m must be a positive number"),
        ({"max_time_s": math.inf}, "max_time_s must be a positive number"),
        ({"max_sites": 0}, "max_sites must be 1 or more"),
    ],
)
def test_bad_stop_rules_are_refused_with_the_field(kwargs: dict, message: str):
    with pytest.raises(ConfigError, match=message):
        StopRule(**kwargs)


def test_bad_options_are_refused_with_the_field():
    rule = StopRule(max_sites=1)
    with pytest.raises(ConfigError, match="geofence radius must be a positive"):
        LiveOptions(stop=rule, fence_radius_m=0.0)
    with pytest.raises(ConfigError, match="maximum leg must be a positive"):
        LiveOptions(stop=rule, max_leg_m=-5.0)
    with pytest.raises(ConfigError, match="ping interval"):
        LiveOptions(stop=rule, ping_interval_s=math.nan)
    with pytest.raises(ConfigError, match="needs --vehicle SPEC"):
        run_live_survey("x.db", position=dict, ranges=dict, vehicle=None, options=LiveOptions(stop=rule))


def _udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind((LOOPBACK, 0))
        return s.getsockname()[1]


class _Sender(threading.Thread):
    """Sends a boat's NMEA and ranges to TARGET over UDP, as a GNSS and a modem on the boat's LAN would."""

    def __init__(self, nmea_port: int, range_port: int) -> None:
        super().__init__(daemon=True)
        self.ports = (nmea_port, range_port)
        self.stop = threading.Event()
        self.proj = LocalProjection(lat0_deg=LAT0, lon0_deg=LON0)

    def run(self) -> None:
        k = 0
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            while not self.stop.is_set():
                now = dt.datetime.now(dt.UTC)
                t = now.replace(microsecond=(now.microsecond // 10_000) * 10_000)
                a = 0.05 * k
                e, n = 60.0 * math.cos(a), 60.0 * math.sin(a)
                lon, lat = self.proj.to_lonlat(e, n)
                text = format_gga(t, float(lat), float(lon), 0.0) + "\r\n" + format_zda(t) + "\r\n"
                s.sendto(text.encode(), (LOOPBACK, self.ports[0]))
                if k % 2:
                    r = float(np.linalg.norm(TARGET - [e, n, 0.0]))
                    line = f"{t.isoformat().replace('+00:00', 'Z')},1,{r:.3f}\n"
                    s.sendto(line.encode(), (LOOPBACK, self.ports[1]))
                k += 1
                self.stop.wait(0.05)


def test_a_dry_run_on_udp_sources_journals_plans_and_stops_on_its_budget(tmp_path: Path):
    path = tmp_path / "j.db"
    settings = JournalSettings(planner=PlannerSettings(kind="greedy", max_distance_m=20.0), beacons=(1,),
                               sigma_range_m=0.3, prior_sigma_enu_m=(100.0, 100.0, 30.0), prior_depth_m=40.0,
                               max_gap_s=1.0)  # fmt: skip
    Journal.start(path, settings.to_meta()).close()
    nmea, ranges = _udp_port(), _udp_port()
    sender = _Sender(nmea, ranges)
    epochs, notices = [], []
    opts = LiveOptions(stop=StopRule(max_sites=15), dry_run=True, fence_radius_m=100.0, max_leg_m=30.0)
    result = None

    def run() -> None:
        nonlocal result
        result = run_live_survey(
            path, position=position_opener(f"udp://{LOOPBACK}:{nmea}", None),
            ranges=range_opener(f"udp://{LOOPBACK}:{ranges}", sound_speed_mps=1500.0, beacons=(1,)),
            vehicle=None, options=opts, on_epoch=epochs.append, on_notice=notices.append,
        )  # fmt: skip

    runner = threading.Thread(target=run)
    runner.start()
    time.sleep(0.3)  # the loop binds its UDP ports first
    sender.start()
    runner.join(60.0)
    sender.stop.set()
    assert result is not None
    # a dry run is a rehearsal: its site budget counts the sites it would have sent
    assert result.status == "sites" and result.sites == 15, result.message
    with Journal.open(path) as j:
        rec = j.records()
        plans = j.events("plan")
        commands = j.events("command")
    assert rec.n_fixes > 0 and rec.n_ranges > 0
    assert plans and all(p.body["site"]["status"] in ("inside", "clipped") for p in plans)
    assert all(p.body["site"]["leg_m"] <= 30.0 + 1e-6 for p in plans)
    assert {c.body["status"] for c in commands} == {None}
    # the epoch that planned the 15th site stopped the survey (the stop rule follows the command)
    assert epochs[-1].stop.done and epochs[-1].stop.status == "sites" and epochs[-1].waypoint is not None
    line = epoch_line(epochs[-1])
    assert " next " in line and "dry run" in line and "b1 " in line
    assert result_lines(result)[0].startswith("survey ")
