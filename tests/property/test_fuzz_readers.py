"""Fuzz tests of every reader of user files: random bytes and near-valid input.

Promise under test (issue 11): whatever the bytes, a reader returns a valid result or raises one of the
project's own errors (:class:`oceanloc.errors.OceanlocError`), never another exception; and what it
returns is inside the physical ranges (no fix outside WGS84, no NaN, no duplicated range). Examples are
drawn from a fixed seed (``derandomize=True``, the suite's profile) so every run tries the same inputs;
each test is bounded in examples and inputs are tiny, so the whole file runs in seconds.
"""

import atexit
import datetime as dt
import io
import shutil
import struct
import tempfile
import wave
from pathlib import Path

import numpy as np
import pynmea2
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from oceanloc.config.builtin import builtin_folder, builtin_names
from oceanloc.config.drift import drift_scenario_from_table
from oceanloc.config.flock import flock_scenario_from_table
from oceanloc.config.survey import survey_scenario_from_table
from oceanloc.config.toml_fields import parse_toml
from oceanloc.errors import OceanlocError
from oceanloc.io.gnssa import read_gnssa
from oceanloc.io.nmea import format_gga, format_hdt, format_zda, read_nmea
from oceanloc.io.qc import BEACON_ID_RANGE, HEIGHT_RANGE_M, MAX_RANGE_M, TIME_RANGE_UNIX_S
from oceanloc.io.usbl import read_usbl
from oceanloc.io.wav import read_wav

