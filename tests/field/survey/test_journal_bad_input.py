"""The journal under bad input: nothing out of range goes in, a bad stored row is skipped and removable,
SQLite failures (damaged pages, a read-only folder) are one-line JournalErrors."""

import dataclasses
import datetime as dt
import logging
import os
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.field.survey.journal import Journal, JournalError, append_gps_log, append_range_log
from oceanloc.io.nmea import format_gga, format_hdt, format_zda, read_nmea
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import read_usbl
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

T = 1.5e9
TIME_RANGE = r"is outside \[315964800, 4102444800\] s \(Unix time: 1980-01-06 to 2100-01-01 UTC\)"


@pytest.mark.parametrize(
    ("method", "args", "message"),
    [
        ("add_fix", (1e20, 32.7, -117.2, 0.0), r"fix at 1e\+20 s: time 1e\+20 s " + TIME_RANGE),
        ("add_fix", (-1e15, 32.7, -117.2, 0.0), r"fix at -1e\+15 s: time -1e\+15 s " + TIME_RANGE),
        ("add_fix", (1.0, 32.7, -117.2, 0.0), "time 1 s " + TIME_RANGE),
        ("add_fix", (float("nan"), 32.7, -117.2, 0.0), "time nan s " + TIME_RANGE),
        ("add_fix", (T, 91.0, -117.2, 0.0), r"latitude 91 deg is outside \[-90, 90\] deg"),
        ("add_fix", (T, 32.7, 999.0, 0.0), r"longitude 999 deg is outside \[-180, 360\] deg"),
        ("add_fix", (T, 32.7, -117.2, 1e6), r"height 1000000 m is outside \[-1000, 10000\] m"),
        ("add_fix", (T, 32.7, -117.2, float("-inf")), r"height -inf m is outside"),
        ("add_range", (1e20, 1, 5.0), r"range at 1e\+20 s: time 1e\+20 s " + TIME_RANGE),
        ("add_range", (T, 1, 0.0), r"range 0 m is not in \(0, 10000\] m"),
        ("add_range", (T, 1, 1e5), r"range 100000 m is not in \(0, 10000\] m"),
        ("add_range", (T, 1, float("nan")), r"range nan m is not in"),
        ("add_range", (T, 10**30, 5.0), r"beacon id 1000000000...000000 \(31 characters\) is not an integer"),
        (
            "add_range",
            (T, 2**63, 5.0),
            r"beacon id 9223372036854775808 is not an integer in \[0, 2147483647\]",
        ),
        ("add_range", (T, -1, 5.0), r"beacon id -1 is not an integer in \[0, 2147483647\]"),
        ("add_range", (T, 1.5, 5.0), r"beacon id 1.5 is not an integer"),
        ("add_heading", (-1e15, 0, 10.0), r"heading at -1e\+15 s: time -1e\+15 s " + TIME_RANGE),
        ("add_heading", (T, 0, 400.0), r"heading 400 deg is outside \[0, 360\] deg"),
        ("add_heading", (T, -1, 10.0), r"heading order -1 is not an integer"),
    ],
)
def test_out_of_range_values_are_rejected_naming_field_and_range(
    tmp_path: Path, method: str, args: tuple, message: str
):
    with Journal(tmp_path / "j.db") as j:
        with pytest.raises(DataError, match=message):
            getattr(j, method)(*args)
        rec = j.records()
        assert rec.n_fixes == rec.n_ranges == rec.heading_deg.size == 0
        assert j.range_at(T, 10**30) is None  # a huge id is looked up without an OverflowError


