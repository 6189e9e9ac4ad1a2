"""The USBL range reader's fast path against its general rules: the same ranges bit for bit, the same QC.

:func:`~oceanloc.io.usbl.read_usbl` reads plain ``YYYY-MM-DDTHH:MM:SS.fffZ,beacon,value`` lines by
string operations and every other line through ``UsblLineParser.feed(..., fast=False)``. Promise under
test: on simulated pier logs (outliers, corrupt lines, further damage) and on generated lines, both give
identical ranges, line numbers, QC issues (file:line, reason, detail) and counts, and the same state.
"""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from oceanloc.io.qc import QcReport, read_lines
from oceanloc.io.usbl import UsblLineParser, range_log_from_records, read_usbl
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

FAST = settings(derandomize=True, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])


def _assert_same_as_general_rules(path: Path, **kwargs) -> None:
    qc_ref = QcReport()
    parser = UsblLineParser(**{k: v for k, v in kwargs.items() if k != "column"})
    records = [parser.feed(n, t, qc_ref, path, fast=False) for n, t in read_lines(path, qc_ref)]
    ref = range_log_from_records(records, qc_ref, str(path))
    qc = QcReport()
    got = read_usbl(path, qc=qc, **kwargs)
    assert qc == qc_ref
    for name in ("t_unix_s", "beacon", "range_m", "line"):
        a, b = getattr(ref, name), getattr(got, name)
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), name


@pytest.mark.parametrize(
    "kwargs", [{"beacons": (1, 2)}, {}, {"beacons": (2,), "max_range_m": 12.0, "sound_speed_mps": 1480.0}]
)
def test_pier_ranges_read_as_the_general_rules_read_them(tmp_path: Path, kwargs: dict):
    logs = simulate_pier_logs(tmp_path, PierLogSettings(duration_s=1200.0), np.random.default_rng(7))
    _assert_same_as_general_rules(logs.ranges_path, **kwargs)
    rng = np.random.default_rng(8)
    lines = logs.ranges_path.read_text().splitlines()
    for k in range(2, len(lines), 5):  # one character replaced in every 5th line
        pos = int(rng.integers(len(lines[k])))
        lines[k] = lines[k][:pos] + str(rng.choice(list("0123456789.,:-+TZ x"))) + lines[k][pos + 1 :]
    for k in range(30, len(lines) - 3, 97):  # a line repeated, one moved back in time
        lines[k + 1], lines[k + 3] = lines[k], lines[k + 3 - 2]
    bad = tmp_path / "corrupted.csv"
    bad.write_text("\n".join(lines) + "\n", encoding="ascii")
    _assert_same_as_general_rules(bad, **kwargs)
    assert len(read_usbl(bad, **kwargs).qc.counts()) >= 4


@st.composite
def range_lines(draw) -> str:
    def pick(good, bad):
        return draw(bad) if draw(st.integers(0, 7)) == 0 else draw(good)

    date = pick(
        st.sampled_from(["2018-01-04", "2024-02-29"]),
        st.sampled_from(["2023-02-29", "2018-13-01", "20180104", "2018-W01-4", "1970-01-01"]),
    )
    hh = pick(st.integers(0, 23).map(lambda v: f"{v:02d}"), st.sampled_from(["24", "7", "xx"]))
    mm = pick(st.integers(0, 59).map(lambda v: f"{v:02d}"), st.sampled_from(["60", "5"]))
    ss = pick(st.integers(0, 59).map(lambda v: f"{v:02d}"), st.sampled_from(["60", "61"]))
    frac = pick(
        st.sampled_from([".000", ".370", ".999", ".123456", ".5"]), st.sampled_from(["", ".1234567", ","])
    )
    zone = pick(st.just("Z"), st.sampled_from(["", "z", "+02:00", " UTC", "+0000"]))
    beacon = pick(
        st.sampled_from(["1", "2", "01"]), st.sampled_from(["9", "-1", "", "x", "2147483648", " 1"])
    )
    value = pick(
        st.floats(0.001, 40).map(lambda v: f"{v:.3f}"),
        st.sampled_from(["nan", "-3.0", "0", "", "1e5", "inf", " 8.2", "8,2", "12001"]),
    )
    return f"{date}T{hh}:{mm}:{ss}{frac}{zone},{beacon},{value}"


@settings(FAST, max_examples=300)
@given(st.lists(range_lines(), min_size=1, max_size=16), st.sampled_from(["range_m", "owtt_s", "twtt_s"]))
def test_generated_lines_give_what_the_general_rules_give(texts: list[str], column: str):
    fast = UsblLineParser(beacons=(1, 2), column=column)
    slow = UsblLineParser(beacons=(1, 2), column=column)
    qc_fast, qc_slow = QcReport(), QcReport()
    for number, text in enumerate(texts, start=1):
        a = fast.feed(number, text, qc_fast, "r.csv")
        b = slow.feed(number, text, qc_slow, "r.csv", fast=False)
        assert (a is None) == (b is None), text
        if a is not None:
            assert a.to_record() == b.to_record(), text
            assert np.float64(a.t_unix_s).tobytes() == np.float64(b.t_unix_s).tobytes(), text
        assert qc_fast == qc_slow, text
        assert (fast.last_t, fast._at_last_t) == (slow.last_t, slow._at_last_t), text
