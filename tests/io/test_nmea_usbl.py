import datetime as dt
from pathlib import Path

import numpy as np
import pynmea2
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from oceanloc.errors import DataError
from oceanloc.io.nmea import format_gga, format_zda, read_nmea
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import align_ranges, read_usbl

T0 = dt.datetime(2018, 1, 4, 18, 0, tzinfo=dt.UTC)
ZDA = format_zda(T0)
GGA = [format_gga(T0 + dt.timedelta(seconds=k), 32.705 + 1e-5 * k, -117.236, -1.478) for k in range(5)]
FUZZ = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def test_nmea_fixes_dates_and_every_bad_line_named(tmp_path: Path):
    lines = [
        ZDA,
        GGA[0],
        GGA[1][:-2] + "FF",
        GGA[1][:20],
        "$GPGGA,180002.00,32xx.3,N,11714.16,W,2,9,0.9,0,M,0,M,,",
        GGA[2],
        GGA[1],
        GGA[3],
        "$GPXXX,1,2*00",
    ]
    path = tmp_path / "gps.nmea"
    path.write_text("\n".join(lines) + "\n")
    log = read_nmea(path)
    assert log.n_fixes == 3
    np.testing.assert_allclose(log.t_unix_s - T0.timestamp(), [0.0, 2.0, 3.0])
    np.testing.assert_allclose(log.lat_deg[0], 32.705, atol=1e-7)
    got = {(i.line, i.reason) for i in log.qc.issues}
    assert got == {
        (3, "bad checksum"),
        (4, "truncated sentence"),
        (5, "truncated sentence"),
        (7, "time going backwards"),
        (9, "bad checksum"),
    }


def test_usbl_units_beacons_and_bad_lines(tmp_path: Path):
    path = tmp_path / "r.csv"
    path.write_text(
        "utc,beacon,twtt_s\n"
        "2018-01-04T18:00:00.500Z,1,0.0120\n"
        "2018-01-04T18:00:01.000Z,x,0.01\n"
        "2018-01-04T18:00:01.500Z,1,nan\n"
        "2018-01-04T18:00:02.000Z,1,-0.01\n"
        "2018-01-04T18:00:02.500Z,7,0.01\n"
        "2018-01-04T18:00:00.000Z,2,0.01\n"
        "2018-01-04T18:00:03.500,2,0.0040\n"
        "2018-01-04T18:00:04\n"
    )
    log = read_usbl(path, sound_speed_mps=1500.0, beacons=[1, 2])
    np.testing.assert_allclose(log.range_m, [9.0, 3.0])  # 0.5 * c * TWTT
    reasons = [(i.line, i.reason) for i in log.qc.issues]
    assert reasons == [
        (3, "non-numeric field"),
        (4, "NaN or infinite value"),
        (5, "negative or absurd range"),
        (6, "unknown beacon id"),
        (7, "time going backwards"),
        (9, "truncated sentence"),
    ]


def test_empty_file_and_missing_header_are_data_errors(tmp_path: Path):
    empty = tmp_path / "e.csv"
    empty.write_text("")
    with pytest.raises(DataError, match="empty file"):
        read_usbl(empty)
    nohead = tmp_path / "n.csv"
    nohead.write_text("2018-01-04T18:00:00Z,1,3.0\n")
    with pytest.raises(DataError, match=r"n\.csv:1: expected a header"):
        read_usbl(nohead)
    latin = tmp_path / "l.nmea"
    latin.write_bytes(b"\xe9\xe8\n" + "\n".join([ZDA, GGA[0]]).encode() + b"\n")
    log = read_nmea(latin)
    assert log.n_fixes == 1 and log.qc.issues[0].reason == "wrong encoding"


