"""The gpsd client: its QC on gpsd reports, and the real gpsd daemon fed NMEA through a pty (loopback)."""

import datetime as dt
import itertools
import json
import os
import shutil
import socket
import subprocess
import threading
import time
import tty
from pathlib import Path

import numpy as np
import pynmea2
import pytest
from hypothesis import given
from hypothesis import strategies as st

from oceanloc.errors import DataError
from oceanloc.io.gpsd import GpsdClient, GpsdReportParser, read_gpsd_lines
from oceanloc.io.nmea import GpsFix, Heading, format_gga, format_hdt, format_zda
from oceanloc.io.qc import QcReport
from oceanloc.io.streams import open_position_stream
from tests.field._live_rig import LOOPBACK, free_port, wait_listening

NEEDS_GPSD = pytest.mark.skipif(
    shutil.which("gpsd") is None, reason="gpsd is not installed (apt-get install gpsd gpsd-clients)"
)


def _tpv(**fields) -> str:
    return json.dumps({"class": "TPV", "mode": 3, "time": "2018-01-04T18:00:00.000Z", **fields})


@pytest.mark.parametrize(
    ("line", "reason", "detail"),
    [
        ('{"class":"TPV","mode":1,"time":"2018-01-04T18:00:00.000Z"}', "invalid fix", "TPV mode 1 (no fix)"),
        ('{"class":"TPV","mode":3,"lat":1.0,"lon":2.0}', "truncated sentence", "TPV without time"),
        (_tpv(lat="north", lon=2.0, altHAE=0.0), "non-numeric field", "lat 'north' is not a number"),
        (_tpv(lat=91.0, lon=2.0, altHAE=0.0), "out-of-range value", "lat 91.0"),
        (_tpv(lat=1.0, lon=-181.0, altHAE=0.0), "out-of-range value", "lon -181.0"),
        (
            '{"class":"TPV","mode":3,"time":"2018-01-04T18:00:00Z","lat":NaN,"lon":2,"altHAE":0}',
            "NaN or infinite value",
            "",
        ),
        (_tpv(mode=2, lat=1.0, lon=2.0), "invalid fix", "2D fix without altitude"),
        (_tpv(lat=1.0, lon=2.0, altHAE=0.0, time="yesterday"), "non-numeric field", "Invalid isoformat"),
        ('{"class":"TPV", "mode":3, "lat":', "truncated sentence", "not JSON"),
        ("[1, 2]", "truncated sentence", "not a JSON object"),
        ('{"class":"ERROR","message":"unrecognized request"}', "gpsd error", "unrecognized request"),
        ('{"class":"ATT","heading":"east"}', "non-numeric field", "heading 'east'"),
    ],
)
def test_bad_reports_are_recorded_with_a_reason(line: str, reason: str, detail: str):
    qc = QcReport()
    assert GpsdReportParser().feed(7, line, qc, "gpsd://127.0.0.1:2947") is None
    (issue,) = qc.issues
    assert (issue.file, issue.line, issue.reason) == ("gpsd://127.0.0.1:2947", 7, reason)
    assert detail in issue.detail
    assert str(issue).startswith(f"gpsd://127.0.0.1:2947:7: {reason}")


def test_heights_headings_and_time_order():
    lines = [
        '{"class":"VERSION","release":"3.22"}',
        '{"class":"ATT","heading":370.5}',
        _tpv(lat=32.7, lon=-117.2, altMSL=-1.5, geoidSep=-35.0),
        '{"class":"ATT","heading":12.5}',
        _tpv(lat=32.7, lon=-117.2, altHAE=-36.0),  # same time: not kept
        _tpv(lat=32.7, lon=-117.2, alt=-1.0, time="2018-01-04T18:00:01.000Z"),
        '{"class":"HDG","heading":-10.0}',
    ]
    records, qc = read_gpsd_lines(lines, "rec")
    assert [r.heading_deg for r in records if isinstance(r, Heading)] == [12.5, 350.0]
    fixes = [r for r in records if isinstance(r, GpsFix)]
    assert [f.h_m for f in fixes] == [-36.5, -1.0]  # altMSL + geoidSep; alt (+ no separation)
    assert [(i.line, i.reason) for i in qc.issues] == [(2, "out-of-range value"), (5, "time going backwards")]
    assert records[0].t_unix_s == dt.datetime(2018, 1, 4, 18, tzinfo=dt.UTC).timestamp()  # heading at the fix
    with pytest.raises(DataError, match="rec: no valid fix or heading"):
        read_gpsd_lines(['{"class":"TPV","mode":0}'], "rec")


