"""The SeaTrac pinger against the beacon simulator over a pseudo-terminal: ranges, dropouts, timeouts."""

import math
import os
import threading
import time
import tty

import numpy as np
import pytest

from oceanloc.errors import ConfigError, DataError
from oceanloc.io.seatrac import (
    RANGE_VALID,
    AcoFix,
    AcoRange,
    Cst,
    MsgType,
    SeatracPinger,
    decode_frame,
    encode_ping_error,
    encode_ping_resp,
    encode_ping_send,
    encode_ping_send_status,
)
from oceanloc.sim.seatrac_beacon import BeaconSimConfig, SeatracBeaconSimulator

TRANSPONDERS = {1: (30.0, 40.0, -50.0), 2: (-60.0, 20.0, -45.0)}
SIGMA_M = 0.1


def _moving(t0: float):
    """The head moves east at 2 m/s from the origin (so each ping sees a different true range)."""
    return lambda t: np.array([2.0 * (t - t0), 0.0, 0.0])


def test_ranges_dropouts_and_unknown_beacons_end_to_end():
    cfg = BeaconSimConfig(
        transponders_enu_m=TRANSPONDERS,
        sigma_range_m=SIGMA_M,
        p_dropout=0.1,
        p_multipath=0.05,
        time_scale=0.05,
        range_timeout_m=300.0,
    )
    sim = SeatracBeaconSimulator(cfg, _moving(time.monotonic()), np.random.default_rng(7))
    n_cycles = 40
    t_start = time.monotonic()
    with sim, SeatracPinger(sim.port, beacons=[1, 2, 3], sound_speed_mps=1500.0, timeout_s=1.0) as pinger:
        records = list(pinger.records(n_cycles=n_cycles))
    elapsed = time.monotonic() - t_start
    assert sim.error is None and sim.bad_commands == 0
    assert len(records) == len(sim.pings) == 3 * n_cycles
    # No hang: every ping ends within its timeout; here well within (acoustic delays x 0.05).
    assert elapsed < 3 * n_cycles * 0.2
    by_outcome: dict[str, list[float]] = {"ok": [], "multipath": []}
    for rec, ping in zip(records, sim.pings, strict=True):
        assert rec.beacon == ping.beacon
        if ping.outcome == "dropout":
            assert rec.status == "timeout" and rec.range_m is None
            assert (
                f"beacon {rec.beacon}: no acoustic reply" in rec.message
                and "XCVR_RESP_TIMEOUT" in rec.message
            )
            continue
        assert rec.status == "ok"
        # The client's range is the simulator's to RANGE_TIME's resolution (1500 m/s * 100 ns = 0.15 mm).
        assert abs(rec.range_m - ping.reported_range_m) <= 1e-3
        by_outcome[ping.outcome].append(rec.range_m - ping.true_range_m)
        assert rec.azimuth_deg is not None and 0.0 <= rec.azimuth_deg < 360.0
        assert -90.0 <= rec.elevation_deg < 0.0  # transponders below the head
    assert all(r.status == "timeout" for r in records[2::3])  # beacon 3 has no transponder
    assert sim.pings[2].to_record() == {
        "t_mono_s": sim.pings[2].t_mono_s,
        "beacon": 3,
        "outcome": "dropout",
        "true_range_m": None,
        "reported_range_m": None,
    }
    errors = np.asarray(by_outcome["ok"])
    n = errors.size
    assert n >= 60
    # Gaussian noise: mean within 4 standard errors (4 * 0.1 / sqrt(n) ~ 0.05 m), sd within 30 % of sigma
    # (the sample sd of n >= 60 normals has a relative standard error ~ 1/sqrt(2n) < 0.1).
    assert abs(errors.mean()) < 4 * SIGMA_M / math.sqrt(n)
    assert 0.7 * SIGMA_M < errors.std(ddof=1) < 1.3 * SIGMA_M
    # Multipath replies are longer by 2 to 6 m (plus the noise).
    assert all(2.0 - 5 * SIGMA_M < e < 6.0 + 5 * SIGMA_M for e in by_outcome["multipath"])
    n_drop = sum(p.outcome == "dropout" for p in sim.pings[0::3] + sim.pings[1::3])
    # 80 pings to real transponders at p = 0.1: 8 expected, sd 2.7; 0 or over 20 would be a bug.
    assert 1 <= n_drop <= 20


