"""The NMEA fast path against pynmea2, the reference: the same records bit for bit and the same QC.

:func:`~oceanloc.io.nmea.read_nmea` parses well-formed GGA, RMC, HDT and ZDA sentences with plain
string operations and hands every other line to the pynmea2 path (``NmeaLineParser.feed(...,
fast=False)``); :func:`~oceanloc.io.qc.read_lines` decodes a plain ASCII file at once. Promise under
test: on simulated pier logs (corrupt lines, outliers) and on generated lines (checksums right and
wrong, empty fields, odd hemispheres, fractional seconds, bad dates), both give identical fixes,
headings, line numbers, QC issues (file:line, reason, detail) and counts.
"""

import datetime as dt
from functools import reduce
from operator import xor
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from oceanloc.io.nmea import GpsFix, Heading, NmeaLineParser, gps_log_from_records, read_nmea
from oceanloc.io.qc import QcReport, decode_line, read_lines
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

FAST = settings(derandomize=True, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
ARRAYS = ("t_unix_s", "lat_deg", "lon_deg", "h_m", "heading_t_unix_s", "heading_deg", "line", "heading_line")


def _reference_lines(path: Path, qc: QcReport):
    """read_lines as it was: every line through decode_line (the bytes rule)."""
    raw = path.read_bytes()
    if not raw.strip():
        qc.add(path, 0, "empty file")
        return
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raw = raw.decode("utf-16").encode("utf-8")
    for number, line in enumerate(raw.splitlines(), start=1):
        text = decode_line(line, number, qc, path)
        if text is not None:
            yield number, text


def _reference_read(path: Path):
    """read_nmea through pynmea2 only: (GpsLog or the DataError text, QcReport)."""
    qc = QcReport()
    parser = NmeaLineParser()
    fixes, headings = [], []
    for number, text in _reference_lines(path, qc):
        rec = parser.feed(number, text, qc, path, fast=False)
        if isinstance(rec, GpsFix):
            fixes.append(rec)
        elif isinstance(rec, Heading):
            headings.append(rec)
    try:
        return gps_log_from_records(fixes, headings, qc, str(path)), qc
    except Exception as exc:
        return str(exc), qc


def _assert_same_as_reference(path: Path) -> None:
    ref, ref_qc = _reference_read(path)
    qc = QcReport()
    try:
        got = read_nmea(path, qc=qc)
    except Exception as exc:
        got = str(exc)
    assert qc == ref_qc  # issues (file, line, reason, detail) in order, lines read, records kept
    if isinstance(ref, str):
        assert got == ref
        return
    for name in ARRAYS:
        a, b = getattr(ref, name), getattr(got, name)
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), name


@pytest.mark.parametrize("seed", [3, 24])
def test_pier_logs_read_as_pynmea2_reads_them(tmp_path: Path, seed: int):
    settings_ = PierLogSettings(duration_s=1200.0, outlier_fraction=0.2)
    logs = simulate_pier_logs(tmp_path, settings_, np.random.default_rng(seed))
    _assert_same_as_reference(logs.nmea_path)
    qc = read_nmea(logs.nmea_path).qc
    assert qc.records_kept == 1200 and len(qc.issues) == 5  # the simulator's corrupt lines
    # And corrupted further: one character of every 7th line replaced, some lines moved back in time.
    rng = np.random.default_rng(seed)
    lines_ = logs.nmea_path.read_text().splitlines()
    for k in range(3, len(lines_), 7):
        pos = int(rng.integers(len(lines_[k])))
        char = str(rng.choice(list("0123456789.,*-+NSEWAVx $")))
        lines_[k] = lines_[k][:pos] + char + lines_[k][pos + 1 :]
        body = lines_[k][1:-3]
        if k % 2 and lines_[k][-3:-2] == "*" and "*" not in body:  # a checksum that matches the damage
            lines_[k] = _sentence(body, "right")
    for k in range(50, len(lines_) - 20, 301):
        lines_[k], lines_[k + 20] = lines_[k + 20], lines_[k]
    bad = tmp_path / "corrupted.nmea"
    bad.write_text("\r\n".join(lines_) + "\r\n", encoding="ascii")
    _assert_same_as_reference(bad)
    qc = read_nmea(bad).qc
    assert len(qc.issues) > 150 and len(qc.counts()) >= 4


def _sentence(body: str, checksum: str) -> str:
    good = f"{reduce(xor, body.encode(), 0):02X}"
    mark = {"right": good, "lower": good.lower(), "wrong": f"{int(good, 16) ^ 0x11:02X}"}.get(checksum, "")
    return f"${body}" + ("" if checksum == "missing" else f"*{mark}")