# ------------------------------------------------------------------------------------- the real daemon


def _no_fix_gga(t: dt.datetime) -> str:
    fields = (t.strftime("%H%M%S.00"), "", "", "", "", "0", "00", "99.99", "", "", "", "", "", "")
    return str(pynmea2.GGA("GP", "GGA", fields))


class _NmeaFeeder(threading.Thread):
    """Writes epochs of GGA + HDT + ZDA into the pty master, a fix every 0.1 s of wall time."""

    def __init__(self, fd: int, t0: dt.datetime, n_good: int, n_bad: int) -> None:
        super().__init__(daemon=True)
        self.fd, self.t0, self.n_good, self.n_bad = fd, t0, n_good, n_bad
        self.stop = threading.Event()
        self.fed: list[tuple[float, float, float]] = []

    def run(self) -> None:
        k = 0
        while not self.stop.is_set():
            t = self.t0 + dt.timedelta(seconds=k)
            good = k % (self.n_good + self.n_bad) < self.n_good
            lat = 32.705 + 1e-5 * k
            # A receiver without a fix sends GGA with quality 0 and empty position fields. (gpsd 3.22
            # reports a quality-0 GGA that still carries a position as a 3D fix: it cannot be told apart.)
            gga = format_gga(t, lat, -117.236, -1.478) if good else _no_fix_gga(t)
            lines = [gga, format_hdt(10.0 + k), format_zda(t)]
            if good:
                self.fed.append((t.timestamp(), lat, 10.0 + k))
            try:
                os.write(self.fd, ("\r\n".join(lines) + "\r\n").encode())
            except OSError:
                return
            k += 1
            self.stop.wait(0.1)


