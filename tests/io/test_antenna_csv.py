"""The antenna CSV (time, geodetic or ECEF position, sd or full covariance, roll/pitch/heading): pymap3d is
the oracle of the conversions, every form round-trips, and every bad row or file is named with its line
or column."""

import datetime as dt
from pathlib import Path

import numpy as np
import pymap3d
import pytest

from oceanloc.errors import DataError
from oceanloc.field.gnatss_input import antenna_pings, gnatss_example_config
from oceanloc.io.antenna_csv import (
    POSITION_FORMS,
    TIME_FORMS,
    gps_to_unix_s,
    is_antenna_csv,
    read_antenna_csv,
    unix_to_gps_s,
    write_antenna_csv,
)
from oceanloc.io.gnatss import read_gnatss_config, read_gps_pos_freed, read_pxp_tt, read_roll_pitch_heading

EXAMPLE = gnatss_example_config().parent
HEADER = "time_utc,lat_deg,lon_deg,height_m,sd_e_m,sd_n_m,sd_u_m,roll_deg,pitch_deg,heading_deg\n"


def _row(t: str = "2023-06-26T00:00:00Z", lat="45.3", lon="-124.97", h="-26.3", sd=("0.02", "0.02", "0.04"),
         rph=("1.0", "2.0", "90.0")) -> str:  # fmt: skip
    return ",".join([t, lat, lon, h, *sd, *rph]) + "\n"


