"""GNATSS's file formats: the documented examples parse to the documented values; writers and readers
round-trip; bad input is skipped with file:line and a reason, or refused with one clear line."""

from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.io.gnatss import (
    EpochResiduals,
    in_windows,
    j2000_from_datetime,
    join_pxp_positions,
    read_deletions,
    read_epoch_residuals,
    read_gnatss_config,
    read_gps_pos_freed,
    read_level2_csv,
    read_pos_freed_trans_twtt,
    read_pxp_tt,
    read_roll_pitch_heading,
    read_sound_speed_profile,
    write_epoch_residuals,
    write_level2_csv,
)
from oceanloc.sim.gnatss_survey import ArraySurveySpec, write_gnatss_survey

# the pxp_tt and POS_FREED_TRANS_TWTT excerpts of GNATSS's documentation ("Running GNATSS", v0.1)
PXP_DOC = """26-JUN-23 00:00:07.00   2241985   2337422   2469996
26-JUN-23 00:00:22.00   2240506   2346387   2463020
"""
POS_DOC = """\
   741009607.0000000  -2575338.456      -3682605.618       4511008.716      0.7592545444E-03  0.3218813907E-06  -.3030846830E-05  0.3218813907E-06  0.7594897193E-03  -.4333961609E-05  -.3030846830E-05  -.4333961609E-05  0.7598263681E-03
   741009609.2419850  -2575338.614      -3682604.946       4511008.820      0.2796384902E-03  0.1142867658E-06  -.8293527721E-06  0.1142867658E-06  0.2797219910E-03  -.1185933310E-05  -.8293527721E-06  -.1185933310E-05  0.2798324391E-03
   741009609.3374220  -2575338.610      -3682604.861       4511008.866      0.3749910877E-03  0.1630394849E-06  -.1153364964E-05  0.1630394849E-06  0.3751102085E-03  -.1649254651E-05  -.1153364964E-05  -.1649254651E-05  0.3752666760E-03
   741009609.4699960  -2575338.593      -3682604.744       4511008.958      0.5023142547E-03  0.2296528483E-06  -.1602120826E-05  0.2296528483E-06  0.5024820449E-03  -.2290953239E-05  -.1602120826E-05  -.2290953239E-05  0.5027016135E-03
"""  # noqa: E501


def _write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_documented_pxp_tt_and_positions_join_at_the_documented_epochs(tmp_path: Path):
    tt = read_pxp_tt(_write(tmp_path, "pxp_tt", PXP_DOC))
    # 26-JUN-23 00:00:07 is 741009607 J2000 seconds (the documentation's POS_FREED_TRANS_TWTT time)
    assert tt.t_transmit_s[0] == 741009607.0
    assert tt.twtt_s[0].tolist() == pytest.approx([2.241985, 2.337422, 2.469996], abs=1e-12)
    pos = read_pos_freed_trans_twtt(_write(tmp_path, "POS", POS_DOC))
    assert pos.cov_m2[0, 0, 0] == pytest.approx(0.7592545444e-03)
    assert pos.cov_m2[0, 0, 2] == pytest.approx(-0.3030846830e-05)  # Fortran "-.303E-05"
    pings = join_pxp_positions(tt, pos, ["A", "B", "C"])
    assert pings.n_replies == 3  # the second interrogation has no positions in the excerpt
    assert pings.receive_xyz_m[2].tolist() == [-2575338.593, -3682604.744, 4511008.958]
    assert "pxp_tt:2: invalid fix (no transducer position at the interrogation" in str(tt.qc.issues[0])


def test_j2000_origin():
    import datetime as dt

    assert j2000_from_datetime(dt.datetime(2000, 1, 1, 12)) == 0.0
    assert j2000_from_datetime(dt.datetime(2023, 6, 26, 0, 0, 7)) == 741009607.0


@pytest.fixture(scope="module")
def survey(tmp_path_factory: pytest.TempPathFactory):
    folder = tmp_path_factory.mktemp("syn")
    spec = ArraySurveySpec(n_pings=60, missing_fraction=0.1, seed=3)
    return write_gnatss_survey(spec, folder)


def test_writers_round_trip_through_every_reader(survey):
    truth, files = survey
    cfg = read_gnatss_config(files.config)
    assert cfg.ids == truth.ids
    assert cfg.inputs["gps_solution"] == str(files.level2_csv)
    l2 = read_level2_csv(files.level2_csv, cfg.ids)
    joined = join_pxp_positions(
        read_pxp_tt(files.pxp_tt, 3), read_pos_freed_trans_twtt(files.pos_freed_trans_twtt), cfg.ids
    )
    assert l2.n_replies == joined.n_replies == truth.pings.n_replies  # partial replies kept
    order = np.lexsort((joined.transponder, joined.t_transmit_s))
    order2 = np.lexsort((l2.transponder, l2.t_transmit_s))
    assert np.allclose(joined.receive_xyz_m[order], l2.receive_xyz_m[order2], atol=1e-4)
    assert np.allclose(joined.twtt_s[order], l2.twtt_s[order2], atol=1e-6)
    prof = read_sound_speed_profile(files.sound_speed)
    assert prof.harmonic_mean_mps(0.0, truth.spec.depths_m[0]) == pytest.approx(truth.sound_speed_mps[0])
    ant = read_gps_pos_freed(files.gps_pos_freed)
    att = read_roll_pitch_heading(files.roll_pitch_heading)
    assert ant.t_s.size == att.t_s.size == pos_epochs(files)


