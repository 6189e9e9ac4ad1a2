"""SeaTrac framing, CRC16 and PING messages: the guide's vectors, round trips, bad frames."""

import contextlib
from dataclasses import replace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from oceanloc.errors import ConfigError, DataError
from oceanloc.io.seatrac import (
    POSITION_ENHANCED,
    POSITION_VALID,
    RANGE_VALID,
    USBL_VALID,
    AcoFix,
    AcoPosition,
    AcoRange,
    AcoUsbl,
    Cid,
    Cst,
    MsgType,
    OtherMessage,
    PingError,
    PingSendStatus,
    SeatracDecodeError,
    crc16,
    decode_frame,
    decode_message,
    decode_ping_send,
    encode_frame,
    encode_ping_error,
    encode_ping_resp,
    encode_ping_send,
    encode_ping_send_status,
    range_from_fix,
)

# The Developer Guide's own example (section 4.3): the CID_SYS_INFO command and the beacon's answer.
GUIDE_COMMAND = "#0281C1"
GUIDE_RESPONSE = "$0234000000011B0301690E000000000000FF900301006901B7FAC5BFFF910301007A07750463A973BA"


def test_crc_known_vectors():
    assert crc16(b"") == 0
    assert crc16(b"\x02") == 0xC181  # the guide's "#0281C1"
    assert crc16(b"123456789") == 0xBB3D  # CRC-16/ARC catalogue check value
    body = bytes.fromhex(GUIDE_RESPONSE[1:-4])
    assert crc16(body) == 0xBA73  # the guide's response ends "73BA" (little-endian)


def test_guide_frames_encode_and_decode():
    assert encode_frame(Cid.SYS_INFO) == (GUIDE_COMMAND + "\r\n").encode()
    frame = decode_frame(GUIDE_RESPONSE + "\r\n")
    assert (frame.sync, frame.cid, len(frame.payload)) == (
        "$",
        0x02,
        38,
    )  # 41 bytes with the CID and checksum, as the guide says
    assert int.from_bytes(frame.payload[:4], "little") == 52  # uptime, as the guide decodes it
    assert isinstance(decode_message(GUIDE_RESPONSE), OtherMessage)


def test_ping_send_frame():
    frame = encode_ping_send(3, MsgType.MSG_REQU)
    assert frame.startswith(b"#400304") and frame.endswith(b"\r\n") and len(frame) == 13
    cmd = decode_ping_send(decode_frame(frame, sync="#").payload)
    assert (cmd.beacon_id, cmd.msg_type) == (3, MsgType.MSG_REQU)
    with pytest.raises(ConfigError, match="1 to 15"):
        encode_ping_send(0)
    with pytest.raises(ConfigError, match="MSG_REQ"):
        encode_ping_send(1, MsgType.MSG_OWAY)


def _grid(lo: int, hi: int, scale: int) -> st.SearchStrategy[float]:
    """Values exactly on a field's grid (integer / scale), so a round trip is exact."""
    return st.integers(lo, hi).map(lambda k: k / scale)


I16 = (-32768, 32767)


@st.composite
def acofixes(draw) -> AcoFix:
    has_range, has_usbl, has_pos = draw(st.booleans()), draw(st.booleans()), draw(st.booleans())
    flags = (RANGE_VALID * has_range) | (USBL_VALID * has_usbl) | (POSITION_VALID * has_pos)
    flags |= draw(st.sampled_from([0, POSITION_ENHANCED]))
    rng = usbl = pos = None
    if has_range:
        rng = AcoRange(
            count=draw(st.integers(0, 2**32 - 1)),
            time_s=draw(st.integers(-(2**31), 2**31 - 1)) / 1e7,
            dist_m=draw(_grid(0, 65535, 10)),
        )
    if has_usbl:
        n = draw(st.integers(0, 4))
        usbl = AcoUsbl(
            rssi_db=tuple(draw(st.lists(_grid(*I16, 10), min_size=n, max_size=n))),
            azimuth_deg=draw(_grid(0, 3600, 10)),
            elevation_deg=draw(_grid(-900, 900, 10)),
            fit_error=draw(_grid(*I16, 100)),
        )
    if has_pos:
        pos = AcoPosition(
            easting_m=draw(_grid(*I16, 10)), northing_m=draw(_grid(*I16, 10)), depth_m=draw(_grid(*I16, 10))
        )
    return AcoFix(
        dest_id=draw(st.integers(0, 15)),
        src_id=draw(st.integers(1, 15)),
        flags=flags,
        msg_type=draw(st.sampled_from(list(MsgType))),
        yaw_deg=draw(_grid(-1800, 1800, 10)),
        pitch_deg=draw(_grid(-900, 900, 10)),
        roll_deg=draw(_grid(-1800, 1800, 10)),
        depth_local_m=draw(_grid(0, 65535, 10)),
        vos_mps=draw(_grid(0, 65535, 10)),
        rssi_db=draw(_grid(*I16, 10)),
        range=rng,
        usbl=usbl,
        position=pos,
    )