def test_usbl_angles_follow_the_geometry():
    cfg = BeaconSimConfig(
        transponders_enu_m={4: (100.0, 0.0, -100.0)},
        sigma_range_m=0.0,
        p_dropout=0.0,
        p_multipath=0.0,
        time_scale=0.02,
    )
    with (
        SeatracBeaconSimulator(cfg, lambda t: np.zeros(3), np.random.default_rng(1)) as sim,
        SeatracPinger(sim.port, beacons=[4], timeout_s=1.0) as pinger,
    ):
        rec = pinger.ping(4)
        again = pinger.ping(4)  # a second ping on the same port
    assert rec.status == "ok" and again.status == "ok"
    assert rec.range_m == pytest.approx(math.sqrt(2) * 100.0, abs=1e-3)
    assert rec.azimuth_deg == pytest.approx(90.0, abs=0.05)  # due east
    assert rec.elevation_deg == pytest.approx(-45.0, abs=0.05)
    assert rec.travel_time_s == pytest.approx(math.sqrt(2) * 100.0 / 1500.0, abs=1e-7)


def test_range_only_pings_have_no_angles_and_the_sound_speed_is_the_callers():
    cfg = BeaconSimConfig(
        transponders_enu_m={1: (0.0, 0.0, -150.0)},
        sigma_range_m=0.0,
        p_dropout=0.0,
        p_multipath=0.0,
        time_scale=0.02,
        sound_speed_mps=1500.0,
    )
    with (
        SeatracBeaconSimulator(cfg, lambda t: np.zeros(3), np.random.default_rng(1)) as sim,
        SeatracPinger(
            sim.port, beacons=[1], msg_type=MsgType.MSG_REQ, sound_speed_mps=1480.0, timeout_s=1.0
        ) as pinger,
    ):
        rec = pinger.ping(1)
    assert rec.azimuth_deg is None and rec.elevation_deg is None
    assert rec.range_m == pytest.approx(1480.0 * 0.1, abs=1e-4)  # 150 m at 1500 m/s is 0.1 s one way


def test_a_silent_port_times_out_within_the_timeout():
    master, slave = os.openpty()
    tty.setraw(slave)
    try:
        with SeatracPinger(os.ttyname(slave), beacons=[1], timeout_s=0.3) as pinger:
            t0 = time.monotonic()
            rec = pinger.ping(1)
            waited = time.monotonic() - t0
    finally:
        os.close(master)
        os.close(slave)
    assert rec.status == "no response" and rec.range_m is None
    assert "nothing within 0.3 s (not even the send status)" in rec.message
    assert 0.3 <= waited < 0.6


def _scripted_beacon(lines_after_command: list[bytes]):
    """A pty whose far end answers the first command with ``lines_after_command``."""
    master, slave = os.openpty()
    tty.setraw(slave)
    got: list[bytes] = []

    def answer():
        buf = b""
        while b"\n" not in buf:
            buf += os.read(master, 256)
        got.append(buf)
        for line in lines_after_command:
            os.write(master, line)

    thread = threading.Thread(target=answer, daemon=True)
    thread.start()
    return master, slave, thread, got


