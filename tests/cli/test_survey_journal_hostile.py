"""``oceanloc survey`` under hostile input: bad command-line records refused before any write, a poisoned
journal reported and repaired with ``survey check``, a read-only journal still readable."""

import os
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from oceanloc.field.survey import journal as journal_module
from oceanloc.field.survey.check import check_journal
from oceanloc.field.survey.journal import Journal, JournalError
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

START = ["--planner", "greedy", "--max-distance", "4", "--beacon", "1", "--beacon", "2"]


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "oceanloc", *args], capture_output=True, text=True, env=os.environ, cwd=cwd
    )


def _started(tmp_path: Path, with_logs: bool = True) -> tuple[str, str, str]:
    logs = simulate_pier_logs(
        tmp_path, PierLogSettings(duration_s=300.0, stationary_s=100.0), np.random.default_rng(5)
    )
    assert _cli("survey", "start", "s.db", *START, cwd=tmp_path).returncode == 0
    if with_logs:
        add = _cli(
            "survey", "add", "s.db", "--nmea", logs.nmea_path.name, "--ranges", "ranges.csv", cwd=tmp_path
        )
        assert add.returncode == 0, add.stderr
    return "s.db", logs.nmea_path.name, logs.ranges_path.name


def _counts(path: Path) -> tuple[int, int]:
    with Journal.open(path) as j:
        rec = j.records()
    return rec.n_fixes, rec.n_ranges


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--fix", "1e20,10,10,0", "time 1e+20 s is outside [315964800, 4102444800] s"),
        ("--fix", "-1e15,10,10,0", "time -1e+15 s is outside [315964800, 4102444800] s"),
        ("--fix", "1.6e9,10,10,1e9", "height 1000000000 m is outside [-1000, 10000] m"),
        ("--fix", "1.6e9,99,10,0", "LAT 99 is outside [-90, 90]"),
        ("--fix", "1.6e9,10,999,0", "LON 999 is outside [-180, 360]"),
        ("--range", "1e20,1,10", "time 1e+20 s is outside"),
        ("--range", "1.6e9,99999999999999999999,10", "beacon id 99999999999999999999 is not an integer in"),
        ("--range", "1.6e9,1,1e6", "range 1000000 m is not in (0, 10000] m"),
        ("--range", "1.6e9,1,nan", "R is NaN or infinite"),
    ],
)
def test_a_bad_command_line_record_is_refused_before_any_file_is_written(
    tmp_path: Path, option: str, value: str, message: str
):
    journal, nmea, ranges = _started(tmp_path, with_logs=False)
    res = _cli("survey", "add", journal, "--nmea", nmea, "--ranges", ranges, option, value, cwd=tmp_path)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and message in lines[0], res.stderr
    assert option in lines[0] and "Traceback" not in res.stderr + res.stdout
    assert _counts(tmp_path / journal) == (0, 0)  # nothing from the files either


