"""The live survey's safety end to end on loopback (boat simulator, real gpsd, SeaTrac beacon simulator,
``oceanloc survey run`` as a subprocess): cutting the MAVLink link or the ranges puts the boat in HOLD
within the timeout; SIGTERM holds it and exits 0; a dry run plans and commands nothing, and serves the
live page meanwhile."""

from __future__ import annotations

import json
import math
import signal
import subprocess
import time
import urllib.request
from pathlib import Path

from oceanloc.sim.boat import MODE_GUIDED, MODE_HOLD
from tests.field._live_rig import NEEDS_GPSD, live_rig, run_command, start_survey, terminate
from tests.field.test_live_survey_end_to_end import DROPS, TRANSPONDERS, _events, _wait_for


@NEEDS_GPSD
def test_cutting_the_vehicle_link_or_the_ranges_holds_the_boat(tmp_path: Path):
    journal = tmp_path / "survey.db"
    with live_rig(TRANSPONDERS) as rig:
        start_survey(journal, DROPS)
        cmd = run_command(rig, journal, "--max-time", "300", "--timeouts", "1,3,1", "--ping-interval", "0.1")
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            _wait_for(lambda: rig.boat.mode == MODE_GUIDED and len(_events(journal, "command")) >= 5, 60.0,
                      "the boat in GUIDED under commands")  # fmt: skip
            # the MAVLink link: the boat's own GCS failsafe holds it (FS_TIMEOUT 5 simulated s = 0.5 s)
            rig.boat.cut_link(True)
            t_cut = time.monotonic()
            _wait_for(lambda: rig.boat.mode == MODE_HOLD, 3.0, "HOLD after the link cut")
            held_after_s = time.monotonic() - t_cut
            _wait_for(lambda: any("no vehicle" in e["message"] for e in _events(journal, "link")), 3.0,
                      "the loop noticing the lost vehicle link")  # fmt: skip
            rig.boat.cut_link(False)
            _wait_for(lambda: rig.boat.mode == MODE_GUIDED, 10.0, "the survey resuming in GUIDED")
            # the ranges: the beacons fall silent; the loop commands HOLD after its 3 s ranges timeout
            rig.beacons.silent = True
            t_mute = time.monotonic()
            _wait_for(lambda: rig.boat.mode == MODE_HOLD, 3.0 + 2.0, "HOLD after the ranges stopped")
            ranges_hold_s = time.monotonic() - t_mute
            _wait_for(lambda: any("no ranges" in e["message"] for e in _events(journal, "link")), 3.0,
                      "the HOLD for the silent ranges journaled")  # fmt: skip
            rig.beacons.silent = False
            _wait_for(lambda: rig.boat.mode == MODE_GUIDED, 10.0, "the survey resuming after the ranges")
            # SIGTERM: HOLD, journal the stop, exit 0
            rc = terminate(proc, signal.SIGTERM)
            err = proc.stderr.read()
        finally:
            if proc.poll() is None:
                proc.kill()
        assert rc == 0, err[-2000:]
        assert rig.boat.mode == MODE_HOLD
    assert "Traceback" not in err
    assert held_after_s <= 1.5
    # 3 s after the last range, which came up to a ping cycle (about 0.15 s) before the beacons fell silent
    assert 3.0 - 0.5 <= ranges_hold_s <= 3.0 + 1.5
    (stop,) = _events(journal, "stop")
    assert stop["status"] == "interrupted"


@NEEDS_GPSD
def test_a_dry_run_plans_and_commands_nothing_and_serves_the_live_page(tmp_path: Path):
    journal = tmp_path / "survey.db"
    with live_rig(TRANSPONDERS) as rig:
        start_survey(journal, DROPS)
        cmd = run_command(
            rig, journal, "--dry-run", "--max-time", "6", "--ping-interval", "0.1", "--serve", "0"
        )
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            first = proc.stderr.readline()  # "live page of JOURNAL: http://127.0.0.1:PORT/"
            url = first.rsplit(" ", 1)[-1].strip()
            assert url.startswith("http://127.0.0.1:"), first
            _wait_for(lambda: len(_events(journal, "plan")) >= 3, 30.0, "three plans")
            with urllib.request.urlopen(url, timeout=10) as page:
                assert page.status == 200 and b"<html" in page.read(2000).lower()

            def data() -> dict:
                with urllib.request.urlopen(url.rstrip("/") + "/data", timeout=10) as answer:
                    return json.loads(answer.read())

            # the page's server reads the journal twice a second: the track is there within a few reads
            _wait_for(lambda: len(data()["fix"]["e"]) > 0, 5.0, "the track on the live page")
            assert "fixes" in data()["status"]["records"]
            out, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
        assert rig.boat.mode == MODE_HOLD
        assert not rig.boat.received.get("SET_POSITION_TARGET_GLOBAL_INT")
    assert proc.returncode == 0, err[-2000:]
    assert "dry run" in out and " next " in out
    plans = _events(journal, "plan")
    assert plans and all(math.isfinite(p["next"]["lat_deg"]) for p in plans)
    assert {c["status"] for c in _events(journal, "command")} == {None}