def _gps_log(path: Path, headings: tuple[float, ...] = (20.0,)) -> Path:
    t0 = dt.datetime(2018, 1, 4, 18, 0, tzinfo=dt.UTC)
    lines = [format_zda(t0)]
    for k in range(3):
        lines.append(format_gga(t0 + dt.timedelta(seconds=k), 32.705 + 1e-5 * k, -117.236, -1.478))
        lines += [format_hdt(h + k) for h in headings]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_logs_are_checked_before_the_first_write_bad_records_become_qc_lines(tmp_path: Path):
    """A log built in code with out-of-range records (the readers never return any): the bad records are
    QC lines naming source and line, the good ones are written, nothing raises half-way."""
    log = read_nmea(_gps_log(tmp_path / "g.nmea"))
    bad = dataclasses.replace(
        log,
        t_unix_s=log.t_unix_s * np.array([1.0, 1e11, 1.0]),
        lat_deg=log.lat_deg + np.array([0.0, 0.0, 80.0]),
        heading_deg=log.heading_deg * np.array([1.0, 1.0, 30.0]),
        qc=QcReport(),
    )
    ranges = tmp_path / "r.csv"
    ranges.write_text("utc,beacon,range_m\n2018-01-04T18:00:00Z,1,5\n2018-01-04T18:00:01Z,2,6\n")
    rlog = read_usbl(ranges)
    rbad = dataclasses.replace(rlog, beacon=np.array([1, 2**40]), qc=QcReport())
    with Journal.start(tmp_path / "j.db", {}) as j:
        fixes, heads = append_gps_log(j, bad, "g.nmea")
        rng = append_range_log(j, rbad, "r.csv")
        assert str(fixes) == "3 fixes (1 new, 0 already stored, 2 rejected)"
        assert str(heads) == "3 headings (2 new, 0 already stored, 1 rejected)"
        assert str(rng) == "2 ranges (1 new, 0 already stored, 1 rejected)"
        issues = [str(i) for i in bad.qc.issues + rbad.qc.issues]
        assert issues[0].startswith("g.nmea:4: out of range (time 1.515088801e+20 s is outside [315964800")
        assert issues[1] == "g.nmea:6: out of range (latitude 112.70502 deg is outside [-90, 90] deg)"
        assert issues[2] == "g.nmea:7: out of range (heading 660 deg is outside [0, 360] deg)"
        assert (
            issues[3]
            == "r.csv:3: out of range (beacon id 1099511627776 is not an integer in [0, 2147483647])"
        )
        assert j.records().n_fixes == 1 and j.records().n_ranges == 1


def test_conflicting_headings_are_duplicates_with_both_values(tmp_path: Path):
    first = read_nmea(_gps_log(tmp_path / "a.nmea"))
    other = read_nmea(_gps_log(tmp_path / "b.nmea", headings=(25.0,)))
    with Journal.start(tmp_path / "j.db", {}) as j:
        append_gps_log(j, first, "a.nmea")
        _, again = append_gps_log(j, first, "a.nmea")
        assert str(again) == "3 headings (0 new, 3 already stored)"
        fixes, heads = append_gps_log(j, other, "b.nmea")
        assert str(fixes) == "3 fixes (0 new, 3 already stored)"
        assert str(heads) == "3 headings (0 new, 0 already stored, 3 conflicting)"
        assert str(other.qc.issues[0]) == (
            "b.nmea:3: duplicate record (heading 1 after the fix at 1515088800.000 s is stored with "
            "20.0 deg, this line 25.0 deg)"
        )
        np.testing.assert_array_equal(j.headings()[:, 2], [20.0, 21.0, 22.0])


def _poison(path: Path) -> None:
    """Rows no version of the journal writes today, stored behind its back."""
    with sqlite3.connect(path) as db:
        db.executemany(
            "INSERT INTO fixes VALUES (?, ?, ?, ?)",
            [(1e20, 32.7, -117.2, 0.0), (-1e15, 32.7, -117.2, 0.0), (T + 1e8, "abc", -117.2, 0.0)],
        )
        db.executemany(
            "INSERT INTO ranges VALUES (?, ?, ?)",
            [(T + 1e8, 1, -5.0), (T + 1e8, 2**40, 5.0), (1e300, 1, 5.0)],
        )
        db.execute("INSERT INTO headings VALUES (?, ?, ?)", (T + 1e8, 0, 1000.0))
    db.close()