@given(acofixes())
def test_ping_resp_round_trip(fix: AcoFix):
    assert decode_message(encode_ping_resp(fix)) == fix


@given(st.sampled_from(list(Cst)), st.integers(1, 15))
def test_status_and_error_round_trip(status: Cst, beacon: int):
    assert decode_message(encode_ping_send_status(status, beacon)) == PingSendStatus(
        status=status, beacon_id=beacon
    )
    assert decode_message(encode_ping_error(status, beacon)) == PingError(status=status, beacon_id=beacon)


@given(acofixes(), st.data())
def test_truncated_frames_raise_the_decode_error(fix: AcoFix, data):
    frame = encode_ping_resp(fix).decode().rstrip()
    cut = data.draw(st.integers(0, len(frame) - 1))
    with pytest.raises(SeatracDecodeError):
        decode_message(frame[:cut])


@given(acofixes(), st.data())
def test_one_corrupted_character_is_always_caught(fix: AcoFix, data):
    frame = encode_ping_resp(fix).decode().rstrip()
    at = data.draw(st.integers(1, len(frame) - 1))
    new = data.draw(st.sampled_from("0123456789ABCDEFGZ #$-"))
    bad = frame[:at] + new + frame[at + 1 :]
    if bad == frame:
        return
    # CRC-16 detects every error burst up to 16 bits, so any changed hex digit fails the checksum.
    with pytest.raises(SeatracDecodeError):
        decode_message(bad)


@given(st.binary(max_size=80))
def test_arbitrary_bytes_raise_only_the_projects_errors(raw: bytes):
    with contextlib.suppress(DataError):
        decode_message(raw)
    with contextlib.suppress(DataError):
        decode_message(b"$" + raw.hex().encode())


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("", "empty frame"),
        ("#400104ABCD", "does not start with '\\$'"),
        ("$40G1", "non-hex character 'G' at column 4"),
        ("$401", "odd number of hex characters \\(3\\)"),
        ("$40", "too short: 1 bytes"),
        ("$4001000000", "bad checksum: frame says 0x0000, content gives 0x"),
        (b"$40\xff".decode("latin-1").encode("latin-1"), "non-ASCII byte at position 3"),
    ],
)
def test_decode_errors_name_what_is_wrong(line, message):
    with pytest.raises(SeatracDecodeError, match=message):
        decode_frame(line)


def test_short_payload_names_the_field():
    fix = AcoFix(
        dest_id=15,
        src_id=2,
        flags=RANGE_VALID,
        msg_type=MsgType.MSG_RESP,
        yaw_deg=0.0,
        pitch_deg=0.0,
        roll_deg=0.0,
        depth_local_m=0.5,
        vos_mps=1500.0,
        rssi_db=-60.0,
        range=AcoRange(count=1000, time_s=0.02, dist_m=30.0),
    )
    body = encode_ping_resp(fix).decode().rstrip()
    payload = bytes.fromhex(body[1:-4])[:-3]  # cut into the RANGE fields, then re-frame with a valid CRC
    with pytest.raises(SeatracDecodeError, match="CID_PING_RESP: payload too short at RANGE fields"):
        decode_message(encode_frame(payload[0], payload[1:], sync="$"))
    with pytest.raises(SeatracDecodeError, match="CID_PING_ERROR: 1 unexpected trailing bytes"):
        decode_message(encode_frame(Cid.PING_ERROR, b"\x34\x01\x00", sync="$"))
    with pytest.raises(ConfigError, match="disagree with the USBL fields"):
        replace(fix, flags=RANGE_VALID | USBL_VALID)


def test_range_is_sound_speed_times_one_way_time():
    fix = AcoFix(
        dest_id=15,
        src_id=1,
        flags=RANGE_VALID,
        msg_type=MsgType.MSG_RESP,
        yaw_deg=0.0,
        pitch_deg=0.0,
        roll_deg=0.0,
        depth_local_m=0.0,
        vos_mps=1450.0,
        rssi_db=0.0,
        range=AcoRange(count=0, time_s=0.0123456, dist_m=17.9),
    )
    back = decode_message(encode_ping_resp(fix))
    assert isinstance(back, AcoFix)
    # RANGE_TIME (100 ns) times the survey's sound speed, not RANGE_DIST (the beacon's VOS, 0.1 m).
    assert range_from_fix(back, 1500.0) == pytest.approx(1500.0 * 0.0123456, abs=1e-9)
    assert range_from_fix(replace(fix, flags=0, range=None), 1500.0) is None