FUZZ = settings(derandomize=True, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
BYTES = settings(FUZZ, max_examples=400)
LINES = settings(FUZZ, max_examples=700)
SCENARIO_EDITS = settings(FUZZ, max_examples=800)

TMP = Path(tempfile.mkdtemp(prefix="oceanloc-fuzz-"))
atexit.register(shutil.rmtree, TMP, ignore_errors=True)
T0 = dt.datetime(2018, 1, 4, 18, 0, tzinfo=dt.UTC)


def _file(name: str, content: bytes) -> Path:
    path = TMP / name
    path.write_bytes(content)
    return path


def _only_own_errors(read, *args, **kwargs):
    """Call a reader; an OceanlocError is an answer (returns None), any other exception fails the test."""
    try:
        return read(*args, **kwargs)
    except OceanlocError:
        return None


# Field text a corrupt or hostile log may hold.
JUNK = st.one_of(
    st.sampled_from(
        [
            "",
            "nan",
            "NaN",
            "inf",
            "-inf",
            "1e400",
            "-1e400",
            "1e20",
            "-1e15",
            "0",
            "-0",
            "-1",
            "99",
            "999",
            "9999.9999",
            "99900.0000",
            "186000.00",
            "246060",
            "235960.99",
            "000000",
            "999999",
            "x",
            "1_0",
            "0x10",
            "１２",
            "9" * 40,
            "-" + "9" * 30,
            "1e-320",
            "+",
            ".",
            "..",
            "1.2.3",
        ]
    ),
    st.text(alphabet="0123456789.-+eENSWnaifx ", max_size=12),
)


# --- NMEA -----------------------------------------------------------------------------------------


def _check_gps(log) -> None:
    assert np.all(np.abs(log.lat_deg) <= 90.0) and np.all(np.abs(log.lon_deg) <= 180.0)
    assert np.all((log.h_m >= HEIGHT_RANGE_M[0]) & (log.h_m <= HEIGHT_RANGE_M[1]))
    assert np.all((log.t_unix_s >= TIME_RANGE_UNIX_S[0]) & (log.t_unix_s <= TIME_RANGE_UNIX_S[1]))
    assert np.all(np.diff(log.t_unix_s) > 0.0)
    assert np.all((log.heading_deg >= 0.0) & (log.heading_deg <= 360.0))
    assert log.line.shape == log.t_unix_s.shape


@BYTES
@given(st.binary(max_size=160))
def test_nmea_random_bytes(blob: bytes):
    log = _only_own_errors(read_nmea, _file("r.nmea", blob))
    if log is not None:
        _check_gps(log)


VALID_NMEA = [
    format_zda(T0),
    format_gga(T0, 32.705, -117.236, -1.478),
    str(
        pynmea2.RMC(
            "GP", "RMC", ("180001.00", "A", "3242.30", "N", "11714.16", "W", "0", "0", "040118", "", "")
        )
    ),
    format_hdt(42.0),
    format_gga(T0 + dt.timedelta(seconds=2), 32.70501, -117.236, -1.478),
]


@LINES
@given(st.lists(st.tuples(st.integers(0, len(VALID_NMEA) - 1), st.integers(0, 14), JUNK), max_size=6))
def test_nmea_checksum_valid_sentences_with_hostile_fields(edits):
    """Each edit replaces one field of a valid sentence and re-computes the checksum, so the value
    checks (not the checksum) must catch it."""
    lines = list(VALID_NMEA)
    for k, field, text in edits:
        msg = pynmea2.parse(lines[k])
        data = list(msg.data)
        data[field % len(data)] = text.replace(",", "").replace("*", "")
        lines[k] = str(type(msg)(msg.talker, msg.sentence_type, tuple(data)))
    log = _only_own_errors(read_nmea, _file("n.nmea", ("\n".join(lines) + "\n").encode()))
    if log is not None:
        _check_gps(log)
        assert log.n_fixes + len(log.qc.issues) >= 2  # every GGA is a fix or a named QC line


# --- USBL / range CSV ------------------------------------------------------------------------------


def _check_ranges(log) -> None:
    assert np.all(np.isfinite(log.range_m)) and np.all((log.range_m > 0.0) & (log.range_m <= MAX_RANGE_M))
    assert np.all((log.t_unix_s >= TIME_RANGE_UNIX_S[0]) & (log.t_unix_s <= TIME_RANGE_UNIX_S[1]))
    assert np.all((log.beacon >= BEACON_ID_RANGE[0]) & (log.beacon <= BEACON_ID_RANGE[1]))
    assert np.all(np.diff(log.t_unix_s) >= 0.0)
    keys = set(zip(log.t_unix_s.tolist(), log.beacon.tolist(), strict=True))
    assert len(keys) == log.range_m.size  # no (time, beacon) twice


@BYTES
@given(st.binary(max_size=160))
def test_usbl_random_bytes(blob: bytes):
    log = _only_own_errors(read_usbl, _file("r.csv", blob))
    if log is not None:
        _check_ranges(log)


STAMPS = st.one_of(
    st.builds(
        lambda s, z: (T0 + dt.timedelta(seconds=s)).strftime("%Y-%m-%dT%H:%M:%S.%f") + z,
        st.floats(-1e9, 1e9, allow_nan=False),
        st.sampled_from(["Z", "", "+02:00", "-0800", " UTC", "+25:00", "z", " +01", "+14:00"]),
    ),
    JUNK,
)
BEACONS = st.one_of(st.integers(-(2**70), 2**70).map(str), st.integers(0, 3).map(str), JUNK)
VALUES = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr), st.floats(0.1, 50.0).map(str), JUNK
)


@LINES
@given(
    st.sampled_from(["range_m", "owtt_s", "twtt_s", "range"]),
    st.lists(st.tuples(STAMPS, BEACONS, VALUES), max_size=6),
    st.integers(0, 3),
)
def test_usbl_near_valid_lines(column: str, rows, repeat: int):
    body = [f"{t},{b},{v}" for t, b, v in rows]
    body += body[:repeat]  # repeated lines are used once
    text = f"utc,beacon,{column}\n" + "\n".join(body) + "\n"
    log = _only_own_errors(read_usbl, _file("u.csv", text.encode()), beacons=[0, 1, 2] if repeat else None)
    if log is not None:
        _check_ranges(log)


# --- GNSS-A ping files ------------------------------------------------------------------------------