def pos_epochs(files) -> int:
    return read_pos_freed_trans_twtt(files.pos_freed_trans_twtt).t_s.size


def test_harmonic_mean_is_exact_for_a_linear_profile(tmp_path: Path):
    prof = read_sound_speed_profile(_write(tmp_path, "ssp", "depth,speed\n0 1500\n-1000 1520\n"))
    # 1000 m / int dz / (1500 + 0.02 z) = 1000 * 0.02 / ln(1520 / 1500)
    assert prof.harmonic_mean_mps(0.0, 1000.0) == pytest.approx(20.0 / np.log(1520.0 / 1500.0), rel=1e-12)


@pytest.mark.parametrize(
    ("text", "where"),
    [
        (
            "26-JUN-23 00:00:07.00 2241985 2337422 2469996\n26-JUN-23 00:00:22.00 22405x6 2346387 2463020\n",
            ":2: non-numeric field (field 3",
        ),
        (
            "26-JUN-23 00:00:07.00 2241985 2337422 2469996\n26-JUN-23 00:00:22.00 2240506 2346387\n",
            ":2: truncated sentence",
        ),
        (
            "26-JUN-23 00:00:07.00 2241985 2337422 2469996\n26-JUN-23 00:00:02.00 2240506 2346387 2463020\n",
            ":2: time going backwards",
        ),
        (
            "26-JUN-23 00:00:07.00 2241985 2337422 2469996\n26-JUN-23 00:00:22.00 -1 2346387 2463020\n",
            ":2: negative or absurd range",
        ),
        (
            "26-JUN-23 00:00:07.00 2241985 2337422 2469996\n32-JUN-23 00:00:22.00 2240506 2346387 2463020\n",
            ":2: non-numeric field (date-time",
        ),
    ],
)
def test_pxp_tt_bad_lines_are_named_and_skipped(tmp_path: Path, text: str, where: str):
    tt = read_pxp_tt(_write(tmp_path, "pxp_tt", text))
    assert tt.t_transmit_s.size == 1
    assert where in str(tt.qc.issues[0])


def test_pxp_tt_in_seconds_is_refused(tmp_path: Path):
    with pytest.raises(DataError, match="not microseconds"):
        read_pxp_tt(_write(tmp_path, "pxp_tt", "741009607.0 2.241985 2.337422\n741009622.0 2.24 2.33\n"))


def test_positions_not_in_metres_are_named(tmp_path: Path):
    km = POS_DOC.replace(
        "-2575338.456      -3682605.618       4511008.716", "-2575.338456 -3682.605618 4511.008716"
    )
    pos = read_pos_freed_trans_twtt(_write(tmp_path, "POS", km))
    assert pos.t_s.size == 3
    assert "POS:1: out of range (|XYZ| 6367.4 m is not an Earth-fixed surface position (metres))" in str(
        pos.qc.issues[0]
    )


def test_bad_covariance_and_field_count(tmp_path: Path):
    lines = POS_DOC.splitlines()
    asym = lines[1].replace("0.1142867658E-06  0.2797219910E-03", "0.9142867658E-06  0.2797219910E-03")
    text = "\n".join([lines[0], asym, lines[2] + " 7", lines[3]]) + "\n"
    pos = read_pos_freed_trans_twtt(_write(tmp_path, "POS", text))
    assert [str(i).split(": ", 1)[1] for i in pos.qc.issues] == [
        "non-numeric field (covariance is not symmetric)",
        "wrong field count (14 fields, expected 13 (time, X, Y, Z, 9 covariance))",
    ]


def test_sound_speed_in_feet_per_second_is_refused(tmp_path: Path):
    with pytest.raises(DataError, match="ssp: 3 of 3 sound speeds are outside 1300-1700 m/s"):
        read_sound_speed_profile(_write(tmp_path, "ssp", "-1 4921\n-2 4920\n-3 4919\n"))
    with pytest.raises(DataError, match="at least two depths, got 1"):
        read_sound_speed_profile(_write(tmp_path, "ssp", "-1 1500\n"))


def test_level2_missing_column_and_bad_rows(tmp_path: Path, survey):
    _, files = survey
    header, *rows = files.level2_csv.read_text().splitlines()
    with pytest.raises(DataError, match=r"l2.csv:1: Level-2 CSV header lacks column\(s\) TravelTime"):
        read_level2_csv(
            _write(tmp_path, "l2.csv", header.replace("TravelTime", "TT") + "\n" + rows[0] + "\n")
        )
    cells = rows[1].split(",")
    cells[2] = str(float(cells[2]) + 0.5)  # TravelTime no longer T_receive - T_transmit
    other = rows[2].split(",")
    other[1] = "X-9"
    bad = _write(
        tmp_path,
        "l2b.csv",
        "\n".join([header, rows[0], ",".join(cells), ",".join(other)]) + "\n",
    )
    pings = read_level2_csv(bad, ("SYN1-1", "SYN1-2", "SYN1-3"))
    msgs = [str(i) for i in pings.qc.issues]
    assert pings.n_replies == 1
    assert "l2b.csv:3: out of range (T_receive - T_transmit" in msgs[0]
    assert "l2b.csv:4: unknown beacon id (MT_ID 'X-9'" in msgs[1]


