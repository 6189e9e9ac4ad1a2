"""The live survey end to end on loopback: the boat simulator (ArduPilot Rover's dialect), the real gpsd and
the SeaTrac beacon simulator, with ``oceanloc survey run`` as a subprocess of the installed package.

Two hidden transponders; the simulators run ten times faster than real time (the journal's seconds are
wall seconds: see tests/field/_live_rig.py). Asserted: the survey stops by its rule with every
transponder within 3 sigma of its estimate; a kill -9 mid-survey and a restart of the same command
finish it with every committed record kept; no commanded site leaves the geofence; on the time the
planned survey took, its information (log det at the truth) beats a circle and a lawnmower flown by the
same boat. The safety tests (link loss, SIGTERM, dry run) are in test_live_survey_safety.py.
"""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from oceanloc.field.geofence import contains, fence_from_radius
from oceanloc.geo.enu import EnuOrigin, geodetic_to_enu
from oceanloc.io.mavlink_vehicle import MavlinkVehicle
from oceanloc.io.seatrac import SeatracPinger
from tests.field._live_rig import (
    LAT0,
    LON0,
    NEEDS_GPSD,
    SITL_ENV,
    circle_waypoints,
    interpolate_track,
    lawnmower_waypoints,
    live_rig,
    range_information,
    run_command,
    start_survey,
)

TRANSPONDERS = {1: (30.0, 20.0, -20.0), 2: (-22.0, 38.0, -15.0)}
DROPS = {1: (38.0, 14.0, 18.0), 2: (-30.0, 44.0, 17.0)}  # where the crew dropped them: 10 m off, depth 2 m
SIGMA_RANGE_M = 0.3  # the survey's range sigma (see tests/field/_live_rig.py: start_survey)
PRIOR_SIGMA_M = np.array([15.0, 15.0, 8.0])
FENCE_RADIUS_M = 80.0
RUN = ("--goal", "0.8", "--max-time", "120", "--fence-radius", str(FENCE_RADIUS_M), "--max-leg", "25",
       "--timeouts", "1,3,1", "--ping-interval", "0.1")  # fmt: skip


def _rows(path: Path, table: str) -> list[tuple]:
    with sqlite3.connect(f"file:{path}?mode=ro", uri=True) as db:
        return db.execute(f"SELECT * FROM {table}").fetchall()


def _events(path: Path, kind: str) -> list[dict]:
    return [json.loads(r[3]) for r in _rows(path, "events") if r[2] == kind]


def _wait_for(predicate, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.05)
    pytest.fail(f"timed out after {timeout_s} s waiting for {what}")


def _journal_origin(path: Path) -> EnuOrigin:
    _t, lat, lon, h = min(_rows(path, "fixes"))
    return EnuOrigin(lat_deg=lat, lon_deg=lon, h_m=h)


def _truth_in(origin: EnuOrigin) -> dict[int, np.ndarray]:
    """The hidden transponders (ENU about the boat's start) in the journal's ENU frame."""
    from oceanloc.geo.enu import enu_to_geodetic

    start = EnuOrigin(lat_deg=LAT0, lon_deg=LON0, h_m=0.0)
    out = {}
    for b, p in TRANSPONDERS.items():
        g = enu_to_geodetic(np.array(p), start)
        out[b] = geodetic_to_enu(g[0], g[1], g[2], origin).reshape(3)
    return out


def _journal_log_det(path: Path, n_ranges: int) -> float:
    """Sum over beacons of log det Y at the truth from the journal's first ``n_ranges`` ranges."""
    origin = _journal_origin(path)
    truth = _truth_in(origin)
    fixes = np.array(sorted(_rows(path, "fixes")))
    track = geodetic_to_enu(fixes[:, 1], fixes[:, 2], fixes[:, 3], origin).reshape(-1, 3)
    ranges = np.array(sorted(_rows(path, "ranges")))[:n_ranges]
    keep = np.ones(ranges.shape[0], dtype=bool)
    total = 0.0
    for b, target in truth.items():
        t = ranges[keep & (ranges[:, 1] == b), 0]
        total += range_information(interpolate_track(fixes[:, 0], track[:, :2], t), target, SIGMA_RANGE_M,
                                   PRIOR_SIGMA_M)  # fmt: skip
    return total


def _fly_pattern(waypoints, n_ranges: int) -> float:
    """Fly a mission with the same boat, beacons and pinging for ``n_ranges`` ranges; their log det."""
    with live_rig(TRANSPONDERS, gpsd=False, seed=5) as rig:
        vehicle = MavlinkVehicle(rig.vehicle_spec, gcs_heartbeat_hz=20.0)
        track: list[tuple[float, float, float]] = []
        stop = threading.Event()

        def sample() -> None:
            while not stop.is_set():
                tr = rig.boat.truth()
                track.append((time.time(), tr.east_m, tr.north_m))
                stop.wait(0.01)

        sampler = threading.Thread(target=sample, daemon=True)
        sampler.start()
        try:
            assert vehicle.connect(5.0).ok
            _wait_for(lambda: vehicle.latest_fix() is not None, 5.0, "a vehicle fix")
            assert vehicle.upload_mission(waypoints).ok
            ranges = []
            port = rig.ranges_spec.split("://")[1].split("?")[0]
            with SeatracPinger(port, beacons=sorted(TRANSPONDERS), timeout_s=2.0) as pinger:
                assert vehicle.start_mission().ok
                while len(ranges) < n_ranges:
                    for b in sorted(TRANSPONDERS):
                        rec = pinger.ping(b)
                        if rec.ok:
                            ranges.append((rec.t_unix_s, b))
                        time.sleep(0.1)
        finally:
            stop.set()
            sampler.join(1.0)
            vehicle.close()
    tr = np.array(track)
    rr = np.array(ranges)[:n_ranges]
    total = 0.0
    for b, target in TRANSPONDERS.items():
        t = rr[rr[:, 1] == b, 0]
        total += range_information(interpolate_track(tr[:, 0], tr[:, 1:], t), np.array(target), SIGMA_RANGE_M,
                                   PRIOR_SIGMA_M)  # fmt: skip
    return total