def test_out_of_range_log_records_are_qc_lines(tmp_path: Path):
    journal, _, _ = _started(tmp_path, with_logs=False)
    (tmp_path / "r.csv").write_text(
        "utc,beacon,range_m\n2018-01-04T18:00:10Z,1,20000\n2018-01-04T18:00:11Z,1,20\n"
    )
    res = _cli("survey", "add", journal, "--ranges", "r.csv", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert "r.csv: 1 ranges (1 new, 0 already stored)" in " ".join(res.stdout.split())
    assert "r.csv:2: negative or absurd range (20000 m is not in (0, 10000] m)" in res.stderr
    assert "Traceback" not in res.stderr


def _poison(path: Path) -> None:
    """Store a fix at time 1e20 behind the journal's back (as an old version or a hand edit could)."""
    db = sqlite3.connect(path)
    db.execute("INSERT INTO fixes VALUES (1e20, 10.0, 10.0, 0.0)")
    db.commit()
    db.close()


def test_a_poisoned_journal_is_reported_checked_and_repaired(tmp_path: Path):
    journal, _, _ = _started(tmp_path)
    before = _counts(tmp_path / journal)
    _poison(tmp_path / journal)
    for args in (["status"], ["export", "--csv", "out"], ["next"]):
        res = _cli("survey", *args, journal, cwd=tmp_path)
        assert res.returncode in (0, 2) and "Traceback" not in res.stderr, (args, res.stderr)
        assert "1 invalid record(s) skipped" in res.stderr, (args, res.stderr)
    assert _cli("survey", "status", journal, cwd=tmp_path).returncode == 0
    assert len((tmp_path / "out" / "fixes.csv").read_text().splitlines()) > before[0]

    add = _cli("survey", "add", journal, "--fix", "2018-01-04T18:10:00Z,32.7,-117.2,0", cwd=tmp_path)
    assert add.returncode == 0 and "invalid stored record skipped: fixes row" in add.stderr

    check = _cli("survey", "check", journal, cwd=tmp_path)
    assert check.returncode == 1 and "Traceback" not in check.stderr
    assert "s.db: fixes t=1e+20: time 1e+20 s is outside" in " ".join(check.stdout.split())
    assert "1 problem(s); `--remove-invalid` deletes them" in check.stderr

    fixed = _cli("survey", "check", journal, "--remove-invalid", cwd=tmp_path)
    assert fixed.returncode == 0 and "removed 1 invalid record(s)" in fixed.stdout, fixed.stdout
    assert _counts(tmp_path / journal) == (before[0] + 1, before[1])  # only the bad row went
    again = _cli("survey", "check", journal, cwd=tmp_path)
    assert again.returncode == 0 and "ok (no problems)" in again.stdout
    status = _cli("survey", "status", journal, cwd=tmp_path)
    assert status.returncode == 0 and "invalid" not in status.stderr


def test_check_of_a_file_that_is_not_a_journal_is_a_usage_error(tmp_path: Path):
    (tmp_path / "notes.txt").write_text("hello\n" * 100)
    res = _cli("survey", "check", "notes.txt", cwd=tmp_path)
    assert res.returncode == 2 and "notes.txt: not a survey journal" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr


def test_a_journal_in_a_read_only_folder_is_read_and_add_says_why(tmp_path: Path, monkeypatch):
    """In-process, with the folder reported read-only (tests may run as root, who may write anywhere)."""
    journal, _, _ = _started(tmp_path)
    path = tmp_path / journal
    n = _counts(path)
    real = os.access
    monkeypatch.setattr(
        journal_module.os, "access", lambda p, mode: False if mode == os.W_OK else real(p, mode)
    )
    with Journal.open(path) as j:
        assert j.read_only and (j.records().n_fixes, j.records().n_ranges) == n
        with pytest.raises(
            JournalError, match=r"s.db: the journal is read-only here: the folder .* is read-only"
        ):
            j.add_fix(1.6e9, 10.0, 10.0, 0.0)
    assert check_journal(path).clean


def _cli_without_root_override(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """The command with file permissions enforced: root drops CAP_DAC_OVERRIDE (setpriv)."""
    cmd = [sys.executable, "-m", "oceanloc", *args]
    if os.geteuid() == 0:
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            pytest.skip("running as root without setpriv: permissions are not enforced")
        cmd = [setpriv, "--bounding-set", "-dac_override,-dac_read_search", *cmd]
    return subprocess.run(cmd, capture_output=True, text=True, env=os.environ, cwd=cwd)


@pytest.mark.skipif(os.name != "posix", reason="POSIX permissions")
def test_a_journal_in_a_read_only_folder_through_the_command(tmp_path: Path):
    folder = tmp_path / "ro"
    folder.mkdir()
    journal, _, _ = _started(folder)
    folder.chmod(0o555)
    try:
        runs = {
            name: _cli_without_root_override("survey", *args, journal, cwd=folder)
            for name, args in {
                "status": ["status"],
                "next": ["next"],
                "export": ["export", "--geojson", str(tmp_path / "s.geojson")],
                "check": ["check"],
                "add": ["add", "--fix", "2018-01-04T18:10:00Z,32.7,-117.2,0"],
            }.items()
        }
    finally:
        folder.chmod(0o755)
    if "Permission" in runs["status"].stderr:
        pytest.skip(f"cannot drop write permission here: {runs['status'].stderr[-200:]}")
    for name, res in runs.items():
        assert "Traceback" not in res.stderr and "not a survey journal" not in res.stderr, (name, res.stderr)
    assert runs["status"].returncode == 0 and "182 used" in runs["status"].stdout
    assert runs["next"].returncode == 0 and runs["export"].returncode == 0, runs["next"].stderr
    assert runs["check"].returncode == 0 and "ok (no problems)" in runs["check"].stdout
    add = runs["add"]
    assert add.returncode == 2 and len(add.stderr.strip().splitlines()) == 1
    assert "s.db: the journal is read-only here: the folder . is read-only" in add.stderr, add.stderr