def test_deletions_both_layouts_and_windows(tmp_path: Path):
    legacy = read_deletions(
        _write(tmp_path, "deletns.dat", "26-JUN-23 00:00:00 26-JUN-23 00:01:00 manual cut\n")
    )
    assert legacy.tolist() == [[741009600.0, 741009660.0]]
    csv = read_deletions(_write(tmp_path, "deletions.csv", "starttime,endtime\n741009600.0,741009600.0\n"))
    assert in_windows(np.array([741009600.0, 741009601.0]), csv).tolist() == [True, False]
    qc = read_deletions(
        _write(
            tmp_path,
            "qc.csv",
            "starttime,endtime,notes\n2023-06-26T00:00:00,2023-06-26 00:00:30,bad, noisy\n",
        )
    )
    assert qc.tolist() == [[741009600.0, 741009630.0]]
    with pytest.raises(DataError, match=r"d.dat:1: time going backwards \(deletion ends before it starts\)"):
        read_deletions(_write(tmp_path, "d.dat", "26-JUN-23 00:01:00 26-JUN-23 00:00:00\n"))


def test_epoch_residuals_round_trip(tmp_path: Path):
    r = EpochResiduals(t_s=np.array([741009600.0]), ids=("A", "B"), residual_cm=np.array([[1.5, -2.25]]))
    back = read_epoch_residuals(write_epoch_residuals(tmp_path / "residuals.csv", r))
    assert back.ids == ("A", "B")
    assert back.residual_cm.tolist() == [[1.5, -2.25]]
    assert (
        (tmp_path / "residuals.csv")
        .read_text()
        .splitlines()[1]
        .startswith("741009600.000000,2023-06-26T00:00:00")
    )


def test_config_errors_name_the_entry(tmp_path: Path):
    p = _write(
        tmp_path,
        "c.yaml",
        "site_id: X\narray_center: {lat: 45, lon: -125}\n"
        "transponders:\n  - {lat: 45, lon: -125, height: -1000}\n",
    )
    with pytest.raises(DataError, match=r"c.yaml: transponders\[0\].internal_delay is missing"):
        read_gnatss_config(p)
    with pytest.raises(DataError, match=r"c2\.yaml: not a readable YAML file"):
        read_gnatss_config(_write(tmp_path, "c2.yaml", "site_id: [unclosed\n"))


def test_level2_writer_sorts_by_receive_time(tmp_path: Path, survey):
    truth, _ = survey
    back = read_level2_csv(write_level2_csv(tmp_path / "l2.csv", truth.pings))
    assert np.all(np.diff(back.t_receive_s) >= 0.0)


# the Level-2 header and row of GNATSS's documentation ("L-2 Data")
L2_DOC = (
    "T_receive,MT_ID,TravelTime,T_transmit,ant_cov_XX1,ant_cov_XY1,ant_cov_XZ1,ant_cov_YX1,ant_cov_YY1,"
    "ant_cov_YZ1,ant_cov_ZX1,ant_cov_ZY1,ant_cov_ZZ1,X_receive,Y_receive,Z_receive,ant_cov_XX0,ant_cov_XY0,"
    "ant_cov_XZ0,ant_cov_YX0,ant_cov_YY0,ant_cov_YZ0,ant_cov_ZX0,ant_cov_ZY0,ant_cov_ZZ0,X_transmit,Y_transmit,"
    "Z_transmit\n"
    "712483771.569176,NDP1-2,3.569176,712483768.0,0.0002271,9.8e-07,-2.2e-07,9.8e-07,0.0002278,-3.1e-07,"
    "-2.2e-07,-3.1e-07,0.00022849,-2606685.75482955,-3705817.00172181,4474091.26651063,7.841e-05,1.1e-07,"
    "-4e-08,1.1e-07,7.849e-05,-6e-08,-4e-08,-6e-08,7.857e-05,-2606687.12007168,-3705817.05582391,"
    "4474089.56415817\n"
)


def test_documented_level2_row(tmp_path: Path):
    from oceanloc.io.gnatss import LEVEL2_COLUMNS

    assert ",".join(LEVEL2_COLUMNS) == L2_DOC.splitlines()[0]  # the column order GNATSS writes
    pings = read_level2_csv(_write(tmp_path, "gps_solution.csv", L2_DOC))
    assert pings.ids == ("NDP1-2",)
    assert pings.twtt_s[0] == pytest.approx(3.569176)
    assert pings.transmit_cov_m2[0, 2, 2] == pytest.approx(7.857e-05)
    assert pings.receive_xyz_m[0, 2] == pytest.approx(4474091.26651063)