def test_alignment_interpolates_and_drops_ranges_without_gps(tmp_path: Path):
    gps_path = tmp_path / "g.nmea"
    gps_path.write_text("\n".join([ZDA, *GGA]) + "\n")
    r_path = tmp_path / "r.csv"
    r_path.write_text("utc,beacon,range_m\n2018-01-04T18:00:01.500Z,1,5.0\n2018-01-04T18:00:09.000Z,1,5.0\n")
    aligned = align_ranges(read_nmea(gps_path), read_usbl(r_path))
    assert aligned.dropped_no_gps == 1 and aligned.range_m.size == 1
    # halfway between fixes 1 and 2: 1.5e-5 deg north of the first fix = 1.663 m (pymap3d geodesy)
    assert aligned.vehicle_enu_m[0, 1] == pytest.approx(1.5e-5 * 110_865.0, rel=2e-3)


@FUZZ
@given(st.binary(max_size=300))
def test_nmea_random_bytes_never_crash(tmp_path: Path, blob: bytes):
    path = tmp_path / "f.nmea"
    path.write_bytes(ZDA.encode() + b"\n" + blob + b"\n" + GGA[4].encode() + b"\n")
    try:
        log = read_nmea(path)
    except DataError:
        return
    assert np.all(np.isfinite(log.lat_deg))


@FUZZ
@given(st.integers(0, len(GGA[2]) - 1), st.characters(codec="utf-8"))
def test_nmea_mutated_valid_line_is_kept_or_named(tmp_path: Path, pos: int, char: str):
    mutated = GGA[2][:pos] + char + GGA[2][pos + 1 :]
    path = tmp_path / "m.nmea"
    path.write_text("\n".join([ZDA, GGA[0], mutated, GGA[3]]) + "\n", encoding="utf-8")
    log = read_nmea(path)
    assert log.n_fixes + len(log.qc.issues) >= 3  # nothing silently lost
    assert log.t_unix_s[0] == T0.timestamp()


@FUZZ
@given(st.text(max_size=80))
def test_usbl_mutated_lines_never_crash(tmp_path: Path, junk: str):
    path = tmp_path / "u.csv"
    path.write_text(f"utc,beacon,range_m\n2018-01-04T18:00:00Z,1,3.0\n{junk}\n", encoding="utf-8")
    log = read_usbl(path, qc=QcReport())
    assert log.range_m[0] == 3.0


def _sentence(kind: str, *fields: str) -> str:
    """A checksum-valid sentence with arbitrary field text."""
    return str(getattr(pynmea2, kind)("GP", kind, fields))


def _gga(time: str = "180010.00", lat: str = "3242.3000", ns: str = "N", lon: str = "11714.1600",
         ew: str = "W", alt: str = "-1.478") -> str:  # fmt: skip
    return _sentence("GGA", time, lat, ns, lon, ew, "2", "09", "0.9", alt, "M", "0.0", "M", "", "")


def _rmc(time: str, lat: str, lon: str, date: str) -> str:
    return _sentence("RMC", time, "A", lat, "N", lon, "W", "0", "0", date, "", "")


