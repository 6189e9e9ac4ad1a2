"""Usage and user errors of the field commands, through a real subprocess: exit 2, one reason, no
traceback; user text with rich markup (``[/x]``) is printed as written."""

import os
import subprocess
import sys
from pathlib import Path

import pytest


def _run(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "oceanloc", *args], capture_output=True, text=True, env=os.environ, cwd=cwd
    )


@pytest.mark.parametrize(
    ("args", "reason"),
    [
        (["localize", "logs", "[/x]gps.nmea", "r.csv"], "[/x]gps.nmea: file not found"),
        (["localize", "logs", "gps.nmea", "ranges.csv", "--origin", "95,0"], "--origin: LAT 95 is outside"),
        (["localize", "logs", "gps.nmea", "ranges.csv", "--truth", "[b]t.json"], "[b]t.json: cannot read"),
        (
            ["localize", "noise", "gps.nmea", "ranges.csv", "--window", "0"],
            "--max-speed and --window positive",
        ),
        (["localize", "gnssa", "--site-velocity", "EURX"], "'EURX' is none of auto, none"),
        (["replay", "logs", "gps.nmea", "ranges.csv", "--planners", "k11"], "unknown planner 'k11'"),
        (["replay", "logs", "gps.nmea", "ranges.csv", "--prior-sigma", "1,2"], "--prior-sigma must be 3"),
        (["replay", "gnssa", "--runs", "0"], "Invalid value for '--runs'"),
        (["simulate", "logs", "--site", "1,2,3,4"], "--site: expected LAT,LON[,H]"),
        (["survey", "start", "j.db", "--planner", "k0x"], "unknown planner 'k0x'"),
    ],
)
def test_field_usage_errors_exit_2_with_one_reason(tmp_path: Path, args: list[str], reason: str):
    # gps.nmea and ranges.csv exist but are not valid logs: the option errors come first
    (tmp_path / "gps.nmea").write_text("")
    (tmp_path / "ranges.csv").write_text("")
    res = _run(*args, cwd=tmp_path)
    err = " ".join(res.stderr.split())
    assert res.returncode == 2, (args, res.stdout, res.stderr)
    assert reason in err and "Traceback" not in res.stderr + res.stdout, (args, err)