PING = (
    "49231669.0 55.7853 115.8632 53.3079 0.0168 0.0150 0.0177 "
    "49231669.3858 55.8253 115.8 53.3 0.0168 0.015 0.0177 0.1858"
)
HEADER = "# Topocentric coordinates: Lat0=32.8668445 deg., Lon0=-117.2701205 deg., H0=-88.738 m"


@BYTES
@given(st.binary(max_size=200))
def test_gnssa_random_bytes(blob: bytes):
    survey = _only_own_errors(read_gnssa, _file("g.txt", blob))
    if survey is not None:
        assert np.all(np.isfinite(survey.twtt_s)) and np.all((survey.twtt_s > 0) & (survey.twtt_s < 60))


@LINES
@given(
    st.lists(st.tuples(st.integers(0, 15), JUNK), max_size=4),
    st.sampled_from([HEADER, "# Lat0=1e999 Lon0=nan H0=x", "# Lat0=95 Lon0=0 H0=0", "#"]),
)
def test_gnssa_near_valid_lines(edits, header: str):
    lines = [header]
    for k in range(3):
        fields = PING.split()
        fields[0] = str(49231669.0 + k)
        fields[7] = str(49231669.3858 + k)
        lines.append(" ".join(fields))
    for field, text in edits:
        fields = lines[2].split()
        if field < len(fields):
            fields[field] = text
        lines[2] = " ".join(fields)
    survey = _only_own_errors(read_gnssa, _file("p.txt", ("\n".join(lines) + "\n").encode()))
    if survey is not None:
        assert np.all(np.isfinite(survey.transmit_enu_m)) and np.all(survey.sigma_transmit_enu_m > 0)
        assert survey.n_pings + len(survey.qc.issues) >= 3


# --- TOML scenario loaders -------------------------------------------------------------------------

LOADERS = {
    "survey": survey_scenario_from_table,
    "flock": flock_scenario_from_table,
    "drift": lambda root: drift_scenario_from_table(root, None),
}
SCENARIOS = [(kind, name) for kind in LOADERS for name in builtin_names(kind)]
TOML_VALUES = st.one_of(
    st.sampled_from(
        [
            "1e308",
            "-1e308",
            "nan",
            "inf",
            "-inf",
            "0",
            "-0.0",
            "-1",
            "1e-320",
            "1e30",
            "1e-300",
            "5e-324",
            "9" * 30,
            "-" + "9" * 30,
            "9" * 400 + ".0",
            '"x"',
            '""',
            "[]",
            "[1, 2]",
            "[1e999]",
            "[nan, 1, 2]",
            "[" + "9" * 400 + ", 1, 2]",
            "{}",
            "true",
            "2024-01-01",
            "[[1]]",
            "[" * 40 + "]" * 40,
            "{a = {b = {c = 1}}}",
        ]
    ),
    st.integers(-(2**63), 2**63 - 1).map(str),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
)


def _scenario_text(kind: str, name: str) -> str:
    return builtin_folder(kind).joinpath(f"{name}.toml").read_text(encoding="utf-8")


@BYTES
@given(st.text(max_size=120))
def test_toml_random_text(text: str):
    root = _only_own_errors(parse_toml, text, "fuzz.toml")
    for load in LOADERS.values():
        if root is not None:
            _only_own_errors(load, parse_toml(text, "fuzz.toml"))


