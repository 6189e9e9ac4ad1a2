"""Live streams on loopback only: specs, NMEA and range lines over UDP, TCP and a pty, timeouts, errors."""

import datetime as dt
import os
import socket
import threading
import time
import tty

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oceanloc.errors import ConfigError, DataError
from oceanloc.io.nmea import GpsFix, Heading, format_gga, format_hdt, format_zda
from oceanloc.io.streams import (
    NmeaStream,
    RangeTextStream,
    SeatracRangeStream,
    StreamTimeoutError,
    open_position_stream,
    open_range_stream,
    parse_spec,
)
from oceanloc.io.transports import UdpLineSource
from oceanloc.io.usbl import RangeRecord
from oceanloc.sim.seatrac_beacon import BeaconSimConfig, SeatracBeaconSimulator

T0 = dt.datetime(2018, 1, 4, 18, 0, tzinfo=dt.UTC)
LOOPBACK = "127.0.0.1"


def _nmea_lines() -> list[str]:
    return [
        format_zda(T0),
        format_gga(T0, 32.705, -117.236, -1.478),
        format_hdt(13.0),
        format_gga(T0, 32.705, -117.236, -1.478)[:-2] + "FF",  # bad checksum
        format_gga(T0 + dt.timedelta(seconds=1), 32.70501, -117.236, -1.478),
        format_gga(T0, 32.705, -117.236, -1.478),  # time going backwards
    ]


def _check_nmea(records: list, qc, name: str) -> None:
    fixes = [r for r in records if isinstance(r, GpsFix)]
    headings = [r for r in records if isinstance(r, Heading)]
    assert [f.t_unix_s - T0.timestamp() for f in fixes] == [0.0, 1.0]
    assert fixes[1].lat_deg == pytest.approx(32.70501, abs=1e-7)
    assert [(h.t_unix_s, h.heading_deg) for h in headings] == [(T0.timestamp(), 13.0)]
    got = [(i.line, i.reason) for i in qc.issues]
    assert got == [(4, "bad checksum"), (6, "time going backwards")]
    assert str(qc.issues[0]).startswith(f"{name}:4: bad checksum (")


def _free_port(kind: int) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind((LOOPBACK, 0))
        return s.getsockname()[1]


# ------------------------------------------------------------------------------------------------ specs


def test_specs_parse():
    s = parse_spec("udp://127.0.0.1:10110")
    assert (s.scheme, s.host, s.port, s.path) == ("udp", "127.0.0.1", 10110, "")
    assert parse_spec("gpsd://127.0.0.1").port == 2947
    s = parse_spec("serial:///dev/ttyUSB0?baud=4800")
    assert (s.scheme, s.path, s.baud) == ("serial", "/dev/ttyUSB0", 4800)
    s = parse_spec("seatrac:///dev/ttyUSB1?beacons=1,2&timeout=2.5")
    assert (s.path, s.beacons, s.baud, s.params["timeout"]) == ("/dev/ttyUSB1", (1, 2), 115200, "2.5")
    assert parse_spec("serial:///dev/ttyUSB0").baud == 4800
    assert parse_spec("tcp://localhost:2947").host == "localhost"


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("127.0.0.1:10110", "expected SCHEME://"),
        ("http://127.0.0.1:80", "scheme 'http' is not one of"),
        ("udp://:10110", "no host"),
        ("tcp://127.0.0.1", "no port"),
        ("tcp://127.0.0.1:99999", "Port out of range"),
        ("tcp://127.0.0.1:abc", "Port could not be cast"),
        ("udp://127.0.0.1:10110/x", "unexpected path '/x'"),
        ("udp://127.0.0.1:10110?baud=9600", "unknown option 'baud' \\(allowed: column\\)"),
        ("serial://dev/ttyUSB0", "needs three slashes"),
        ("serial:///dev/ttyUSB0?baud=fast", "baud 'fast' is not an integer"),
        ("serial:///dev/ttyUSB0?baud=9600&baud=4800", "option 'baud' given twice"),
        ("seatrac:///dev/ttyUSB1", "no beacons"),
        ("seatrac:///dev/ttyUSB1?beacons=1,x", "not integers"),
        ("seatrac:///dev/ttyUSB1?beacons=1,1", "distinct ids from 1 to 15"),
        ("seatrac:///dev/ttyUSB1?beacons=16", "distinct ids from 1 to 15"),
        ("seatrac:///dev/ttyUSB1?beacons=1&timeout=0", "outside \\(0, 600\\]"),
        ("seatrac:///dev/ttyUSB1?beacons=1&msg=OWAY", "msg 'OWAY' is not REQ"),
        ("tcp://127.0.0.1:1?column=feet", "column 'feet' is not one of range_m, owtt_s, twtt_s"),
    ],
)
def test_bad_specs_are_one_line_config_errors(spec: str, message: str):
    with pytest.raises(ConfigError, match=message) as err:
        parse_spec(spec)
    assert str(err.value).startswith(f"source {spec!r}: ") and "\n" not in str(err.value)