def test_a_poisoned_journal_is_read_skipping_and_reporting_the_bad_rows_which_can_be_removed(
    tmp_path: Path, caplog
):
    path = tmp_path / "j.db"
    logs = simulate_pier_logs(
        tmp_path, PierLogSettings(duration_s=120.0, stationary_s=40.0), np.random.default_rng(1)
    )
    with Journal.start(path, {}) as j:
        append_gps_log(j, read_nmea(logs.nmea_path), "gps")
        append_range_log(j, read_usbl(logs.ranges_path, beacons=(1, 2)), "ranges")
        clean = j.records()
        assert j.check() == [] and clean.invalid == ()
    _poison(path)
    with caplog.at_level(logging.WARNING), Journal.open(path) as j:
        rec = j.records()
        assert len(rec.invalid) == 7
        assert "j.db: 7 invalid record(s) skipped (first: fixes row" in caplog.text
        for got, want in zip(
            (rec.fix_t_unix_s, rec.lat_deg, rec.range_m, rec.beacon, rec.heading_deg),
            (clean.fix_t_unix_s, clean.lat_deg, clean.range_m, clean.beacon, clean.heading_deg),
            strict=True,
        ):
            np.testing.assert_array_equal(got, want)
        problems = j.check()
        assert len(problems) == 7
        assert any("latitude nan deg is outside" in p for p in problems)  # text in a REAL column
        assert any("beacon id 1099511627776" in p for p in problems)
        assert any("heading 1000 deg" in p for p in problems)
        removed = j.remove_invalid()
        assert [r.table for r in removed] == ["fixes"] * 3 + ["headings"] + ["ranges"] * 3
        assert j.remove_invalid() == [] and j.check() == []
        after = j.records()
        assert after.invalid == () and after.n_fixes == clean.n_fixes and after.n_ranges == clean.n_ranges


def _main(args: list[str], capsys) -> tuple[int, str, str]:
    """The console script in-process (a subprocess costs seconds of imports): (exit, stdout, stderr)."""
    from oceanloc.cli.app import main

    try:
        main(args)
        code = 0
    except SystemExit as exc:
        code = int(exc.code)
    out, err = capsys.readouterr()
    return code, out, err


def test_commands_reading_a_poisoned_journal_still_work(tmp_path: Path, capsys):
    """`survey status` and `export` on a journal holding out-of-range rows: exit 0, estimates as before."""
    logs = simulate_pier_logs(
        tmp_path, PierLogSettings(duration_s=120.0, stationary_s=40.0), np.random.default_rng(2)
    )
    journal = str(tmp_path / "s.db")

    def run(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "oceanloc", "survey", *args],
            capture_output=True,
            text=True,
            env=os.environ,
        )

    assert run("start", journal, "--beacon", "1", "--beacon", "2").returncode == 0
    add = run("add", journal, "--nmea", str(logs.nmea_path), "--ranges", str(logs.ranges_path))
    assert add.returncode == 0, add.stderr
    before = run("status", journal)
    _poison(Path(journal))
    after = run("status", journal)
    assert after.returncode == 0 and "Traceback" not in after.stderr, after.stderr
    assert after.stdout == before.stdout
    assert "7 invalid record(s) skipped" in after.stderr
    export = run("export", journal, "--csv", str(tmp_path / "csv"))
    assert export.returncode == 0 and "Traceback" not in export.stderr, export.stderr