@pytest.mark.parametrize(
    ("sentence", "reason", "detail"),
    [
        (_gga(lat="9900.0000"), "out of range", "latitude 99 deg is outside [-90, 90] deg"),
        (_gga(lat="9000.0060"), "out of range", "latitude 90.0001 deg"),
        (_gga(lon="99900.0000"), "out of range", "longitude -999 deg is outside [-180, 180] deg"),
        (_gga(lon="18000.0600", ew="E"), "out of range", "longitude 180.001 deg"),
        (_gga(ns="X"), "non-numeric field", "hemisphere 'X'"),
        (_gga(ew=""), "non-numeric field", "hemisphere"),
        (_gga(alt="1e6"), "out of range", "ellipsoidal height 1000000 m"),
        (_gga(alt="-5000"), "out of range", "ellipsoidal height -5000 m"),
        (_gga(alt="nan"), "NaN or infinite value", "height"),
        (_gga(time="186000.00"), "non-numeric field", "time of day '186000.00' is not HHMMSS"),
        (_gga(time="246060"), "non-numeric field", "time of day '246060'"),
        (_gga(time="nan"), "non-numeric field", "time of day 'nan'"),
        (_gga(time="1843"), "non-numeric field", "time of day '1843'"),
        (_rmc("180010.00", "9900.0000", "11714.16", "040118"), "out of range", "latitude 99 deg"),
        (_rmc("180010.00", "3242.30", "99900.0000", "040118"), "out of range", "longitude -999 deg"),
        (_rmc("186000.00", "3242.30", "11714.16", "040118"), "non-numeric field", "time of day"),
        (_rmc("180010.00", "3242.30", "11714.16", "999999"), "non-numeric field", "date '999999'"),
        (_sentence("ZDA", "180010.00", "04", "01", "0001", "00", "00"), "out of range", "date 0001-01-04"),
        (_sentence("ZDA", "180010.00", "04", "01", "2100", "00", "00"), "out of range", "outside 1980-2099"),
        (_sentence("ZDA", "180010.00", "99", "01", "2018", "00", "00"), "non-numeric field", "day is out"),
        (_sentence("ZDA", "186000.00", "04", "01", "2018", "00", "00"), "non-numeric field", "time of day"),
        (_sentence("HDT", "361.0", "T"), "out of range", "heading 361 deg is outside [0, 360] deg"),
        (_sentence("HDT", "-1", "T"), "out of range", "heading -1 deg"),
        (_sentence("HDT", "inf", "T"), "NaN or infinite value", "heading"),
    ],
)
def test_nmea_out_of_range_or_malformed_values_are_qc_lines(
    tmp_path: Path, sentence: str, reason: str, detail: str
):
    """A checksum-valid sentence with an impossible value is a QC line naming file, line and range; the
    valid fixes before and after it are kept, and nothing outside the WGS84 ranges is returned."""
    path = tmp_path / "bad.nmea"
    path.write_text("\n".join([ZDA, GGA[0], sentence, GGA[1], GGA[2]]) + "\n")
    log = read_nmea(path)
    assert log.n_fixes == 3
    np.testing.assert_allclose(log.t_unix_s - T0.timestamp(), [0.0, 1.0, 2.0])
    assert np.all(np.abs(log.lat_deg) <= 90.0) and np.all(np.abs(log.lon_deg) <= 180.0)
    assert log.heading_deg.size == 0
    [issue] = log.qc.issues
    assert (issue.line, issue.reason) == (3, reason)
    assert detail in issue.detail
    assert str(issue).startswith(f"{path}:3: {reason}")


def test_nmea_file_of_only_bad_times_is_one_data_error_naming_the_file(tmp_path: Path):
    path = tmp_path / "times.nmea"
    path.write_text("\n".join([ZDA, _gga(time="186000.00"), _gga(time="246060"), _gga(time="nan")]) + "\n")
    with pytest.raises(DataError, match=r"times\.nmea: no valid GPS fix.*3 lines skipped"):
        read_nmea(path)


