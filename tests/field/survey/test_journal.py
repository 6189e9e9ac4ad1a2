import dataclasses
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.field.survey.journal import Journal
from oceanloc.io.qc import QcReport

T1 = 1.5e9
WRITER = """
import sys
from oceanloc.field.survey.journal import Journal
from oceanloc.io.qc import QcReport
j = Journal(sys.argv[1])
for k in range(100000):
    j.add_fix(1.5e9 + k, 32.7 + 1e-6 * k, -117.2, 0.0)
    j.add_range(1.5e9 + k + 0.5, 1 + k % 2, 10.0 + 0.001 * k)
    if k == 50:
        print("running", flush=True)
"""


def test_readd_is_idempotent_and_bad_values_rejected(tmp_path: Path):
    with Journal(tmp_path / "j.db") as j:
        assert j.add_fix(1.5e9, 32.7, -117.2, 0.0) is True
        assert j.add_fix(1.5e9, 32.7, -117.2, 0.0) is False
        assert j.add_range(1.5e9 + 0.5, 1, 9.0) and not j.add_range(1.5e9 + 0.5, 1, 9.0)
        with pytest.raises(DataError, match=r"range -1 m is not in \(0, 10000\] m"):
            j.add_range(1.5e9 + 1, 1, -1.0)
        assert j.fixes().shape == (1, 4) and j.ranges().shape == (1, 3)


def test_killed_writer_loses_nothing_committed_and_resumes_identically(tmp_path: Path):
    path = tmp_path / "survey.db"
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(path)], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "running"
    time.sleep(0.3)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    with Journal(path) as j:
        fixes, ranges = j.fixes(), j.ranges()
    n = fixes.shape[0]
    assert n > 50
    # Committed records form an unbroken prefix of the stream: nothing committed was lost.
    np.testing.assert_array_equal(fixes[:, 0], 1.5e9 + np.arange(n))
    assert ranges.shape[0] in (n - 1, n)
    # Replaying the whole stream prefix again is idempotent: the state is identical.
    with Journal(path) as j:
        for k in range(n):
            j.add_fix(1.5e9 + k, 32.7 + 1e-6 * k, -117.2, 0.0)
        np.testing.assert_array_equal(j.fixes(), fixes)


