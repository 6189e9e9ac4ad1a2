import json
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pymap3d
import pytest
from typer.testing import CliRunner

from oceanloc.cli.app import app, main
from oceanloc.field.survey.estimates import next_waypoint, survey_estimates
from oceanloc.field.survey.journal import Journal
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.io.nmea import read_nmea
from oceanloc.io.usbl import read_usbl
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

START = ["--planner", "greedy", "--max-distance", "4", "--beacon", "1", "--beacon", "2"]


def _logs(folder: Path, duration_s: float, seed: int = 5) -> tuple[Path, Path]:
    settings = PierLogSettings(duration_s=duration_s, stationary_s=min(400.0, duration_s / 3))
    logs = simulate_pier_logs(folder, settings, np.random.default_rng(seed))
    return logs.nmea_path, logs.ranges_path


def _run(args: list[str], capsys) -> tuple[int, str, str]:
    """Run the console script in-process: (exit status, stdout, stderr) with whitespace collapsed."""
    try:
        main(args)
        code = 0
    except SystemExit as exc:
        code = int(exc.code)
    out, err = capsys.readouterr()
    return code, " ".join(out.split()), " ".join(err.split())


def _invoke(args: list[str]) -> str:
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    return " ".join(res.output.split())


def test_start_add_status_next_export(tmp_path: Path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # short relative paths in the messages
    nmea, ranges = _logs(Path("."), 300.0)
    journal = "s.db"
    out = _invoke(["survey", "start", journal, *START])
    assert "planner greedy, d_max 4 m" in out and "beacons 1, 2" in out
    add = ["survey", "add", journal, "--nmea", str(nmea), "--ranges", str(ranges)]
    first = _invoke(add)
    n_fix, n_rng = read_nmea(nmea).n_fixes, read_usbl(ranges, beacons=(1, 2)).t_unix_s.size
    assert f"gps.nmea: {n_fix} fixes ({n_fix} new, 0 already stored)" in first
    assert f"ranges.csv: {n_rng} ranges ({n_rng} new, 0 already stored)" in first
    assert "gps.nmea:11: truncated sentence" in first and "ranges.csv:117: unknown beacon id (9)" in first
    again = _invoke(add)
    assert f"{n_fix} fixes (0 new, {n_fix} already stored)" in again
    assert f"{n_rng} ranges (0 new, {n_rng} already stored)" in again
    with Journal.open(journal) as j:
        assert j.fixes().shape[0] == n_fix and j.ranges().shape[0] == n_rng

    out = _invoke(["survey", "status", journal, "--json", "st.json"])
    assert f"{n_fix} fixes" in out and "Beacons, ENU from" in out and "(earliest fix)" in out
    status = json.loads(Path("st.json").read_text())
    assert status["provenance"]["inputs"][0]["path"] == journal and status["fixes"] == n_fix
    assert [b["beacon"] for b in status["beacons"]] == [1, 2]
    assert sum(status["ranges"].values()) == n_rng
    in_estimates = sum(b["ranges_used"] + b["ranges_excluded"] for b in status["beacons"])
    assert in_estimates == status["ranges"]["used"] + status["ranges"]["outlier"]
    assert f"ranges: {status['ranges']['used']} used, {status['ranges']['outlier']} outlier" in out

    out = _invoke(["survey", "next", journal, "--json", "next.json"])
    assert "go 4.00 m on bearing" in out and "deg (clockwise from true north)" in out
    assert "heading deg" in out and "lat deg" in out
    nxt = json.loads(Path("next.json").read_text())
    assert nxt["planner"] == "greedy" and nxt["distance_m"] <= 4.0 + 1e-9
    with Journal.open(journal) as j:
        rec, settings = j.records(), JournalSettings.from_meta(j.meta())
    w = next_waypoint(rec, settings)
    assert [nxt["next"]["e_m"], nxt["next"]["n_m"]] == w.next_enu_m[:2].tolist()
    assert [nxt["next"]["lat_deg"], nxt["next"]["lon_deg"]] == w.next_geodetic[:2].tolist()

    out = _invoke(["survey", "export", journal, "--geojson", "s.geojson", "--csv", "csv"])
    assert "wrote s.geojson (2 beacons with ellipses, track of" in out
    features = json.loads(Path("s.geojson").read_text())["features"]
    assert [f["geometry"]["type"] for f in features] == ["Point", "Polygon", "Point", "Polygon", "LineString"]
    assert sorted(p.name for p in Path("csv").iterdir()) == [
        "estimates.csv",
        "fixes.csv",
        "headings.csv",
        "ranges.csv",
    ]


def test_manual_records_and_next_from_the_lookahead(tmp_path: Path, capsys):
    journal = str(tmp_path / "m.db")
    assert (
        _run(["survey", "start", journal, "--planner", "lookahead", "-k", "2", "--heading", "90"], capsys)[0]
        == 0
    )
    fixes = [f"2018-01-04T18:00:{k:02d}Z,32.705,{-117.236 + 1e-5 * (k % 3)},0" for k in range(12)]
    beacon_enu = np.array([5.0, 3.0, -10.0])
    args = ["survey", "add", journal]
    for text in fixes:
        args += ["--fix", text]
    for k, (t, lat, lon, h) in enumerate(t.split(",") for t in fixes):
        e, n, u = pymap3d.geodetic2enu(float(lat), float(lon), float(h), 32.705, -117.236, 0.0)
        args += ["--range", f"{t},1,{np.linalg.norm(beacon_enu - [e, n, u]) + 0.01 * (-1) ** k:.4f}"]
    code, out, _ = _run(args, capsys)
    assert code == 0 and "--fix: 12 fixes (12 new, 0 already stored)" in out
    assert "--range: 12 ranges (12 new, 0 already stored)" in out
    code, out, _ = _run(args, capsys)
    assert "--fix: 12 fixes (0 new, 12 already stored)" in out
    code, out, _ = _run(["survey", "next", journal, "--json", str(tmp_path / "n.json")], capsys)
    assert code == 0, out
    nxt = json.loads((tmp_path / "n.json").read_text())
    assert nxt["heading_source"] == "fixes" and len(nxt["waypoints"]) == 2
    assert nxt["distance_m"] == pytest.approx(5.0)  # speed 1 m/s, period 5 s


WRITER_TIMEOUT_S = 120.0


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> tuple[Path, Path, Path]:
    """Simulated logs and the journal of one uninterrupted ``survey add`` of both: (nmea, ranges, journal)."""
    folder = tmp_path_factory.mktemp("stream")
    # 3 hours: the add commits in transactions of APPEND_CHUNK records, so the log spans several.
    nmea, ranges = _logs(folder, 10_800.0, seed=11)
    whole = folder / "whole.db"
    _invoke(["survey", "start", str(whole), *START])
    _invoke(["survey", "add", str(whole), "--nmea", str(nmea), "--ranges", str(ranges)])
    return nmea, ranges, whole


@pytest.mark.parametrize("stream", ["gps+ranges", "ranges"])
def test_killed_add_loses_nothing_and_resumes_identically(tmp_path: Path, capsys, stream: str, uninterrupted):
    nmea, ranges, whole = uninterrupted
    killed = tmp_path / "killed.db"
    assert _run(["survey", "start", str(killed), *START], capsys)[0] == 0
    files = (
        ["--ranges", str(ranges)] if stream == "ranges" else ["--nmea", str(nmea), "--ranges", str(ranges)]
    )

    def add(path: Path, sources: list[str]) -> list[str]:
        return ["survey", "add", str(path), *sources]

    # Kill the writer once 100 records of the stream's first table are committed.
    table = "ranges" if stream == "ranges" else "fixes"
    proc = subprocess.Popen(
        [sys.executable, "-m", "oceanloc.cli.app", *add(killed, files)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    watch = sqlite3.connect(killed, timeout=30.0)
    deadline = time.monotonic() + WRITER_TIMEOUT_S
    while watch.execute(f"SELECT count(*) FROM {table}").fetchone()[0] < 100 and time.monotonic() < deadline:
        assert proc.poll() is None, "the writer finished before it could be killed"
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    watch.close()
    assert proc.returncode == -signal.SIGKILL

    gps, rng = read_nmea(nmea), read_usbl(ranges, beacons=(1, 2))
    with Journal.open(killed) as j:
        cut = j.records()
    n, m = cut.n_fixes, cut.n_ranges
    assert (
        (100 <= n < gps.n_fixes and m == 0) if table == "fixes" else (n == 0 and 100 <= m < rng.t_unix_s.size)
    )
    # Committed records are an unbroken prefix of the stream (each fix followed by its HDT, then the ranges).
    np.testing.assert_array_equal(cut.fix_t_unix_s, gps.t_unix_s[:n])
    np.testing.assert_array_equal(cut.lat_deg, gps.lat_deg[:n])
    np.testing.assert_array_equal(cut.heading_deg, gps.heading_deg[: cut.heading_deg.size])
    assert cut.heading_deg.size in (n - 1, n) or n == 0
    np.testing.assert_array_equal(cut.range_t_unix_s, rng.t_unix_s[:m])
    np.testing.assert_array_equal(cut.range_m, rng.range_m[:m])
    # Re-running the same add completes the journal; then its state is that of an uninterrupted run.
    code, out, _ = _run(add(killed, files), capsys)
    assert (
        code == 0 and f"{rng.t_unix_s.size} ranges ({rng.t_unix_s.size - m} new, {m} already stored)" in out
    )
    if stream != "ranges":
        assert f"{gps.n_fixes} fixes ({gps.n_fixes - n} new, {n} already stored)" in out
    if stream == "ranges":  # the GPS log too, to compare with the uninterrupted run of both files
        assert _run(add(killed, ["--nmea", str(nmea)]), capsys)[0] == 0
    with Journal.open(killed) as a, Journal.open(whole) as b:
        ra, rb = a.records(), b.records()
        settings = JournalSettings.from_meta(a.meta())
    for field in (
        "fix_t_unix_s",
        "lat_deg",
        "lon_deg",
        "h_m",
        "range_t_unix_s",
        "beacon",
        "range_m",
        "heading_deg",
    ):
        np.testing.assert_array_equal(getattr(ra, field), getattr(rb, field))
    assert ra.n_ranges == rng.t_unix_s.size
    ea, eb = survey_estimates(ra, settings), survey_estimates(rb, settings)
    np.testing.assert_array_equal(ea.positions_enu_m, eb.positions_enu_m)
    np.testing.assert_array_equal(ea.covariances_m2, eb.covariances_m2)
    np.testing.assert_array_equal(ea.range_status, eb.range_status)
    np.testing.assert_array_equal(
        next_waypoint(ra, settings).next_enu_m, next_waypoint(rb, settings).next_enu_m
    )


def test_user_errors_are_one_line_messages_and_lose_nothing(tmp_path: Path, capsys):
    nmea, ranges = _logs(tmp_path, 300.0)
    journal = str(tmp_path / "s.db")
    text = tmp_path / "notes.txt"
    text.write_text("hello\n" * 100)
    Journal(tmp_path / "raw.db").close()
    cases = [
        (["survey", "status", str(tmp_path / "none.db")], "none.db: no survey journal here"),
        (
            ["survey", "add", str(tmp_path / "raw.db"), "--fix", "1.6e9,0,0,0"],
            "raw.db: survey journal was never started",
        ),
        (["survey", "next", str(text)], "notes.txt: not a survey journal"),
        (["survey", "start", journal, "--speed", "-1"], "survey setting speed_mps must be a positive number"),
        (
            ["survey", "start", journal, "--origin", "32.7,abc,0"],
            "--origin: LON 'abc' is not a number",
        ),
        (["survey", "start", journal, "--origin", "95,0,0"], "--origin: LAT 95 is outside [-90, 90]"),
        (
            ["survey", "start", journal, "--planner", "best"],
            "unknown planner 'best': use k0 (random yaw), k1..k10",
        ),
        (
            ["survey", "start", journal, "-k", "0", "--planner", "lookahead"],
            "planner horizon must be at least 1",
        ),
    ]
    for args, message in cases:
        code, out, err = _run(args, capsys)
        assert code == 2 and message in err and "Traceback" not in err + out, (args, err)
    assert not (tmp_path / "none.db").exists() and not Path(journal).exists()

    assert _run(["survey", "start", journal, *START], capsys)[0] == 0
    code, _, err = _run(["survey", "next", journal], capsys)
    assert code == 2 and "no GPS fix in the journal yet" in err
    assert _run(["survey", "add", journal, "--nmea", str(nmea), "--ranges", str(ranges)], capsys)[0] == 0
    with Journal.open(journal) as j:
        before = j.records()
    bad_csv = tmp_path / "bad.csv"
    bad_csv.write_text("time;beacon;range\n1;2;3\n")
    cases = [
        (["survey", "start", journal], "survey already started"),
        (["survey", "add", journal, "--fix", "2018-01-04T18:00:00Z,nan,0,0"], "LAT is NaN or infinite"),
        (["survey", "add", journal, "--fix", "yesterday,32.7,-117.2,0"], "T 'yesterday' is neither ISO 8601"),
        (["survey", "add", journal, "--fix", "1,2,3"], "expected T,LAT,LON,H (4 values), got 3"),
        (
            ["survey", "add", journal, "--range", "1.5e9,7,5.0"],
            "beacon 7 is not one of the survey's beacons 1, 2",
        ),
        (["survey", "add", journal, "--range", "1.5e9,1,-5.0"], "range -5 m is not in (0, 10000] m"),
        (
            ["survey", "add", journal, "--ranges", str(bad_csv)],
            "bad.csv:1: expected a header 'utc,beacon,range_m'",
        ),
        (["survey", "add", journal, "--nmea", str(tmp_path / "gone.nmea")], "gone.nmea: file not found"),
        (["survey", "add", journal], "nothing to add"),
        (["survey", "export", journal], "nothing to export"),
        (
            ["survey", "add", journal, "--range", "1.5e9,1,5", "--fix", "1,95,0,0"],
            "LAT 95 is outside [-90, 90]",
        ),
    ]
    for args, message in cases:
        code, out, err = _run(args, capsys)
        assert code == 2 and message in err and "Traceback" not in err + out, (args, err)
    with Journal.open(journal) as j:
        after = j.records()
    np.testing.assert_array_equal(after.fix_t_unix_s, before.fix_t_unix_s)
    np.testing.assert_array_equal(after.range_m, before.range_m)


@pytest.mark.parametrize("command", [[], ["start"], ["add"], ["next"], ["status"], ["export"]])
def test_every_survey_command_has_help(command: list[str]):
    res = CliRunner().invoke(app, ["survey", *command, "--help"])
    assert res.exit_code == 0 and "Usage" in res.output, res.output