@pytest.fixture
def gpsd_on_a_pty():
    master, slave = os.openpty()
    tty.setraw(slave)
    port = free_port(socket.SOCK_STREAM)
    # -N foreground, -n poll the device without waiting for a client, -b read-only (never write to the
    # "receiver"), -S the port; gpsd listens on loopback only unless given -G.
    proc = subprocess.Popen(
        ["gpsd", "-N", "-n", "-b", "-S", str(port), os.ttyname(slave)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        wait_listening(port, proc)
        yield master, port
    finally:
        proc.terminate()
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
        os.close(master)
        os.close(slave)


@NEEDS_GPSD
def test_real_gpsd_fixes_and_headings_through_a_pty(gpsd_on_a_pty):
    master, port = gpsd_on_a_pty
    t0 = dt.datetime.now(dt.UTC).replace(microsecond=0) - dt.timedelta(seconds=60)
    feeder = _NmeaFeeder(master, t0, n_good=6, n_bad=2)
    feeder.start()
    try:
        with open_position_stream(f"gpsd://{LOOPBACK}:{port}") as client:
            assert isinstance(client, GpsdClient)
            records = []
            deadline = time.monotonic() + 20.0
            while sum(isinstance(r, GpsFix) for r in records) < 10 and time.monotonic() < deadline:
                rec = client.read(2.0)
                if rec is not None:
                    records.append(rec)
            qc = client.qc
    finally:
        feeder.stop.set()
        feeder.join(2)
    fixes = [r for r in records if isinstance(r, GpsFix)]
    headings = [r for r in records if isinstance(r, Heading)]
    assert len(fixes) >= 10, qc.summary()
    fed = {round(t, 3): (lat, hdg) for t, lat, hdg in feeder.fed}
    for f in fixes:
        # Every fix gpsd reports is one we fed, to its printed precision (1e-9 deg), at the ellipsoidal
        # height of the GGA (altitude -1.478 m, separation 0).
        assert round(f.t_unix_s, 3) in fed
        assert abs(f.lat_deg - fed[round(f.t_unix_s, 3)][0]) < 1e-8
        assert f.lon_deg == pytest.approx(-117.236, abs=1e-8) and f.h_m == pytest.approx(-1.478, abs=1e-3)
    assert all(b.t_unix_s > a.t_unix_s for a, b in itertools.pairwise(fixes))
    # HDT comes back as ATT headings (10 + k degrees for epoch k).
    assert headings and all((h.heading_deg - 10.0) % 1.0 == 0.0 for h in headings)
    # The quality-0 epochs come back as TPV mode 1 and are recorded, not kept.
    assert qc.counts().get("invalid fix", 0) >= 1
    assert all(i.file == f"gpsd://{LOOPBACK}:{port}" for i in qc.issues)


@NEEDS_GPSD
def test_real_gpsd_going_away_is_a_data_error(gpsd_on_a_pty):
    _, port = gpsd_on_a_pty
    client = GpsdClient(LOOPBACK, port)
    assert client.read(0.3) is None  # no receiver data yet: None at the timeout, not a hang
    client.close()
    with pytest.raises(DataError, match="cannot connect"):
        GpsdClient(LOOPBACK, free_port(socket.SOCK_STREAM), connect_timeout_s=1.0)


def _rmc(t: dt.datetime, lat_deg: float, lon_deg: float) -> str:
    lat = f"{int(lat_deg):02d}{(lat_deg % 1) * 60:07.4f}"
    lon = f"{int(abs(lon_deg)):03d}{(abs(lon_deg) % 1) * 60:07.4f}"
    fields = (t.strftime("%H%M%S.00"), "A", lat, "N", lon, "W", "0.0", "0.0", t.strftime("%d%m%y"), "", "")
    return str(pynmea2.RMC("GP", "RMC", fields))


NEEDS_GPSFAKE = pytest.mark.skipif(
    shutil.which("gpsfake") is None, reason="gpsfake is not installed (apt-get install gpsd-clients)"
)


@NEEDS_GPSFAKE
def test_gpsfake_replays_a_recorded_file(tmp_path: Path):
    # gpsd hunts for the baud rate and sentence type first, so the early sentences of a replay may be
    # lost: 60 epochs of GGA + RMC, and every fix read must be one of them.
    t0 = dt.datetime(2026, 1, 4, 18, 0, tzinfo=dt.UTC)
    epochs = [(t0 + dt.timedelta(seconds=k), 32.705 + 1e-5 * k) for k in range(60)]
    log = tmp_path / "recorded.nmea"
    log.write_text(
        "".join(
            f"{format_gga(t, lat, -117.236, -1.478)}\r\n{_rmc(t, lat, -117.236)}\r\n" for t, lat in epochs
        )
    )
    port = free_port(socket.SOCK_STREAM)
    proc = subprocess.Popen(
        ["gpsfake", "-1", "-q", "-c", "0.02", "-P", str(port), str(log)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    fixes = []
    try:
        deadline = time.monotonic() + 10.0
        while True:  # gpsfake starts replaying when the first client watches: connect, do not probe
            try:
                client = GpsdClient(LOOPBACK, port, connect_timeout_s=0.5)
                break
            except DataError:
                if time.monotonic() > deadline or proc.poll() is not None:
                    raise
                time.sleep(0.1)
        with client:
            deadline = time.monotonic() + 20.0
            while len(fixes) < 5 and time.monotonic() < deadline:
                rec = client.read(1.0)
                if isinstance(rec, GpsFix):
                    fixes.append(rec)
    finally:
        proc.terminate()
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
    want = {t.timestamp(): lat for t, lat in epochs}
    assert len(fixes) >= 5
    assert all(abs(f.lat_deg - want[f.t_unix_s]) < 1e-6 for f in fixes)  # RMC carries 1e-4 arc-minutes


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=True) | st.text(max_size=30),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner, max_size=3),
    max_leaves=8,
)
TPV_KEYS = st.sampled_from(
    ["class", "mode", "time", "lat", "lon", "altHAE", "altMSL", "alt", "geoidSep", "heading"]
)


@given(
    st.dictionaries(TPV_KEYS, JSON_VALUES, max_size=8), st.sampled_from(["TPV", "ATT", "HDG", "ERROR", None])
)
def test_arbitrary_reports_are_kept_or_recorded_never_raised(obj: dict, kind):
    if kind is not None:
        obj = {**obj, "class": kind}
    qc = QcReport()
    rec = GpsdReportParser().feed(1, json.dumps(obj), qc, "gpsd://x")
    if isinstance(rec, GpsFix):
        assert -90 <= rec.lat_deg <= 90 and -180 <= rec.lon_deg <= 180 and np.isfinite(rec.h_m)
    assert all(str(i).startswith("gpsd://x:1: ") for i in qc.issues)


@given(st.text(max_size=200))
def test_arbitrary_text_is_recorded_never_raised(text: str):
    qc = QcReport()
    GpsdReportParser().feed(3, text, qc, "gpsd://x")