def test_position_and_range_sources_accept_only_their_schemes():
    with pytest.raises(ConfigError, match="position source 'seatrac:///dev/x\\?beacons=1': scheme 'seatrac'"):
        open_position_stream("seatrac:///dev/x?beacons=1")
    with pytest.raises(ConfigError, match=r"range source 'gpsd://127\.0\.0\.1': scheme 'gpsd'"):
        open_range_stream("gpsd://127.0.0.1")


# ---------------------------------------------------------------------------------------------- NMEA


def test_nmea_over_udp_with_several_sentences_per_datagram():
    with open_position_stream(f"udp://{LOOPBACK}:0") as stream:
        assert isinstance(stream, NmeaStream)
        host, port = stream.source.address
        lines = _nmea_lines()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(("\r\n".join(lines[:3]) + "\r\n").encode(), (host, port))
            for line in lines[3:]:
                tx.sendto(line.encode(), (host, port))  # one sentence per datagram, no line end
        records = [stream.read(1.0) for _ in range(3)]
        t0 = time.monotonic()
        assert stream.read(0.2) is None  # nothing more: None at the timeout, not a hang
        assert 0.2 <= time.monotonic() - t0 < 0.5
        _check_nmea(records, stream.qc, stream.name)


def _serve_tcp(payload: bytes, *, close: bool = True):
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.bind((LOOPBACK, 0))
    server.listen(1)
    port = server.getsockname()[1]

    def run():
        conn, _ = server.accept()
        with conn:
            for k in range(0, len(payload), 7):  # dribble: lines split across segments
                conn.sendall(payload[k : k + 7])
            if not close:
                time.sleep(1.0)
        server.close()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return port, thread


def test_nmea_over_tcp_then_the_server_closes():
    port, thread = _serve_tcp(("\r\n".join(_nmea_lines()) + "\r\n").encode())
    stream = open_position_stream(f"tcp://{LOOPBACK}:{port}")
    records = [stream.read(2.0) for _ in range(3)]
    with pytest.raises(DataError, match=f"tcp://127.0.0.1:{port}: connection closed by the other end"):
        stream.read(2.0)
    _check_nmea(records, stream.qc, f"tcp://{LOOPBACK}:{port}")
    stream.close()
    thread.join(2)


def test_nmea_over_a_serial_pty():
    master, slave = os.openpty()
    tty.setraw(slave)
    try:
        with open_position_stream(f"serial://{os.ttyname(slave)}?baud=4800") as stream:
            os.write(master, ("\r\n".join(_nmea_lines()) + "\r\n").encode())
            records = [stream.read(1.0) for _ in range(3)]
            with pytest.raises(StreamTimeoutError, match=r"nothing valid for 0\.1 s"):
                list(stream.records(idle_timeout_s=0.1))
            _check_nmea(records, stream.qc, f"serial://{os.ttyname(slave)}?baud=4800")
    finally:
        os.close(master)
        os.close(slave)


def test_a_flood_of_bad_lines_does_not_hold_the_reader_past_its_timeout():
    src = UdpLineSource(LOOPBACK, 0)
    stream = NmeaStream(src)
    flood = b"\n".join(b"$GPGGA,garbage*00" for _ in range(3000)) + b"\n"
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        for k in range(0, len(flood), 30000):
            tx.sendto(flood[k : k + 30000], src.address)
    t0 = time.monotonic()
    assert stream.read(0.05) is None
    # The property is a bounded wait, not a speed: 3000 bad lines are QC'd within a few tenths of a second
    # on an idle machine; 2 s leaves room for a loaded one while still catching a reader that drains them all.
    assert time.monotonic() - t0 < 2.0
    assert stream.qc.counts()["bad checksum"] >= 1
    stream.close()


def test_unreachable_sources_are_data_errors():
    port = _free_port(socket.SOCK_STREAM)
    with pytest.raises(DataError, match=f"tcp://127.0.0.1:{port}: cannot connect"):
        open_position_stream(f"tcp://{LOOPBACK}:{port}")
    with pytest.raises(DataError, match="serial:///dev/oceanloc-none: cannot open the serial port"):
        open_position_stream("serial:///dev/oceanloc-none")
    with pytest.raises(DataError, match=r"gpsd://127\.0\.0\.1:\d+: cannot connect"):
        open_position_stream(f"gpsd://{LOOPBACK}:{port}")