@pytest.mark.parametrize(
    ("line", "reason", "detail"),
    [
        ("2018-01-04T18:00:01Z,99999999999999999999999999,3.0", "out of range", "beacon id 9999999999..."),
        ("2018-01-04T18:00:01Z,9223372036854775808,3.0", "out of range", "is outside [0, 2147483647]"),
        ("2018-01-04T18:00:01Z,-1,3.0", "out of range", "beacon id -1 is outside"),
        ("2018-01-04T18:00:01Z,1,1e300", "negative or absurd range", "1e+300 m is not in (0, 10000] m"),
        ("2018-01-04T18:00:01Z,1,0", "negative or absurd range", "0 m is not in (0, 10000] m"),
        ("2018-01-04T18:00:01Z,1,-inf", "NaN or infinite value", "range_m"),
        ("1900-01-04T18:00:01Z,1,3.0", "out of range", "-2208664799 s is outside [315964800, 4102"),
        ("9999-12-31T23:59:59Z,1,3.0", "out of range", "time 253402300799 s is outside"),
        ("0001-01-01T00:00:00+01:00,1,3.0", "out of range", "time -62135600400 s is outside"),
        ("2018-01-04T18:00:01+25:00,1,3.0", "non-numeric field", "is not ISO 8601"),
        ("2018-01-04T24:00:00Z,1,3.0", "non-numeric field", "is not ISO 8601"),
        ("2018-01-04T18:00:00Z,1,3.0", "duplicate record", "the same range on line 2"),
        ("2018-01-04T18:00:00Z,1,3.5", "duplicate record", "another range (3 m) on line 2"),
    ],
)
def test_usbl_bad_values_are_qc_lines(tmp_path: Path, line: str, reason: str, detail: str):
    """Huge or negative beacon ids, ranges and times out of range and repeated (time, beacon) lines are
    QC lines; the valid ranges are kept once each."""
    path = tmp_path / "u.csv"
    path.write_text(f"utc,beacon,range_m\n2018-01-04T18:00:00Z,1,3.0\n{line}\n2018-01-04T18:00:02Z,2,4.0\n")
    log = read_usbl(path)
    np.testing.assert_array_equal(log.range_m, [3.0, 4.0])
    np.testing.assert_array_equal(log.beacon, [1, 2])
    [issue] = log.qc.issues
    assert (issue.line, issue.reason) == (3, reason)
    assert detail in issue.detail


def test_usbl_duplicated_lines_are_used_once(tmp_path: Path):
    body = "".join(f"2018-01-04T18:00:0{k}Z,{b},{3 + k}.0\n" for k in range(3) for b in (1, 2))
    path = tmp_path / "dup.csv"
    path.write_text("utc,beacon,range_m\n" + "".join(line * 2 for line in body.splitlines(keepends=True)))
    log = read_usbl(path)
    assert log.range_m.size == 6
    assert log.qc.counts() == {"duplicate record": 6}
    np.testing.assert_array_equal(log.line, [2, 4, 6, 8, 10, 12])


def test_usbl_a_later_header_switches_the_column(tmp_path: Path):
    """Two logs joined: the second header is a header (not a bad line) and its column applies after it."""
    path = tmp_path / "joined.csv"
    path.write_text(
        "utc,beacon,range_m\n2018-01-04T18:00:00Z,1,3.0\nutc,beacon,twtt_s\n2018-01-04T18:00:01Z,1,0.004\n"
    )
    log = read_usbl(path, sound_speed_mps=1500.0)
    np.testing.assert_allclose(log.range_m, [3.0, 3.0])
    assert (log.qc.issues, log.qc.lines_read, log.qc.records_kept) == ([], 2, 2)


@pytest.mark.parametrize(
    "stamp",
    [
        "2018-01-04T20:00:01.500+02:00",
        "2018-01-04T20:00:01.500+0200",
        "2018-01-04T20:00:01.500+02",
        "2018-01-04T20:00:01.500 +02:00",
        "2018-01-04T10:00:01.500-08:00",
        "2018-01-04T18:00:01.500 UTC",
        "2018-01-04 18:00:01.500z",
        "20180104T180001.5Z",
        "2018-01-04T18:00:01.500",
    ],
)
def test_usbl_times_with_a_zone_offset_align_with_the_gps(tmp_path: Path, stamp: str):
    """Every zone spelling gives the same instant, 1.5 s after the first fix, so the range is aligned."""
    gps_path = tmp_path / "g.nmea"
    gps_path.write_text("\n".join([ZDA, *GGA]) + "\n")
    r_path = tmp_path / "r.csv"
    r_path.write_text(f"utc,beacon,range_m\n{stamp},1,5.0\n")
    log = read_usbl(r_path)
    assert log.t_unix_s[0] == pytest.approx(T0.timestamp() + 1.5, abs=1e-6)
    aligned = align_ranges(read_nmea(gps_path), log)
    assert aligned.dropped_no_gps == 0 and aligned.range_m.size == 1
