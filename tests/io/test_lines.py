"""Line-by-line parsing gives exactly what the file readers give: records, QC issues and counts."""

import datetime as dt
from pathlib import Path

import numpy as np
import pynmea2
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from oceanloc.errors import DataError
from oceanloc.io import lines
from oceanloc.io.nmea import (
    GpsFix,
    Heading,
    NmeaLineParser,
    format_gga,
    format_hdt,
    format_zda,
    gps_log_from_records,
    read_nmea,
)
from oceanloc.io.qc import QcReport, decode_line
from oceanloc.io.usbl import UsblLineParser, range_log_from_records, read_usbl

T0 = dt.datetime(2018, 1, 4, 18, 0, tzinfo=dt.UTC)


def _with_field(sentence: str, index: int, value: str) -> bytes:
    """``sentence`` with field ``index`` (0: the talker and type) replaced and a valid checksum."""
    fields = sentence.split("*")[0][1:].split(",")
    fields[index] = value
    return str(pynmea2.parse("$" + ",".join(fields))).encode()


FUZZ = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

NMEA_POOL = [
    format_zda(T0).encode(),
    *(
        format_gga(T0 + dt.timedelta(seconds=k), 32.705 + 1e-5 * k, -117.236, -1.478).encode()
        for k in range(6)
    ),
    format_gga(T0 + dt.timedelta(seconds=7), 32.7, -117.2, 0.0, quality=0).encode(),
    format_hdt(13.0).encode(),
    format_gga(T0, 32.705, -117.236, -1.478)[:-2].encode() + b"FF",
    format_gga(T0, 32.705, -117.236, -1.478)[:20].encode(),
    b"$GPGGA,180002.00,32xx.3,N,11714.16,W,2,9,0.9,0,M,0,M,,",
    b"$GPRMC,180009.00,V,3242.3,N,11714.16,W,0.0,0.0,040118,,*00",
    b"$GPXXX,1,2*00",
    b"no dollar here",
    b"\xc3\x28 not UTF-8",
    b"$GPGGA\x00,1",
    b"   ",
    # The readers' range checks: latitude, height, time of day, date, heading.
    format_gga(T0 + dt.timedelta(seconds=8), 95.0, -117.236, -1.478).encode(),
    format_gga(T0 + dt.timedelta(seconds=9), 32.7, -117.2, 2e4).encode(),
    _with_field(format_gga(T0, 32.7, -117.2, 0.0), 1, "186000.00"),
    _with_field(format_zda(T0), 4, "2150"),
    str(pynmea2.HDT("GP", "HDT", ("400.0", "T"))).encode(),
]


def _feed_nmea(raw_lines: list[bytes], source: str) -> tuple[list, list, QcReport]:
    qc = QcReport()
    parser = NmeaLineParser()
    fixes, headings = [], []
    for number, raw in enumerate(raw_lines, start=1):
        text = decode_line(raw, number, qc, source)
        if text is None:
            continue
        rec = parser.feed(number, text, qc, source)
        if isinstance(rec, GpsFix):
            fixes.append(rec)
        elif isinstance(rec, Heading):
            headings.append(rec)
    return fixes, headings, qc


@FUZZ
@given(st.lists(st.sampled_from(NMEA_POOL), min_size=1, max_size=25))
def test_nmea_lines_equal_the_file_reader(tmp_path: Path, lines: list[bytes]):
    path = tmp_path / "gps.nmea"
    path.write_bytes(b"\n".join(lines) + b"\n")
    fixes, headings, qc = _feed_nmea(lines, str(path))
    try:
        log = read_nmea(path)
    except DataError as exc:
        assert not fixes
        with pytest.raises(DataError) as again:
            gps_log_from_records(fixes, headings, qc, str(path))
        # The same reasons, in the same order, in both messages.
        assert str(exc).split("(")[0] == str(again.value).split("(")[0]
        return
    streamed = gps_log_from_records(fixes, headings, qc, str(path))
    for name in ("t_unix_s", "lat_deg", "lon_deg", "h_m", "heading_t_unix_s", "heading_deg", "line"):
        np.testing.assert_array_equal(getattr(streamed, name), getattr(log, name), err_msg=name)
    assert streamed.qc.issues == log.qc.issues
    assert (streamed.qc.lines_read, streamed.qc.records_kept) == (log.qc.lines_read, log.qc.records_kept)