def _nmea_with_headings(path: Path) -> Path:
    import datetime as dt

    from oceanloc.io.nmea import format_gga, format_hdt, format_zda

    t0 = dt.datetime(2018, 1, 4, 18, 0, tzinfo=dt.UTC)
    lines = [format_hdt(10.0), format_zda(t0)]  # a heading before any fix has no time
    for k in range(4):
        lines.append(format_gga(t0 + dt.timedelta(seconds=k), 32.705 + 1e-5 * k, -117.236, -1.478))
        lines += [format_hdt(20.0 + k), format_hdt(30.0 + k)] if k == 2 else [format_hdt(20.0 + k)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_append_gps_log_counts_headings_and_conflicts(tmp_path: Path):
    from oceanloc.field.survey.journal import append_gps_log
    from oceanloc.io.nmea import read_nmea

    log = read_nmea(_nmea_with_headings(tmp_path / "g.nmea"))
    with Journal.start(tmp_path / "j.db", {}) as j:
        fixes, heads = append_gps_log(j, log, "g.nmea")
        assert (fixes.new, fixes.already_stored, heads.new) == (4, 0, 5)
        fixes, heads = append_gps_log(j, log, "g.nmea")
        assert (fixes.new, fixes.already_stored, heads.new, heads.already_stored) == (0, 4, 0, 5)
        assert str(fixes) == "4 fixes (0 new, 4 already stored)"
        # Two HDT after the third fix: both kept, in order (seq 0 and 1).
        np.testing.assert_array_equal(j.headings()[:, 1:], [[0, 20], [0, 21], [0, 22], [1, 32], [0, 23]])
        # A fix at a stored time with another position: kept as stored, named in the QC report.
        moved = dataclasses.replace(log, lat_deg=log.lat_deg + 1e-4, qc=QcReport())
        fixes, _ = append_gps_log(j, moved, "other.nmea")
        assert (fixes.new, fixes.already_stored, fixes.conflicting) == (0, 0, 4)
        assert str(moved.qc.issues[0]).startswith("other.nmea:3: duplicate record")
        np.testing.assert_array_equal(j.fixes()[:, 1], log.lat_deg)


def test_open_refuses_missing_unstarted_and_foreign_files(tmp_path: Path):
    import sqlite3

    missing = tmp_path / "none.db"
    with pytest.raises(DataError, match="no survey journal here"):
        Journal.open(missing)
    assert not missing.exists()
    Journal(tmp_path / "raw.db").close()
    with pytest.raises(DataError, match="never started"):
        Journal.open(tmp_path / "raw.db")
    text = tmp_path / "notes.txt"
    text.write_text("not a database at all, just some text\n" * 10)
    with pytest.raises(DataError, match=r"notes\.txt: not a survey journal"):
        Journal.open(text)
    other = tmp_path / "other.db"
    with sqlite3.connect(other) as db:
        db.execute("CREATE TABLE birds (name TEXT)")
    db.close()
    before = other.read_bytes()
    for opener in (Journal.open, Journal, lambda p: Journal.start(p, {})):
        with pytest.raises(DataError, match="tables birds"):
            opener(other)
    assert other.read_bytes() == before and not Path(f"{other}-wal").exists()
    Journal.start(tmp_path / "s.db", {"planner": '"greedy"'}).close()
    with pytest.raises(DataError, match="already started"):
        Journal.start(tmp_path / "s.db", {"planner": '"lookahead"'})
    with Journal.open(tmp_path / "s.db") as j:
        assert j.meta()["planner"] == '"greedy"'
    with pytest.raises(DataError, match="latitude 91"):
        Journal(tmp_path / "r.db").add_fix(1.5e9, 91.0, 0.0, 0.0)


def test_write_to_a_locked_journal_is_a_data_error_and_keeps_the_state(tmp_path: Path):
    import sqlite3

    path = tmp_path / "j.db"
    with Journal(path) as j:
        j.add_fix(T1, 32.7, -117.2, 0.0)
    other = sqlite3.connect(path, isolation_level=None)
    other.execute("BEGIN IMMEDIATE")  # another writer holds the write lock
    with Journal(path, timeout_s=0.05) as j:
        with pytest.raises(DataError, match=r"j\.db: cannot write to the journal \(database is locked\)"):
            j.add_fix(T1 + 1, 32.7, -117.2, 0.0)
        other.rollback()
        assert j.add_fix(T1 + 1, 32.7, -117.2, 0.0)
        np.testing.assert_array_equal(j.fixes()[:, 0], [T1, T1 + 1])
    other.close()


@pytest.mark.parametrize("chunk_size", [1, 2, 3, 1000])
def test_chunked_appends_count_and_report_as_one_record_at_a_time(tmp_path: Path, chunk_size: int):
    # A range log repeating a key within the file (same value: already stored; another value:
    # conflicting, named in QC with the value stored first), appended in transactions of chunk_size
    # records: the same counts, QC lines (in file order) and stored rows whatever the chunking.
    from oceanloc.field.survey.journal import append_range_log
    from oceanloc.io.usbl import RangeLog

    t = T1 + np.array([0.0, 1.0, 0.0, 0.0, 2.0, 1.0, 3.0])
    beacon = np.array([1, 1, 1, 1, 2, 1, 1])
    rng = np.array([10.0, 11.0, 10.0, 19.0, 12.0, 11.5, 13.0])
    log = RangeLog(t_unix_s=t, beacon=beacon, range_m=rng, line=np.arange(2, 9), qc=QcReport())
    with Journal.start(tmp_path / "j.db", {}) as j:
        counts = append_range_log(j, log, "r.csv", chunk_size=chunk_size)
        assert (counts.new, counts.already_stored, counts.conflicting) == (4, 1, 2)
        assert [str(i) for i in log.qc.issues] == [
            "r.csv:5: duplicate record (beacon 1 at this time is stored with 10.0 m, this line 19.0 m)",
            "r.csv:7: duplicate record (beacon 1 at this time is stored with 11.0 m, this line 11.5 m)",
        ]
        np.testing.assert_array_equal(
            j.ranges(), [[T1, 1, 10.0], [T1 + 1, 1, 11.0], [T1 + 2, 2, 12.0], [T1 + 3, 1, 13.0]]
        )
        again = append_range_log(j, log, "r.csv", chunk_size=chunk_size)
        assert (again.new, again.already_stored, again.conflicting) == (0, 5, 2)


def test_killed_bulk_add_commits_a_prefix_of_the_log(tmp_path: Path):
    # A real process appending a long range log in transactions of 500 records, killed (SIGKILL) once
    # the first are committed: what is stored is a prefix of the log; appending the log again stores
    # exactly the log.
    path = tmp_path / "bulk.db"
    Journal.start(path, {}).close()
    writer = """
import sys
import numpy as np
from oceanloc.field.survey.journal import Journal, append_range_log
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import RangeLog
n = 400_000
k = np.arange(n)
log = RangeLog(t_unix_s=1.5e9 + 0.5 * k, beacon=1 + k % 3, range_m=10.0 + 1e-5 * k, line=k, qc=QcReport())
with Journal.open(sys.argv[1]) as j:
    append_range_log(j, log, "r.csv", chunk_size=500)
"""
    proc = subprocess.Popen([sys.executable, "-c", writer, str(path)])
    deadline = time.monotonic() + 120.0
    with Journal.open(path) as j:
        while j.count("ranges") == 0 and time.monotonic() < deadline:
            assert proc.poll() is None, "the writer finished before it could be killed"
            time.sleep(0.002)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n = 400_000
    with Journal.open(path) as j:
        cut = j.ranges()
    m = cut.shape[0]
    assert 0 < m < n and m % 500 == 0  # whole transactions only
    np.testing.assert_array_equal(cut[:, 0], 1.5e9 + 0.5 * np.arange(m))
    np.testing.assert_array_equal(cut[:, 1], 1 + np.arange(m) % 3)
    proc = subprocess.run([sys.executable, "-c", writer, str(path)], check=True)
    with Journal.open(path) as j:
        whole = j.ranges()
    np.testing.assert_array_equal(whole[:, 0], 1.5e9 + 0.5 * np.arange(n))
    np.testing.assert_array_equal(whole[:, 2], 10.0 + 1e-5 * np.arange(n))


def test_usbl_angles_and_events_are_journaled_and_bad_ones_refused(tmp_path):
    with Journal.start(tmp_path / "j.db", {"planner": '"greedy"'}) as j:
        assert j.add_usbl_range(1.8e9, 1, 120.5, 45.0, -30.0)
        assert not j.add_usbl_range(1.8e9, 1, 120.5, 45.0, -30.0)  # stored already: nothing changed
        assert j.add_usbl_range(1.8e9 + 1, 2, 80.0, None, None)  # a range-only modem: no angle row
        np.testing.assert_array_equal(j.usbl_angles(), [[1.8e9, 1, 45.0, -30.0]])
        assert j.range_at(1.8e9 + 1, 2) == 80.0
        with pytest.raises(DataError, match=r"USBL elevation 400.0 deg not in \[-360, 360\]"):
            j.add_usbl_range(1.8e9 + 2, 1, 10.0, 0.0, 400.0)
        assert j.range_at(1.8e9 + 2, 1) is None
        seqs = j.add_events(1.8e9, [("plan", {"x": 1.0}), ("command", {"gain": float("nan")})])
        assert seqs == [1, 2]
        assert [(e.kind, e.body) for e in j.events()] == [("plan", {"x": 1.0}), ("command", {"gain": None})]
        assert j.last_event("plan").seq == 1 and j.last_event("link") is None
        with pytest.raises(DataError, match="event kind 'arm' is not one of"):
            j.add_event(1.8e9, "arm", {})
        assert len(j.events()) == 2