def _damage(path: Path, where: str, page_size: int = 4096) -> None:
    """Overwrite most of one page: the header page (after the magic string), a middle page of the records
    (between the tables' root pages and the end) or the last page."""
    n_pages = path.stat().st_size // page_size
    with sqlite3.connect(path) as db:
        roots = max(r[0] for r in db.execute("SELECT rootpage FROM sqlite_master"))
    page = {"header": 0, "middle": (roots + n_pages) // 2, "last": n_pages - 1}[where]
    with path.open("r+b") as f:
        f.seek(page * page_size + 16 * (page == 0))
        f.write(bytes(range(256)) * (page_size // 256 - 1))


@pytest.mark.parametrize("where", ["header", "middle", "last"])
def test_a_damaged_journal_page_is_a_journal_error_not_a_raw_sqlite_error(tmp_path: Path, where: str):
    path = tmp_path / "j.db"
    with Journal.start(path, {"planner": '"greedy"'}) as j:
        for k in range(400):
            j.add_fix(T + k, 32.7 + 1e-6 * k, -117.2, 0.0)
            j.add_range(T + k + 0.5, 1 + k % 2, 10.0 + 0.001 * k)
    assert not Path(f"{path}-wal").exists()  # checkpointed on close: the pages are in the file
    _damage(path, where)
    with pytest.raises(JournalError) as info, Journal.open(path) as j:
        j.records()
    message = str(info.value)
    assert message.startswith(f"{path}: the journal file is damaged (")
    assert "nothing was changed" in message and "sqlite3 j.db .recover" in message
    assert "\n" not in message


def _run_without_root_override(code: str, *args: str) -> subprocess.CompletedProcess:
    """Run Python with file permissions enforced: root drops CAP_DAC_OVERRIDE (setpriv)."""
    cmd = [sys.executable, "-c", code, *args]
    if os.geteuid() == 0:
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            pytest.skip("running as root without setpriv: permissions are not enforced")
        cmd = [setpriv, "--bounding-set", "-dac_override,-dac_read_search", *cmd]
    return subprocess.run(cmd, capture_output=True, text=True, env=os.environ)


def test_a_journal_in_a_read_only_folder_is_read_and_a_write_says_why(tmp_path: Path):
    folder = tmp_path / "ro"
    folder.mkdir()
    with Journal.start(folder / "j.db", {}) as j:
        j.add_fix(1.6e9, 10.0, 10.0, 0.0)
    folder.chmod(0o555)
    try:
        code = (
            "import sys\nfrom oceanloc.field.survey.journal import Journal\n"
            "j = Journal.open(sys.argv[1])\nprint(j.read_only, j.records().n_fixes)\n"
            "try:\n    j.add_fix(1.7e9, 10.0, 10.0, 0.0)\n"
            "except Exception as e:\n    print(type(e).__name__, e)"
        )
        res = _run_without_root_override(code, str(folder / "j.db"))
    finally:
        folder.chmod(0o755)
    if "True" not in res.stdout and "Permission" in res.stderr:
        pytest.skip(f"cannot drop write permission here: {res.stderr[-200:]}")
    assert res.stdout.strip().splitlines() == [
        "True 1",
        f"JournalError {folder / 'j.db'}: the journal is read-only here: the folder {folder} is read-only (a "
        "journal needs to create j.db-wal and j.db-shm beside it); copy the journal to a writable folder",
    ], res.stdout + res.stderr


def test_survey_add_with_an_out_of_range_fix_keeps_the_file_and_names_the_line(tmp_path: Path, capsys):
    """The issue's case: a checksum-valid GGA at latitude 99 in the middle of a log. Before, `survey add`
    committed part of the file and aborted naming no file or line. Now the line is a QC line
    (file:line: reason), every other fix is added, and re-adding the file changes nothing."""
    import pynmea2

    t0 = dt.datetime(2018, 1, 4, 18, 0, tzinfo=dt.UTC)
    lines = [format_zda(t0)]
    for k in range(6):
        lines.append(format_gga(t0 + dt.timedelta(seconds=k), 32.705 + 1e-5 * k, -117.236, -1.478))
    lat99 = (
        "180002.50",
        "9900.0000",
        "N",
        "11714.1600",
        "W",
        "2",
        "09",
        "0.9",
        "-1.478",
        "M",
        "0.0",
        "M",
        "",
        "",
    )
    lines.insert(4, str(pynmea2.GGA("GP", "GGA", lat99)))
    nmea = tmp_path / "gps.nmea"
    nmea.write_text("\n".join(lines) + "\n")
    journal = str(tmp_path / "s.db")

    def run(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "oceanloc", "survey", *args],
            capture_output=True,
            text=True,
            env=os.environ,
        )

    assert run("start", journal).returncode == 0
    add = run("add", journal, "--nmea", str(nmea))
    err = " ".join(add.stderr.split())
    assert add.returncode == 0 and "Traceback" not in err, err
    assert "gps.nmea:5: out of range (latitude 99 deg is outside [-90, 90] deg)" in err
    assert "6 fixes (6 new, 0 already stored)" in " ".join(add.stdout.split())
    again = run("add", journal, "--nmea", str(nmea))
    assert "6 fixes (0 new, 6 already stored)" in " ".join(again.stdout.split())
    with Journal.open(journal) as j:
        lat = j.records().lat_deg
    assert lat.size == 6 and np.all(np.abs(lat) <= 90.0)
    bad_fix = run("add", journal, "--fix", "1e20,32.7,-117.2,0")
    assert bad_fix.returncode == 2 and "Traceback" not in bad_fix.stderr
    assert "time 1e+20 s is outside [315964800, 4102444800] s" in " ".join(bad_fix.stderr.split())
    assert run("status", journal).returncode == 0