@SCENARIO_EDITS
@given(st.sampled_from(SCENARIOS), st.data())
def test_toml_scenarios_with_hostile_values(scenario, data):
    """A built-in scenario with one to three values replaced (or lines dropped): loaded, or refused with
    a ConfigError; never another exception."""
    kind, name = scenario
    lines = _scenario_text(kind, name).splitlines()
    assignments = [i for i, line in enumerate(lines) if "=" in line and not line.lstrip().startswith("#")]
    for _ in range(data.draw(st.integers(1, 3))):
        i = data.draw(st.sampled_from(assignments))
        key = lines[i].split("=", 1)[0]
        lines[i] = "" if data.draw(st.integers(0, 9)) == 0 else f"{key}= {data.draw(TOML_VALUES)}"
    text = "\n".join(lines) + "\n"
    root = _only_own_errors(parse_toml, text, f"{name}.toml")
    if root is not None:
        _only_own_errors(LOADERS[kind], root)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("a = " + "[" * 500 + "]" * 500, "not valid TOML .arrays or tables nested too deeply"),
        ("a = " + "{b = " * 500 + "1" + "}" * 500, "not valid TOML .arrays or tables nested too deeply"),
        ("[" + ".".join(["a"] * 500) + "]\nx = 1", "tables and arrays nested deeper than 16 levels"),
        ("x = " + "9" * 5000, "not valid TOML .Exceeds the limit .4300 digits"),
    ],
)
def test_toml_nested_500_deep_or_a_5000_digit_number_is_a_config_error(text: str, message: str):
    with pytest.raises(OceanlocError, match=rf"deep\.toml: {message}"):
        parse_toml(text, "deep.toml")


@pytest.mark.parametrize("value", ["9" * 400, "[" + "9" * 400 + ", 1.0, 2.0]"])
def test_toml_integer_beyond_a_float_is_a_config_error(value: str):
    text = _scenario_text("survey", "garcia2019-m1").replace("speed_mps = 3.0", f"speed_mps = {value}")
    text = text.replace("start_enu_m = [-3.0, 9.0, 0.0]", f"start_enu_m = {value}") if "[" in value else text
    with pytest.raises(
        OceanlocError, match=r"\[vehicle\] field '(speed_mps|start_enu_m)': must (be|hold) finite"
    ):
        survey_scenario_from_table(parse_toml(text, "big.toml"))


# --- WAV --------------------------------------------------------------------------------------------


def _wav(n: int = 64, channels: int = 1, width: int = 2, rate: int = 8000) -> bytes:
    buf = io.BytesIO()
    with wave.open(buf, "wb") as f:
        f.setnchannels(channels)
        f.setsampwidth(width)
        f.setframerate(rate)
        f.writeframes(bytes(range(256)) * (n * channels * width // 256 + 1))
    return buf.getvalue()[: 44 + n * channels * width]


def _check_recording(rec) -> None:
    assert rec.sample_rate_hz > 0 and rec.samples.shape[0] > 0
    assert np.all(np.isfinite(rec.samples))
    if not rec.sample_format.startswith("float"):  # integer formats are scaled to full scale
        assert np.all(np.abs(rec.samples) <= 1.0)


@BYTES
@given(st.binary(max_size=200))
def test_wav_random_bytes(blob: bytes):
    rec = _only_own_errors(read_wav, _file("r.wav", b"RIFF" + blob if blob[:1] == b"R" else blob))
    if rec is not None:
        _check_recording(rec)


@LINES
@given(
    st.sampled_from([(1, 1), (1, 2), (2, 2), (1, 3), (1, 4), (3, 2)]),
    st.lists(st.tuples(st.integers(0, 43), st.integers(0, 255)), max_size=4),
    st.one_of(st.none(), st.integers(0, 200)),
    st.sampled_from([None, 0, 2**32 - 1, 1]),
)
def test_wav_near_valid_headers_and_truncations(shape, flips, cut, data_size):
    """A valid small WAV with header bytes changed, the data size field set to 0, 1 or 4 GiB, and the file
    cut anywhere: a Recording of finite full-scale samples, or a DataError naming the file."""
    channels, width = shape
    raw = bytearray(_wav(channels=channels, width=width))
    complete = len(raw)
    for pos, value in flips:
        raw[pos] = value
    if data_size is not None:
        raw[40:44] = struct.pack("<I", data_size)
    if cut is not None:
        raw = raw[:cut]
    rec = _only_own_errors(read_wav, _file("h.wav", bytes(raw)))
    if rec is not None:
        _check_recording(rec)
    if not flips and data_size is None and cut is not None and cut < complete:
        assert rec is None  # a cut file is reported, never returned as a shorter recording