# -------------------------------------------------------------------------------------------- ranges


def test_range_lines_over_udp_and_tcp():
    lines = [
        "2018-01-04T18:00:00.500Z,1,9.184",
        "2018-01-04T18:00:01.000Z,x,0.01",
        "2018-01-04T18:00:01.500Z,7,3.0",  # unknown beacon
        "utc,beacon,owtt_s",
        "2018-01-04T18:00:02.000Z,2,0.004",
    ]
    with open_range_stream(f"udp://{LOOPBACK}:0", beacons={1, 2}, sound_speed_mps=1500.0) as stream:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            for line in lines:
                tx.sendto((line + "\n").encode(), stream.source.address)
        got = [stream.read(1.0) for _ in range(2)]
        assert [(r.beacon, r.range_m) for r in got] == [(1, 9.184), (2, pytest.approx(6.0))]
        assert [(i.line, i.reason) for i in stream.qc.issues] == [
            (2, "non-numeric field"),
            (3, "unknown beacon id"),
        ]
    port, thread = _serve_tcp(("\n".join(lines) + "\n").encode())
    with open_range_stream(f"tcp://{LOOPBACK}:{port}?column=range_m", beacons={1, 2}) as stream:
        got = [stream.read(2.0) for _ in range(2)]
        assert all(isinstance(r, RangeRecord) and r.ok for r in got) and got[
            1
        ].travel_time_s == pytest.approx(0.004)
        assert str(stream.qc.issues[1]) == f"tcp://127.0.0.1:{port}?column=range_m:3: unknown beacon id (7)"
    thread.join(2)


def test_seatrac_spec_pings_the_simulated_beacons():
    cfg = BeaconSimConfig(
        transponders_enu_m={1: (30.0, 40.0, -50.0), 2: (-60.0, 20.0, -45.0)},
        sigma_range_m=0.0,
        p_dropout=0.0,
        p_multipath=0.0,
        time_scale=0.02,
    )
    sim = SeatracBeaconSimulator(cfg, lambda t: np.zeros(3), np.random.default_rng(3))
    with (
        sim,
        open_range_stream(f"seatrac://{sim.port}?beacons=2,1&timeout=1", sound_speed_mps=1500.0) as stream,
    ):
        assert isinstance(stream, SeatracRangeStream)
        got = [stream.read(1.0) for _ in range(4)]
    assert [r.beacon for r in got] == [2, 1, 2, 1]
    truth = {1: float(np.linalg.norm([30.0, 40.0, -50.0])), 2: float(np.linalg.norm([-60.0, 20.0, -45.0]))}
    for r in got:
        # The simulator reports RANGE_TIME rounded to 100 ns; at 1500 m/s that is 0.15 mm.
        assert r.status == "ok" and abs(r.range_m - truth[r.beacon]) < 2e-4


class _Lines:
    """A line source replaying given raw lines (for fuzzing the streams without a socket)."""

    name = "fuzz://lines"

    def __init__(self, lines: list[bytes]) -> None:
        self.lines = list(lines)

    def read_line(self, timeout_s: float) -> bytes | None:
        return self.lines.pop(0) if self.lines else None

    def close(self) -> None:
        pass


@settings(max_examples=150, deadline=None)
@given(st.lists(st.binary(max_size=120) | st.text(max_size=120).map(str.encode), max_size=12))
def test_arbitrary_lines_raise_nothing_and_every_issue_names_the_stream(lines: list[bytes]):
    for stream in (NmeaStream(_Lines(lines)), RangeTextStream(_Lines(lines))):
        while stream.read(0.0) is not None:
            pass
        assert all(str(i).startswith("fuzz://lines:") and "\n" not in str(i) for i in stream.qc.issues)


def test_an_overlong_line_is_cut_and_recorded():
    port, thread = _serve_tcp(b"$" + b"A" * 70_000 + b"\n" + (format_zda(T0) + "\r\n").encode())
    with open_position_stream(f"tcp://{LOOPBACK}:{port}") as stream:
        with pytest.raises(DataError, match="connection closed"):
            stream.read(2.0)
        assert (stream.qc.issues[0].line, stream.qc.issues[0].reason) == (1, "truncated sentence")
        assert "line over 65536 bytes" in stream.qc.issues[0].detail
    thread.join(2)