DIGITS = st.text(alphabet="0123456789", min_size=0, max_size=4)
FRACTIONS = ["", ".00", ".5", ".29", ".57", ".123456789", ".999999", ".9999999", ".99999999999999999"]
GOOD_TIMES = st.builds(
    lambda h, m, s, frac: f"{h:02d}{m:02d}{s:02d}{frac}",
    st.integers(0, 23),
    st.integers(0, 59),
    st.integers(0, 59),
    st.sampled_from(FRACTIONS),
)
BAD_TIMES = st.one_of(
    st.builds(
        lambda h, m, s, frac: f"{h:02d}{m:02d}{s:02d}{frac}",
        st.integers(0, 25),
        st.integers(0, 61),
        st.integers(0, 61),
        st.sampled_from([*FRACTIONS, ".", "5", "x", ".5x"]),
    ),
    st.sampled_from(["", "1800", "nan", " 180000.00", "180000.0a", "18000"]),
)
GOOD_LAT = st.builds(lambda d, m: f"{d:02d}{m:07.4f}", st.integers(0, 90), st.floats(0, 59.9999))
GOOD_LON = st.builds(lambda d, m: f"{d:03d}{m:07.4f}", st.integers(0, 180), st.floats(0, 59.9999))
BAD_COORDS = st.one_of(
    st.builds(
        lambda d, m: f"{d}{m:07.4f}",
        st.sampled_from(["", "0", "9", "90", "91", "180", "181", "0000"]),
        st.floats(0, 59.9999),
    ),
    st.sampled_from(["", "0", "00", "0.0", "3242", "32xx.3000", "3242.", ".3000", "1e3", "-3242.3", "12.5"]),
)
GOOD_HEIGHTS = st.floats(-1000, 10000).map(lambda v: f"{v:.3f}")
NUMBERS = st.one_of(
    st.floats(-2000, 12000).map(lambda v: f"{v:.3f}"),
    st.sampled_from(
        ["", "0", "-0", "nan", "inf", "1e400", "1_0", " 5", "x", "151.1", "360", "360.1", "5.", ".5", "0.0"]
    ),
)
GOOD_HEADINGS = st.one_of(
    st.floats(0, 360).map(lambda v: f"{v:.1f}"), st.sampled_from(["0", "360", "360.0", "5.", ".5", "007"])
)
FIELDS = st.lists(
    st.one_of(BAD_TIMES, BAD_COORDS, NUMBERS, DIGITS, st.sampled_from(["N", "S", "E", "W", "A", "V", "X"])),
    max_size=3,
)
GOOD_DATES = st.sampled_from(["040118", "050118", "311299", "290224", "010168", "311268"])
BAD_DATES = st.sampled_from(
    ["300224", "000118", "041318", "040170", "311269", "4118", "04011", "0401188", "x40118"]
)


@st.composite
def lines(draw) -> str:
    """Mostly well-formed sentences; each field is damaged with probability 1/8 (times 1/3 of the lines)."""

    def pick(good, bad):
        return draw(bad) if draw(st.integers(0, 7)) == 0 else draw(good)

    kind = pick(st.sampled_from(["GGA", "GGA", "HDT", "ZDA", "RMC"]), st.sampled_from(["VTG", "gga", "GSV"]))
    talker = pick(st.sampled_from(["GP", "GN"]), st.sampled_from(["IN", "PG", "G_", "pG", "P1"]))
    lat_dir = pick(st.sampled_from(["N", "S"]), st.sampled_from(["E", "", "n", "X"]))
    lon_dir = pick(st.sampled_from(["E", "W"]), st.sampled_from(["N", "", "w", "X"]))
    if kind.upper() == "GGA":
        fields = [
            pick(GOOD_TIMES, BAD_TIMES),
            pick(GOOD_LAT, BAD_COORDS),
            lat_dir,
            pick(GOOD_LON, BAD_COORDS),
            lon_dir,
            pick(st.sampled_from(["1", "2", "4"]), st.sampled_from(["0", "", "1x", " 2", "+2"])),
            "09",
            "0.9",
            pick(GOOD_HEIGHTS, NUMBERS),
            "M",
            pick(st.sampled_from(["0.0", "", "-33.9", "12"]), NUMBERS),
            "M",
            "",
            "",
        ]
    elif kind == "RMC":
        fields = [
            pick(GOOD_TIMES, st.one_of(BAD_TIMES, st.just(""))),
            pick(st.just("A"), st.sampled_from(["V", ""])),
            pick(GOOD_LAT, st.one_of(BAD_COORDS, st.just(""))),
            lat_dir,
            pick(GOOD_LON, st.one_of(BAD_COORDS, st.just(""))),
            lon_dir,
            "0.5",
            "54.7",
            pick(GOOD_DATES, st.one_of(BAD_DATES, st.just(""))),
            "",
            "",
        ]
    elif kind == "HDT":
        fields = [pick(GOOD_HEADINGS, NUMBERS), "T"]
    elif kind == "ZDA":
        fields = [
            pick(GOOD_TIMES, BAD_TIMES),
            pick(
                st.sampled_from(["04", "4", "31", "15"]),
                st.sampled_from(["00", "", "x", "32", "-1", "9" * 30]),
            ),
            pick(st.sampled_from(["01", "1", "12"]), st.sampled_from(["02", "13", "", "00"])),
            pick(
                st.sampled_from(["2018", "2024", "1980", "2099"]),
                st.sampled_from(["1979", "2100", "18", "", "9" * 40]),
            ),
            "00",
            "00",
        ]
    else:
        fields = ["054.7", "T", "034.4", "M", "005.5", "N", "010.2", "K"]
    if draw(st.integers(0, 7)) == 0:  # cut short, extra fields appended
        fields = fields[: draw(st.integers(0, len(fields)))] + draw(FIELDS)
    body = f"{talker}{kind}," + ",".join(fields)
    text = _sentence(body, pick(st.sampled_from(["right", "lower"]), st.sampled_from(["wrong", "missing"])))
    return pick(st.just(""), st.sampled_from(["junk", "$", " "])) + text