def _track() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A small track with full, correlated ECEF covariances (random SPD, fixed seed)."""
    rng = np.random.default_rng(7)
    k = 40
    t = 741_009_600.0 + np.cumsum(rng.uniform(0.5, 3.0, k))
    lat = 45.3 + 1e-4 * rng.standard_normal(k)
    lon = -124.97 + 1e-4 * rng.standard_normal(k)
    h = -26.0 + 0.3 * rng.standard_normal(k)
    xyz = np.stack(pymap3d.geodetic2ecef(lat, lon, h), axis=-1)
    a = 0.02 * rng.standard_normal((k, 3, 3))
    cov = a @ np.swapaxes(a, 1, 2) + 1e-5 * np.eye(3)
    rph = np.column_stack([rng.uniform(-10, 10, k), rng.uniform(-5, 5, k), rng.uniform(0, 360, k)])
    return t, xyz, cov, rph


def test_geodetic_position_and_enu_covariance_match_pymap3d(tmp_path: Path):
    """The oracle: ECEF of each row's latitude, longitude, height by pymap3d.geodetic2ecef, and the ENU
    covariance taken to ECEF by the Jacobian of pymap3d.enu2ecef about that row's point (central
    differences of 100 m steps: the map is affine, so only rounding of the 6e6 m coordinates, ~1e-11,
    remains)."""
    lat, lon, h = (
        np.array([45.3, -33.9, 89.5]),
        np.array([-124.97, 151.2, 10.0]),
        np.array([-26.3, 40.0, 5.0]),
    )
    c_enu = np.array([[4e-4, 1e-4, -5e-5], [1e-4, 9e-4, 2e-5], [-5e-5, 2e-5, 1.6e-3]])
    p = tmp_path / "a.csv"
    cols = "t_j2000_s,lat_deg,lon_deg,height_m,cov_ee_m2,cov_en_m2,cov_eu_m2,cov_nn_m2,cov_nu_m2,cov_uu_m2"
    tri = [c_enu[i, j] for i, j in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))]
    rows = [",".join(repr(float(v)) for v in [k, lat[k], lon[k], h[k], *tri]) for k in range(3)]
    p.write_text(cols + "\n" + "\n".join(rows) + "\n")
    a = read_antenna_csv(p)
    assert a.rph_deg is None and a.forms == ("j2000", "geodetic", "cov_enu")
    want = np.stack(pymap3d.geodetic2ecef(lat, lon, h), axis=-1)
    assert np.max(np.abs(a.xyz_m - want)) < 1e-9
    step = 100.0
    for k in range(3):
        jac = np.empty((3, 3))
        for i in range(3):
            d = np.zeros(3)
            d[i] = step
            plus = np.array(pymap3d.enu2ecef(*d, lat[k], lon[k], h[k]))
            minus = np.array(pymap3d.enu2ecef(*(-d), lat[k], lon[k], h[k]))
            jac[:, i] = (plus - minus) / (2 * step)
        assert np.allclose(a.cov_xyz_m2[k], jac @ c_enu @ jac.T, rtol=0, atol=1e-12)


@pytest.mark.parametrize("time", TIME_FORMS)
@pytest.mark.parametrize("position", POSITION_FORMS)
@pytest.mark.parametrize("covariance", ["cov_xyz", "cov_enu"])
def test_every_form_round_trips(tmp_path: Path, time: str, position: str, covariance: str):
    """Times to 0.3 us (a float's resolution at Unix 1.7e9 s is 0.24 us; ISO 8601 carries microseconds:
    0.5 us + that), positions to 0.2 um (latitude
    and longitude written to 1e-12 deg = 0.11 um), covariances to 1e-10 relative (12 digits)."""
    t, xyz, cov, rph = _track()
    p = write_antenna_csv(tmp_path / "a.csv", t, xyz, cov, rph, time=time, position=position,
                          covariance=covariance)  # fmt: skip
    assert is_antenna_csv(p)
    a = read_antenna_csv(p)
    assert a.forms == (time, position, covariance)
    assert np.max(np.abs(a.t_s - t)) < (8e-7 if time == "iso" else 3e-7)
    assert np.max(np.abs(a.xyz_m - xyz)) < 2e-7
    assert np.allclose(a.cov_xyz_m2, cov, rtol=1e-10, atol=1e-16)
    assert np.allclose(a.rph_deg, rph, rtol=1e-11, atol=1e-10)
    assert a.qc.records_kept == t.size and not a.qc.issues


def test_enu_sd_equals_the_diagonal_full_enu_covariance(tmp_path: Path):
    sd = ("0.021", "0.017", "0.043")
    (tmp_path / "sd.csv").write_text(
        HEADER + _row(sd=sd) + _row(t="2023-06-26T00:00:01Z", lat="45.31", sd=sd)
    )
    cov_cols = "cov_ee_m2,cov_en_m2,cov_eu_m2,cov_nn_m2,cov_nu_m2,cov_uu_m2"
    full = [f"{v:.12g}" for v in (0.021**2, 0.0, 0.0, 0.017**2, 0.0, 0.043**2)]
    rows = [
        ",".join([t, lat, "-124.97", "-26.3", *full, "1.0", "2.0", "90.0"])
        for t, lat in (("2023-06-26T00:00:00Z", "45.3"), ("2023-06-26T00:00:01Z", "45.31"))
    ]
    (tmp_path / "cov.csv").write_text(
        HEADER.replace("sd_e_m,sd_n_m,sd_u_m", cov_cols) + "\n".join(rows) + "\n"
    )
    a, b = read_antenna_csv(tmp_path / "sd.csv"), read_antenna_csv(tmp_path / "cov.csv")
    assert a.forms[2] == "sd_enu" and b.forms[2] == "cov_enu"
    assert np.allclose(a.cov_xyz_m2, b.cov_xyz_m2, rtol=1e-12, atol=1e-18)
    # a rotation of the diagonal ENU matrix: the trace is kept, and it is not diagonal in ECEF
    assert np.allclose(np.trace(a.cov_xyz_m2, axis1=1, axis2=2), 0.021**2 + 0.017**2 + 0.043**2)
    assert abs(a.cov_xyz_m2[0, 0, 2]) > 1e-4


def test_aliases_case_and_time_scales(tmp_path: Path):
    """Aliases and upper case are accepted; an ISO offset is honoured; GPS time is UTC + 18 s in 2023 and
    + 17 s in 2016 (the leap seconds of IERS Bulletin C)."""
    p = tmp_path / "a.csv"
    p.write_text(
        "# a comment\n Time , Latitude,LON,h_m,Sigma_E,sigma_n,std_u,Roll,PITCH,yaw\n"
        "2023-06-26T02:00:00+02:00,45.3,-124.97,-26.3,0.02,0.02,0.04,1,2,359\n"
        "2023-06-26T00:00:01.5,45.3,-124.97,-26.3,0.02,0.02,0.04,1,2,1\n"
    )
    a = read_antenna_csv(p)
    j2000 = dt.datetime(2000, 1, 1, 12)
    assert a.t_s[0] == (dt.datetime(2023, 6, 26) - j2000).total_seconds()
    assert a.t_s[1] - a.t_s[0] == 1.5
    assert a.forms == ("iso", "geodetic", "sd_enu")
    u = dt.datetime(2023, 6, 26, tzinfo=dt.UTC).timestamp()
    days = (dt.date(2023, 6, 26) - dt.date(1980, 1, 6)).days
    assert unix_to_gps_s(u) == days * 86400 + 18
    assert gps_to_unix_s(days * 86400 + 18) == u
    u16 = dt.datetime(2016, 6, 1, tzinfo=dt.UTC).timestamp()
    assert unix_to_gps_s(u16) - (u16 - dt.datetime(1980, 1, 6, tzinfo=dt.UTC).timestamp()) == 17
    q = tmp_path / "gps.csv"
    q.write_text(
        f"t_gps_s,x,y,z,sd_x,sd_y,sd_z\n{days * 86400 + 18},-2575338.4,-3682605.6,4511008.7,0.02,0.02,0.02\n"
    )
    assert read_antenna_csv(q).t_s[0] == a.t_s[0]
    assert not is_antenna_csv(EXAMPLE / "GPS_POS_FREED") and not is_antenna_csv(EXAMPLE / "RPH")
    assert is_antenna_csv(EXAMPLE / "antenna.csv")


def test_bad_rows_are_skipped_with_file_line_and_reason(tmp_path: Path):
    p = tmp_path / "bad.csv"
    rows = [
        _row(t="2023-06-26T00:00:00Z"),  # 2: good
        _row(t="2023-06-26T00:00:01Z")[:-10] + "\n",  # 3: truncated
        _row(t="2023-06-26T00:00:02Z", lat="abc"),  # 4
        _row(t="26/06/2023 00:00:03"),  # 5: not ISO
        _row(t="2023-06-26T00:00:04Z", h="nan"),  # 6
        _row(t="2023-06-26T00:00:05Z", lat="91"),  # 7
        _row(t="2023-06-26T00:00:06Z", lon="400"),  # 8
        _row(t="2023-06-26T00:00:07Z", h="20000"),  # 9
        _row(t="2023-06-26T00:00:08Z", sd=("0.02", "0", "0.04")),  # 10
        _row(t="2023-06-26T00:00:09Z", rph=("95", "0", "0")),  # 11
        _row(t="2023-06-26T00:00:10Z", rph=("0", "0", "400")),  # 12
        _row(t="2023-06-26T00:00:11Z"),  # 13: good
        _row(t="2023-06-26T00:00:11Z"),  # 14: same time
        _row(t="2023-06-26T00:00:12Z"),  # 15: good
    ]
    p.write_text(HEADER + "".join(rows))
    a = read_antenna_csv(p)
    assert a.qc.records_kept == 3 and a.line.tolist() == [2, 13, 15]
    got = {i.line: str(i) for i in a.qc.issues}
    assert got[3].startswith(f"{p}:3: truncated sentence (8 fields, expected 10")
    assert "lat_deg: 'abc'" in got[4] and "non-numeric field" in got[4]
    assert "time_utc: '26/06/2023 00:00:03' is not an ISO 8601 time" in got[5]
    assert "NaN or infinite value" in got[6]
    assert "latitude 91 deg is outside [-90, 90] deg" in got[7]
    assert "longitude 400 deg is outside [-180, 360] deg" in got[8]
    assert "height 20000 m is outside [-1000, 10000] m" in got[9]
    assert "standard deviations [0.02, 0.0, 0.04] m not in (0, 10] m" in got[10]
    assert "roll 95" in got[11] and "(allowed [-90, 90])" in got[11]
    assert "heading 400 deg" in got[12]
    assert got[14].startswith(f"{p}:14: time going backwards")
    assert sorted(got) == [3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 14]


def test_bad_covariances_and_ecef_positions(tmp_path: Path):
    p = tmp_path / "cov.csv"
    head = "t_j2000_s,x_m,y_m,z_m,cov_xx_m2,cov_xy_m2,cov_xz_m2,cov_yy_m2,cov_yz_m2,cov_zz_m2\n"
    xyz = "-2575338.4,-3682605.6,4511008.7"
    p.write_text(
        head
        + f"1,{xyz},4e-4,0,0,4e-4,0,4e-4\n"
        + f"2,{xyz},4e-4,5e-4,0,4e-4,0,4e-4\n"  # correlation 1.25: not positive definite
        + f"3,{xyz},400,0,0,4e-4,0,4e-4\n"  # variance in cm^2?
        + "4,1000,2000,3000,4e-4,0,0,4e-4,0,4e-4\n"  # km, not m
        + f"5,{xyz},4e-4,4e-4,0,4e-4,0,4e-4\n"  # singular (correlation exactly 1)
    )
    a = read_antenna_csv(p)
    assert a.qc.records_kept == 1
    got = {i.line: str(i) for i in a.qc.issues}
    assert "covariance is not positive definite (smallest eigenvalue -0.0001 m^2)" in got[3]
    assert "variance 400 m^2 > 100 m^2" in got[4]
    assert "|XYZ| 3741.7 m is not an Earth-fixed surface position (metres)" in got[5]
    assert "not positive definite" in got[6]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("lat_deg,lon_deg,height_m,sd_e_m,sd_n_m,sd_u_m\n45,-124,0,1,1,1\n",
         "no time column (accepted: time_utc | t_j2000_s | t_unix_s | t_gps_s; aliases e.g. time, utc"),
        ("time_utc,lat_deg,height_m,sd_e_m,sd_n_m,sd_u_m\n2023-06-26T00:00:00Z,45,0,1,1,1\n",
         "antenna position column 'lon_deg' missing (accepted names: lon_deg, lon, longitude"),
        ("time_utc,lat_deg,lon_deg,height_m\n2023-06-26T00:00:00Z,45,-124,0\n",
         "no position covariance column (accepted: sd_e_m, sd_n_m, sd_u_m | sd_x_m, sd_y_m, sd_z_m | "
         "cov_ee_m2"),
        ("time_utc,lat_deg,lon_deg,height_m,sd_e_m,sd_n_m,sd_u_m,sd_x_m,sd_y_m,sd_z_m\n",
         "position covariance is given twice (sd_enu and sd_xyz columns): keep one"),
        ("time_utc,lat_deg,lon_deg,height_m,sd_e_m,sd_n_m,sd_u_m,roll_deg,pitch_deg\n",
         "attitude column 'heading_deg' missing (accepted names: heading_deg, heading, yaw_deg"),
        ("time,utc,lat_deg,lon_deg,height_m,sd_e_m,sd_n_m,sd_u_m\n",
         "columns 'time' and 'utc' are both time_utc"),
        ("time_utc,lat_deg,lon_deg,height_m,sd_e_m,sd_n_m,sd_u_m\n2023-06-26T00:00:00Z,99,-124,0,1,1,1\n",
         "no valid antenna position (" + "{p}:2: out of range (latitude 99 deg"),
        ("", "no header line"),
    ],
)  # fmt: skip
def test_bad_files_raise_one_line_naming_file_and_column(tmp_path: Path, text: str, message: str):
    p = tmp_path / "a.csv"
    p.write_text(text)
    with pytest.raises(DataError) as err:
        read_antenna_csv(p)
    assert str(err.value).startswith(str(p))
    assert message.format(p=p) in str(err.value)
    assert "\n" not in str(err.value)


def test_radian_headings_are_refused(tmp_path: Path):
    rows = "".join(_row(t=f"2023-06-26T00:00:{k:02d}Z", rph=("0.01", "0.02", "1.5")) for k in range(12))
    (tmp_path / "rad.csv").write_text(HEADER + rows)
    with pytest.raises(DataError, match="angles look like radians"):
        read_antenna_csv(tmp_path / "rad.csv")


def test_geodetic_and_ecef_forms_give_the_same_transducer_positions(tmp_path: Path):
    """The packaged track and attitude written both ways (and as GPS_POS_FREED + RPH): the transducer
    positions through the lever arm agree to < 1e-6 m (geodetic rows carry 1e-12 deg = 0.11 um)."""
    cfg = read_gnatss_config(EXAMPLE / "config.yaml")
    ant = read_gps_pos_freed(EXAMPLE / "GPS_POS_FREED")
    att = read_roll_pitch_heading(EXAMPLE / "RPH")
    cov = np.einsum("ki,ij->kij", ant.sigma_xyz_m**2, np.eye(3))
    out = {}
    for form in POSITION_FORMS:
        p = write_antenna_csv(tmp_path / f"{form}.csv", ant.t_s, ant.xyz_m, cov, att.rph_deg, time="iso",
                              position=form, covariance="sd_enu")  # fmt: skip
        out[form], _ = antenna_pings(read_pxp_tt(EXAMPLE / "pxp_tt", 3), read_antenna_csv(p), None, cfg.ids,
                                     np.asarray(cfg.atd_offsets_frd_m), cfg.array_center)  # fmt: skip
    ref, _ = antenna_pings(read_pxp_tt(EXAMPLE / "pxp_tt", 3), ant, att, cfg.ids,
                           np.asarray(cfg.atd_offsets_frd_m), cfg.array_center)  # fmt: skip
    g, e = out["geodetic"], out["ecef"]
    assert g.n_replies == e.n_replies == ref.n_replies == 600
    assert np.max(np.abs(g.transmit_xyz_m - e.transmit_xyz_m)) < 1e-6
    assert np.max(np.abs(g.receive_xyz_m - e.receive_xyz_m)) < 1e-6
    assert np.max(np.abs(e.receive_xyz_m - ref.receive_xyz_m)) < 1e-6
    assert np.allclose(g.receive_cov_m2, e.receive_cov_m2, rtol=1e-9, atol=1e-15)