USBL_POOL = [
    "2018-01-04T18:00:00.500Z,1,9.184",
    "2018-01-04T18:00:01.000Z,x,0.01",
    "2018-01-04T18:00:01.500Z,1,nan",
    "2018-01-04T18:00:02.000Z,1,-0.01",
    "2018-01-04T18:00:02.500Z,7,3.0",
    "2018-01-04T18:00:00.000Z,2,5.0",
    "2018-01-04T18:00:03.500,2,2.731",
    "2018-01-04T18:00:04",
    "not-a-time,1,2.0",
    "# a comment",
    "2018-01-04T18:00:05.000Z,2,20000",
    # The reader's newer rules: zone offsets, time and beacon-id ranges, a header switching the column.
    "2018-01-04T20:00:06.000+02:00,1,4.0",
    "2018-01-04T10:00:06.000 -0800,2,4.5",
    "1970-01-01T00:00:01Z,1,4.0",
    "2018-01-04T18:00:07Z,99999999999,4.0",
    "utc,beacon,twtt_s",
]


@FUZZ
@given(st.sampled_from(["range_m", "owtt_s", "twtt_s"]), st.lists(st.sampled_from(USBL_POOL), max_size=20))
def test_usbl_lines_equal_the_file_reader(tmp_path: Path, column: str, lines: list[str]):
    path = tmp_path / "r.csv"
    all_lines = [f"utc,beacon,{column}", *lines]
    path.write_text("\n".join(all_lines) + "\n")
    qc = QcReport()
    parser = UsblLineParser(sound_speed_mps=1480.0, beacons={1, 2})
    records = []
    for number, raw in enumerate(all_lines, start=1):
        text = decode_line(raw.encode(), number, qc, str(path))
        if text is not None and (rec := parser.feed(number, text, qc, str(path))) is not None:
            records.append(rec)
    try:
        log = read_usbl(path, sound_speed_mps=1480.0, beacons={1, 2})
    except DataError:
        assert not records
        return
    streamed = range_log_from_records(records, qc, str(path))
    for name in ("t_unix_s", "beacon", "range_m", "line"):
        np.testing.assert_array_equal(getattr(streamed, name), getattr(log, name), err_msg=name)
    assert streamed.qc.issues == log.qc.issues
    assert (streamed.qc.lines_read, streamed.qc.records_kept) == (log.qc.lines_read, log.qc.records_kept)


def test_a_stream_without_a_header_needs_a_column_and_a_header_can_switch_it():
    qc = QcReport()
    with pytest.raises(DataError, match="s:1: expected a header 'utc,beacon,range_m'"):
        UsblLineParser().feed(1, "2018-01-04T18:00:00Z,1,5.0", qc, "s")
    parser = UsblLineParser(column="range_m", sound_speed_mps=1500.0)
    first = parser.feed(1, "2018-01-04T18:00:00Z,1,5.0", qc, "s")
    assert parser.feed(2, "utc,beacon,twtt_s", qc, "s") is None
    second = parser.feed(3, "2018-01-04T18:00:01Z,1,0.01", qc, "s")
    assert first.range_m == 5.0 and first.travel_time_s is None
    assert second.range_m == pytest.approx(7.5) and second.travel_time_s == pytest.approx(0.005)
    assert second.to_record()["range_m"] == pytest.approx(7.5) and second.to_record()["status"] == "ok"


def test_the_old_module_re_exports_the_one_implementation():
    assert lines.NmeaLineParser is NmeaLineParser and lines.UsblLineParser is UsblLineParser
    assert lines.decode_line is decode_line and lines.GpsFix is GpsFix and lines.Heading is Heading
    assert sorted(lines.__all__) == sorted(n for n in vars(lines) if not n.startswith("_"))