@settings(FAST, max_examples=400)
@given(st.lists(lines(), min_size=1, max_size=16))
def test_generated_lines_give_what_pynmea2_gives(texts: list[str]):
    """Line by line: the same record, the same QC issue and the same parser state after each line."""
    start = [_sentence("GPZDA,000000.00,04,01,2018,00,00", "right")]
    fast, slow = NmeaLineParser(), NmeaLineParser()
    qc_fast, qc_slow = QcReport(), QcReport()
    for number, text in enumerate(start + texts, start=1):
        a = fast.feed(number, text, qc_fast, "log.nmea")
        b = slow.feed(number, text, qc_slow, "log.nmea", fast=False)
        assert type(a) is type(b), text
        if a is not None:
            ra, rb = a.to_record(), b.to_record()
            assert ra == rb and all(
                np.float64(ra[k]).tobytes() == np.float64(rb[k]).tobytes()
                for k in ra
                if isinstance(ra[k], float)
            ), text
        assert qc_fast == qc_slow, text
        assert (fast.date, fast.last_t) == (slow.date, slow.last_t), text


@settings(
    FAST, max_examples=150, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(
    st.lists(lines(), min_size=1, max_size=20),
    st.sampled_from(["\n", "\r\n", "\r"]),
    st.lists(
        st.sampled_from([b"", b"   ", b"\x00", b"\x0b", b"\x1c", b"\xc3\xa9", b"\xff", b"\t$GPHDT,1*00"]),
        max_size=3,
    ),
)
def test_generated_files_read_as_pynmea2_reads_them(tmp_path_factory, texts, newline, junk):
    """Whole files, ASCII or not (the decoding at once and line by line), with junk lines among them."""
    start = "$GPZDA,180000.00,04,01,2018,00,00*61"
    raw = newline.join([start, *texts]).encode() + newline.encode()
    for k, extra in enumerate(junk):
        raw += extra + newline.encode() + (texts[k % len(texts)].encode() + newline.encode())
    path = tmp_path_factory.mktemp("nmea") / "gen.nmea"
    path.write_bytes(raw)
    _assert_same_as_reference(path)


def test_fast_timestamps_are_the_datetime_timestamps():
    """The integer-microsecond time of a fix equals datetime.timestamp() at fractional seconds."""
    parser = NmeaLineParser()
    qc = QcReport()
    parser.feed(1, "$GPZDA,180000.00,04,01,2018,00,00*61", qc, "x")
    for k, frac in enumerate([".01", ".29", ".57", ".999999", ".123456789"], start=2):
        body = f"GPGGA,18000{k}{frac},3242.3000,N,11714.1600,W,2,09,0.9,-1.478,M,0.0,M,,"
        fix = parser.feed(k, _sentence(body, "right"), qc, "x")
        us = int(float(frac) * 1_000_000)
        expected = dt.datetime(2018, 1, 4, 18, 0, k, us, tzinfo=dt.UTC).timestamp()
        assert isinstance(fix, GpsFix) and fix.t_unix_s == expected
    assert qc.issues == [] and qc.records_kept == 5


def test_read_lines_decodes_plain_ascii_at_once_as_line_by_line(tmp_path: Path):
    raw = b"a\r\n\r\n  b  \rc\n\n\td\t\n"
    path = tmp_path / "x.txt"
    path.write_bytes(raw)
    qc_a, qc_b = QcReport(), QcReport()
    assert (
        list(read_lines(path, qc_a))
        == list(_reference_lines(path, qc_b))
        == [
            (1, "a"),
            (3, "b"),
            (4, "c"),
            (6, "d"),
        ]
    )
    assert qc_a == qc_b and qc_a.lines_read == 4