def test_bad_frames_are_recorded_and_skipped_and_busy_is_reported():
    fix = AcoFix(
        dest_id=15,
        src_id=2,
        flags=RANGE_VALID,
        msg_type=MsgType.MSG_RESP,
        yaw_deg=0.0,
        pitch_deg=0.0,
        roll_deg=0.0,
        depth_local_m=0.0,
        vos_mps=1500.0,
        rssi_db=-50.0,
        range=AcoRange(count=0, time_s=0.01, dist_m=15.0),
    )
    corrupt = bytearray(encode_ping_resp(fix))
    corrupt[5] = ord("F") if corrupt[5] != ord("F") else ord("E")
    master, slave, thread, got = _scripted_beacon(
        [
            b"garbage\r\n",
            bytes(corrupt),
            encode_ping_send_status(Cst.OK, 2),
            encode_ping_error(Cst.XCVR_RESP_TIMEOUT, 1),
            encode_ping_resp(fix),
        ]
    )
    port = os.ttyname(slave)
    try:
        with SeatracPinger(port, beacons=[2], timeout_s=1.0) as pinger:
            rec = pinger.ping(2)
            qc = pinger.qc
    finally:
        thread.join(2)
        os.close(master)
        os.close(slave)
    assert got[0] == encode_ping_send(2)
    assert decode_frame(got[0], sync="#").payload == bytes([2, MsgType.MSG_REQU])
    assert rec.status == "ok" and rec.range_m == pytest.approx(
        15.0, abs=1e-6
    )  # the other beacon's error ignored
    assert [(i.line, i.reason) for i in qc.issues] == [(1, "bad frame"), (2, "bad frame")]
    assert "does not start with '$'" in qc.issues[0].detail and "bad checksum" in qc.issues[1].detail
    assert qc.issues[0].file == port

    master, slave, thread, _ = _scripted_beacon([encode_ping_send_status(Cst.XCVR_BUSY, 2)])
    try:
        with SeatracPinger(os.ttyname(slave), beacons=[2], timeout_s=1.0) as pinger:
            busy = pinger.ping(2)
    finally:
        thread.join(2)
        os.close(master)
        os.close(slave)
    assert busy.status == "xcvr_busy" and "ping not sent (XCVR_BUSY)" in busy.message


def test_simulator_stops_cleanly_and_the_pinger_reports_a_closed_port():
    cfg = BeaconSimConfig(transponders_enu_m=TRANSPONDERS, time_scale=0.02)
    sim = SeatracBeaconSimulator(cfg, lambda t: np.zeros(3), np.random.default_rng(0))
    sim.start()
    thread = sim._thread
    sim.stop()
    assert thread is not None and not thread.is_alive() and sim.error is None
    with pytest.raises(DataError, match="cannot open the serial port"):
        SeatracPinger("/dev/oceanloc-no-such-port", beacons=[1])
    with pytest.raises(ConfigError, match="1 to 15"):
        SeatracPinger("/dev/null", beacons=[16])
    with pytest.raises(ConfigError, match="transponder id 0"):
        BeaconSimConfig(transponders_enu_m={0: (0.0, 0.0, 0.0)})


def test_a_response_before_the_send_status_is_a_late_answer_and_is_ignored():
    """After a restart (or a ping that timed out), the head may still deliver the answer to an earlier ping
    of the same beacon: it comes before this ping's send status, and its range belongs to another time."""

    def fix(dist_m: float) -> AcoFix:
        return AcoFix(
            dest_id=15, src_id=2, flags=RANGE_VALID, msg_type=MsgType.MSG_RESP, yaw_deg=0.0, pitch_deg=0.0,
            roll_deg=0.0, depth_local_m=0.0, vos_mps=1500.0, rssi_db=-50.0,
            range=AcoRange(count=0, time_s=dist_m / 1500.0, dist_m=dist_m),
        )  # fmt: skip

    master, slave, thread, _ = _scripted_beacon(
        [encode_ping_resp(fix(99.0)), encode_ping_send_status(Cst.OK, 2), encode_ping_resp(fix(15.0))]
    )
    try:
        with SeatracPinger(os.ttyname(slave), beacons=[2], timeout_s=1.0) as pinger:
            rec = pinger.ping(2)
    finally:
        thread.join(2)
        os.close(master)
        os.close(slave)
    assert rec.status == "ok" and rec.range_m == pytest.approx(15.0, abs=1e-6)
