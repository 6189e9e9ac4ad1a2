"""Estimates stored in the journal (``survey status`` / ``survey next`` on a long journal): the same
numbers to the bit as computed from the records, used only while the records are those they came from."""

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest

from oceanloc.config.survey import PlannerSettings
from oceanloc.errors import DataError
from oceanloc.field.survey import estimates as sj
from oceanloc.field.survey import journal as journal_module
from oceanloc.field.survey.estimates import (
    ESTIMATES_NAME,
    add_to_journal,
    journal_next_waypoint,
    journal_status,
    next_waypoint,
    pack_estimates,
    survey_estimates,
    unpack_estimates,
)
from oceanloc.field.survey.journal import Journal
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

SETTINGS = JournalSettings(planner=PlannerSettings(kind="lookahead", horizon=1), beacons=(1, 2))


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("stored")
    return simulate_pier_logs(folder, PierLogSettings(duration_s=600.0), np.random.default_rng(8))


def _journal(folder: Path, logs) -> Path:
    path = folder / "survey.db"
    Journal.start(path, SETTINGS.to_meta()).close()
    add_to_journal(path, nmea=[logs.nmea_path], ranges=[logs.ranges_path])
    return path


def _assert_same(a, b) -> None:
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if dataclasses.is_dataclass(x):
            _assert_same(x, y)
        elif isinstance(x, np.ndarray):
            assert x.dtype == y.dtype, f.name
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        else:
            assert x == y, f.name


def test_pack_unpack_is_exact(logs, tmp_path: Path):
    path = _journal(tmp_path, logs)
    with Journal.open(path) as j:
        est = survey_estimates(j.records(headings=False), SETTINGS)
    assert est.n_beacons == 2
    _assert_same(unpack_estimates(pack_estimates(est)), est)


def test_add_stores_them_and_status_reads_them_without_computing(logs, tmp_path: Path, monkeypatch):
    path = _journal(tmp_path, logs)
    with Journal.open(path) as j:
        direct = survey_estimates(j.records(headings=False), SETTINGS)
        assert j.derived(ESTIMATES_NAME, sj._estimates_key(j)) is not None
        records = j.records()

    def refuse(*args, **kwargs):
        raise AssertionError("recomputed although stored")

    monkeypatch.setattr(sj, "survey_estimates", refuse)
    st = journal_status(path)
    _assert_same(st.estimates, direct)
    assert (st.records.n_fixes, st.records.n_headings, st.records.n_ranges) == (
        records.n_fixes,
        records.n_headings,
        records.n_ranges,
    )
    assert st.records.first_fix_t_unix_s == records.fix_t_unix_s[0]
    assert st.records.last_fix_t_unix_s == records.fix_t_unix_s[-1]
    # survey next: the tail of the journal and the stored estimates give the full computation's plan.
    rng_seed = [0, records.n_fixes, records.n_ranges]
    full = next_waypoint(records, SETTINGS, estimates=direct, rng=np.random.default_rng(rng_seed))
    w = journal_next_waypoint(path)
    assert w.heading_source == full.heading_source == "HDT"
    np.testing.assert_array_equal(w.next_enu_m, full.next_enu_m)
    assert w.yaw_rad == full.yaw_rad and w.from_t_unix_s == full.from_t_unix_s


def test_a_new_record_makes_them_recomputed(logs, tmp_path: Path):
    path = _journal(tmp_path, logs)
    with Journal.open(path) as j:
        before = j.fingerprint()
        rec = j.records()
    t_new = float(rec.fix_t_unix_s[-1]) + 1.0
    add_to_journal(path, fixes=[(t_new, float(rec.lat_deg[-1]), float(rec.lon_deg[-1]), float(rec.h_m[-1]))])
    with Journal.open(path) as j:
        assert j.fingerprint() != before
        fresh = survey_estimates(j.records(headings=False), SETTINGS)
    st = journal_status(path)
    assert st.records.n_fixes == rec.n_fixes + 1
    _assert_same(st.estimates, fresh)
    assert st.estimates.track_enu_m.shape[0] == rec.n_fixes + 1


def test_a_changed_value_changes_the_fingerprint(logs, tmp_path: Path):
    path = _journal(tmp_path, logs)
    with Journal.open(path) as j:
        before = j.fingerprint()
        j._transaction(lambda db: db.execute("UPDATE ranges SET range_m = range_m + 0.001 WHERE rowid = 7"))
        moved = j.fingerprint()
        # A value exchanged between two records (the sums alone would not see it).
        j._transaction(
            lambda db: db.execute(
                "UPDATE ranges SET range_m = CASE rowid WHEN 3 THEN "
                "(SELECT range_m FROM ranges WHERE rowid = 4) "
                "ELSE (SELECT range_m FROM ranges WHERE rowid = 3) END WHERE rowid IN (3, 4)"
            )
        )
        swapped = j.fingerprint()
    assert len({before, moved, swapped}) == 3


def test_read_only_journal_computes_and_stores_nothing(logs, tmp_path: Path, monkeypatch):
    """With the folder reported read-only (tests may run as root, who may write anywhere)."""
    path = _journal(tmp_path, logs)
    with Journal.open(path) as j:
        j._transaction(lambda db: db.execute("DELETE FROM derived"))
    real = os.access
    monkeypatch.setattr(
        journal_module.os, "access", lambda p, mode: False if mode == os.W_OK else real(p, mode)
    )
    st = journal_status(path)
    assert st.estimates is not None and st.estimates.n_beacons == 2
    with Journal.open(path) as j:
        assert j.read_only and j.derived(ESTIMATES_NAME, sj._estimates_key(j)) is None
        assert not j.store_derived(ESTIMATES_NAME, "key", b"x")


def test_next_on_a_journal_without_fixes_says_so(tmp_path: Path):
    path = tmp_path / "empty.db"
    Journal.start(path, SETTINGS.to_meta()).close()
    with pytest.raises(DataError, match="no GPS fix"):
        journal_next_waypoint(path)
    assert journal_status(path).estimates is None