@NEEDS_GPSD
@pytest.mark.parametrize(
    "boat",
    [
        "simulator",
        pytest.param("sitl", marks=pytest.mark.skipif(
            not os.environ.get(SITL_ENV), reason=f"set {SITL_ENV} to an ArduPilot ardurover SITL binary")),
    ],
)  # fmt: skip
def test_planned_survey_stops_by_its_rule_and_survives_kill_9(tmp_path: Path, boat: str):
    """With ``OCEANLOC_SITL`` set, the same test runs with ArduPilot's SITL motorboat as the boat."""
    journal = tmp_path / "survey.db"
    lines = tmp_path / "epochs.jsonl"
    with live_rig(TRANSPONDERS, sitl_folder=tmp_path if boat == "sitl" else None) as rig:
        start_survey(journal, DROPS)
        cmd = run_command(rig, journal, *RUN, "--json-lines", str(lines))
        first = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            _wait_for(lambda: len(_events(journal, "command")) >= 8, 60.0, "8 commands of the first run")
        finally:
            first.kill()  # kill -9: no chance to flush, hold or journal a stop
            first.wait(10)
        assert first.returncode == -signal.SIGKILL
        committed = {t: set(_rows(journal, t)) for t in ("fixes", "ranges", "headings", "usbl", "events")}
        assert not _events(journal, "stop")
        n_before = len(_events(journal, "command"))
        second = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            _wait_for(lambda: len(_events(journal, "command")) >= n_before + 3, 60.0, "the resumed run")
            # `survey status` works on a journal that is being written
            status = subprocess.run(
                [sys.executable, "-m", "oceanloc", "survey", "status", str(journal)],
                capture_output=True, text=True, timeout=60,
            )  # fmt: skip
            _out, err = second.communicate(timeout=120)
        finally:
            if second.poll() is None:
                second.kill()
    assert status.returncode == 0 and "Beacons, ENU" in status.stdout, status.stderr
    assert second.returncode == 0, err[-2000:]
    assert "Traceback" not in err
    # nothing committed was lost
    for table, rows in committed.items():
        assert rows <= set(_rows(journal, table)), table
    starts = _events(journal, "start")
    assert [s["resumed"] for s in starts] == [False, True]
    assert "resuming the survey" in err
    # stopped by its rule, every transponder within its reported 3 sigma
    (stop,) = _events(journal, "stop")
    assert stop["status"] == "goal", stop["message"]
    origin = _journal_origin(journal)
    truth = _truth_in(origin)
    beacons = stop["estimates"]["beacons"]
    assert sorted(e["beacon"] for e in beacons) == sorted(TRANSPONDERS)
    for e in beacons:
        error = np.array(e["enu_m"]) - truth[e["beacon"]]
        print(f"beacon {e['beacon']}: error {np.round(error, 3)} m, sigma {np.round(e['sigma_enu_m'], 3)} m")
        assert np.all(np.abs(error) <= 3.0 * np.array(e["sigma_enu_m"])), (e["beacon"], error)
        assert e["ellipse95_semi_major_m"] <= 0.8 and e["ellipse_trusted"]
    # no commanded site left the geofence (a radius about the first fix)
    fence = fence_from_radius(origin.lat_deg, origin.lon_deg, FENCE_RADIUS_M)
    sites = [p["site"] for p in _events(journal, "plan") if p["site"]["status"] != "refused"]
    assert sites and all(bool(contains(fence, s["lat_deg"], s["lon_deg"])) for s in sites)
    assert all(s["leg_m"] <= 25.0 + 1e-6 for s in sites)
    # the status lines: one JSON object per epoch, with estimates, next site, gain and link states
    epochs = [json.loads(x) for x in lines.read_text().splitlines() if '"epoch"' in x]
    assert epochs and {"beacons", "next", "links", "latency_ms"} <= set(epochs[-1])


@NEEDS_GPSD
def test_on_the_same_time_the_planned_survey_beats_a_circle_and_a_lawnmower(tmp_path: Path):
    """The time budget is counted in ping cycles (one range every 0.1 s of wall time plus its flight): the
    simulators' cadence on a loaded machine varies from run to run, the number of pings does not. The
    patterns are laid out from the drop positions, as a crew would: a circle about their centre through
    both, and a lawnmower over the square around them (14 m between lines)."""
    journal = tmp_path / "survey.db"
    with live_rig(TRANSPONDERS) as rig:
        start_survey(journal, DROPS)
        cmd = run_command(rig, journal, "--max-time", "12", "--ping-interval", "0.1")  # 120 simulated s
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr[-2000:]
    n = len(_rows(journal, "ranges"))
    assert n >= 30
    planned = _journal_log_det(journal, n)
    drops = np.array([d[:2] for d in DROPS.values()])
    centre, radius = drops.mean(axis=0), 0.5 * float(np.linalg.norm(drops[0] - drops[1]))
    circle = _fly_pattern(circle_waypoints(rig.proj, centre, radius), n)
    mower = _fly_pattern(lawnmower_waypoints(rig.proj, centre, 35.0, 14.0), n)
    print(f"log det over {n} ranges: planned {planned:.2f}, circle {circle:.2f}, lawnmower {mower:.2f}")
    assert planned > circle and planned > mower
