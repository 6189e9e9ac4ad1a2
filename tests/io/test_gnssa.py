from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from oceanloc.errors import DataError
from oceanloc.io.gnssa import PUBLISHED_SOUND_SPEED_MPS, lajolla_paths, read_gnssa

PATHS = lajolla_paths()
HEADER = (
    "# time0_transmit N0 E0 U0 sigN0 sigE0 sigU0 time1_receive N1 E1 U1 sigN1 sigE1 sigU1 TWTT(s)\n"
    "# Topocentric coordinates: Lat0=32.8668445 deg., Lon0=-117.2701205 deg., H0=-88.738 m\n"
)
GOOD = (
    " 49231669.0 55.7853 115.8632 53.3079 0.0168 0.0150 0.0177"
    " 49231669.3857999 55.8253 115.8985 53.2556 0.0168 0.0150 0.0177 0.1858000"
)


def test_packaged_surveys_and_published_speeds():
    assert [p.stem for p in PATHS] == sorted(PUBLISHED_SOUND_SPEED_MPS)
    counts = {p.stem: read_gnssa(p).n_pings for p in PATHS}
    assert counts == {
        "gnssa_data_20210723": 555,
        "gnssa_data_20210823_SV3_1063": 339,
        "gnssa_data_20210823_SV3_1065": 548,
        "gnssa_data_20211210": 64,
        "gnssa_data_20220321": 238,
    }
    assert (PATHS[0].parent / "LICENSE").read_text().startswith("BSD 3-Clause")


def test_first_ping_fields_origin_and_turnaround():
    s = read_gnssa(PATHS[0])
    assert s.origin is not None and s.origin.lat_deg == 32.8668445 and s.origin.h_m == -88.738
    np.testing.assert_allclose(s.transmit_enu_m[0], [115.8632, 55.7853, 53.3079])  # file is N, E, U
    np.testing.assert_allclose(s.sigma_receive_enu_m[0], [0.0150, 0.0168, 0.0177])
    assert s.twtt_s[0] == 0.1858 and s.line[0] == 4
    # turn-around delay already removed: 0.200 s in 2021-07/08, 0.080 s in 2021-12 and 2022-03
    np.testing.assert_allclose(s.turnaround_s, 0.2, atol=1e-6)
    np.testing.assert_allclose(read_gnssa(PATHS[4]).turnaround_s, 0.08, atol=1e-6)


def test_malformed_lines_are_skipped_and_named(tmp_path: Path):
    rows = [
        GOOD,
        GOOD.replace("49231669.0 ", "49231679.0 ", 1).replace("49231669.3857999", "49231679.38"),
        GOOD[:60],  # truncated
        GOOD.replace("55.7853", "55.78x3"),  # non-numeric
        GOOD.replace("53.3079", "nan"),
        GOOD.replace("0.1858000", "-0.1858000"),  # negative travel time
        GOOD,  # same transmit time as line 1: time does not advance
    ]
    path = tmp_path / "bad.txt"
    path.write_text(HEADER + "\n".join(rows) + "\n")
    s = read_gnssa(path)
    assert s.n_pings == 2
    reasons = {(i.line, i.reason) for i in s.qc.issues}
    assert reasons == {
        (5, "truncated sentence"),
        (6, "non-numeric field"),
        (7, "NaN or infinite value"),
        (8, "negative or absurd range"),
        (9, "time going backwards"),
    }
    assert "bad.txt:6: non-numeric field (field 2: '55.78x3')" in s.qc.summary()


def test_empty_and_binary_files_raise_data_error_naming_the_file(tmp_path: Path):
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    with pytest.raises(DataError, match=r"empty\.txt: no valid ping \(.*empty file"):
        read_gnssa(empty)
    binary = tmp_path / "bin.txt"
    binary.write_bytes(b"\xff\xd8\xff\x00\x01garbage\n")
    with pytest.raises(DataError, match="wrong encoding"):
        read_gnssa(binary)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.binary(max_size=400))
def test_random_bytes_never_crash(tmp_path: Path, blob: bytes):
    path = tmp_path / "fuzz.txt"
    path.write_bytes(HEADER.encode() + blob + b"\n" + GOOD.encode() + b"\n")
    try:
        s = read_gnssa(path)
    except DataError:
        return
    assert s.n_pings >= 1
    assert np.all(np.isfinite(s.twtt_s))
