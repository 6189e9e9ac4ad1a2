"""``localize logs`` with stray or expected beacons: a stray beacon is listed, never aborts the others."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.field.range_logs import localize_log_files
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "oceanloc", *args], capture_output=True, text=True, env=os.environ, cwd=cwd
    )


@pytest.fixture
def logs(tmp_path: Path) -> Path:
    """A pier log pair with one stray range to beacon 9 in the middle of the GPS track."""
    simulate_pier_logs(
        tmp_path, PierLogSettings(duration_s=300.0, stationary_s=100.0), np.random.default_rng(5)
    )
    path = tmp_path / "ranges.csv"
    lines = [ln for ln in path.read_text().splitlines() if ",9," not in ln]
    k = next(i for i, ln in enumerate(lines) if ln.startswith("2018-01-04T18:02:"))
    lines.insert(k, lines[k].split(",")[0] + ",9,12.5")
    path.write_text("\n".join(lines) + "\n")
    return tmp_path


def test_a_stray_beacon_is_listed_and_the_others_are_solved(logs: Path):
    res = _cli("localize", "logs", "gps.nmea", "ranges.csv", "--json", "out.json", cwd=logs)
    assert res.returncode == 0 and "Traceback" not in res.stderr, res.stderr
    assert "beacon 9: 1 range, not localized (needs 4)" in res.stderr
    record = json.loads((logs / "out.json").read_text())
    assert [b["beacon"] for b in record["beacons"]] == [1, 2]
    assert record["not_localized"] == [{"beacon": 9, "ranges": 1}]


def test_expected_beacons_qc_the_others(logs: Path):
    res = _cli("localize", "logs", "gps.nmea", "ranges.csv", "--beacon", "1", "--beacon", "2", cwd=logs)
    assert res.returncode == 0, res.stderr
    assert "unknown beacon id (9)" in res.stderr and "not localized" not in res.stderr
    only = _cli("localize", "logs", "gps.nmea", "ranges.csv", "--beacon", "1", "--beacon", "5", cwd=logs)
    assert only.returncode == 0 and "beacon 5: 0 ranges, not localized (needs 4)" in only.stderr


def test_no_beacon_with_enough_ranges_is_a_one_line_error(logs: Path):
    res = _cli("localize", "logs", "gps.nmea", "ranges.csv", "--beacon", "9", cwd=logs)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert lines[-1] == (
        "error: ranges.csv: no beacon has the 4 ranges with GPS it needs (ranges per beacon: 9: 1)"
    ), res.stderr
    with pytest.raises(DataError, match="ranges per beacon: 9: 1"):
        localize_log_files(logs / "gps.nmea", logs / "ranges.csv", beacons=[9])
