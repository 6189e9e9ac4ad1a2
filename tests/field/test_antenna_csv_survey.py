"""A GNATSS-format survey solved from the antenna CSV: the same solution as through GPS_POS_FREED + RPH,
within 3 sigma of the truth; the lever arm's sigma propagates into the solution's covariance as the
linear-Gaussian identity says; the lever arm is calibrated back from a wrong prior."""

import dataclasses

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa_array import GnssaArrayOptions
from oceanloc.field.gnatss_input import load_gnatss_input, localize_gnatss_input, process_gnatss_survey
from oceanloc.sim.gnatss_survey import EXAMPLE_SPEC, write_gnatss_survey

SPEC = dataclasses.replace(
    EXAMPLE_SPEC, n_pings=400, ping_interval_s=18.0, gross_fraction=0.0, seed=5, ray_traced=True
)
"""400 interrogations over 2 h of three transponders, the platform looping (heading through 360 deg every
30 min), no gross errors, travel times ray traced through the profile (the model oceanloc fits): about
1 s per solve."""


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    return write_gnatss_survey(SPEC, tmp_path_factory.mktemp("antenna_csv"))


def test_csv_and_gps_pos_freed_paths_give_the_same_solution_near_the_truth(survey):
    """The CSV carries the same track (UTC times, latitude/longitude/height, ECEF sigmas) as
    GPS_POS_FREED + RPH: the solutions agree to 1e-6 m, and each is within 3 sigma of the truth."""
    truth, f = survey
    csv = load_gnatss_input(f.config, pxp_tt=f.pxp_tt, antenna=f.antenna_csv)
    old = load_gnatss_input(f.config, pxp_tt=f.pxp_tt, antenna=f.gps_pos_freed, attitude=f.roll_pitch_heading)
    assert str(f.antenna_csv) in csv.inputs and csv.antenna is not None
    a = localize_gnatss_input(csv, solution="common_shift")
    b = localize_gnatss_input(old, solution="common_shift")
    assert np.max(np.abs(a.positions_enu_m - b.positions_enu_m)) < 1e-6
    assert np.max(np.abs(a.sigma_enu_m - b.sigma_enu_m)) < 1e-6
    assert np.all(np.abs(a.positions_enu_m - truth.transponders_enu_m) < 3.0 * a.sigma_enu_m)
    ind = localize_gnatss_input(csv, solution="independent")
    assert np.all(np.abs(ind.positions_enu_m - truth.transponders_enu_m) < 3.0 * ind.sigma_enu_m)


def test_lever_arm_sigma_grows_the_covariance_by_the_propagated_amount(survey):
    """With the lever arm an unknown of prior ``diag(0.05 m)^2``, the shift's covariance is, by the law of
    total covariance of the (linearised) Gaussian posterior, ``C_0 + K C_l K^T``: ``C_0`` the covariance
    with the lever arm fixed, ``C_l`` the lever arm's posterior covariance, ``K = d shift / d lever``
    found by central differences of re-solves with the lever arm moved by +-1 cm (linear: K changes by
    < 1e-3 between 1 mm and 1 cm steps). No Monte Carlo, so no standard error: the tolerance, 2 % of
    ``sqrt(C_ii C_jj)``, covers the Gauss-Newton linearisation and the re-estimated noise (measured
    0.6 %). The gradient is not estimated, the model selection and the outlier loop are off, so that each
    re-solve uses the same model and replies; the GNSS common-mode term and the jackknife, which the
    identity is not about, are off too."""
    _, f = survey
    opts = GnssaArrayOptions(
        solution="common_shift", estimate_gradient=False, outlier_threshold=1e9, select_model=False,
        gnss_common_mode=False, jackknife_blocks=0,
    )  # fmt: skip
    d0 = load_gnatss_input(f.config, pxp_tt=f.pxp_tt, antenna=f.antenna_csv)
    base = localize_gnatss_input(d0, options=opts)
    k = np.zeros((3, 3))
    h = 0.01
    for i in range(3):
        moved = []
        for sign in (1.0, -1.0):
            arm = d0.antenna.lever_arm_frd_m + sign * h * np.eye(3)[i]
            data = dataclasses.replace(d0, antenna=dataclasses.replace(d0.antenna, lever_arm_frd_m=arm))
            moved.append(localize_gnatss_input(data, options=opts).positions_enu_m[0])
        k[:, i] = (moved[0] - moved[1]) / (2 * h)
    d1 = load_gnatss_input(f.config, pxp_tt=f.pxp_tt, antenna=f.antenna_csv, lever_arm_sigma_m=0.05)
    with_sigma = localize_gnatss_input(d1, options=opts)
    c_l = np.array(with_sigma.extra["lever_arm_covariance_m2"])
    assert np.all(np.sqrt(np.diag(c_l)) <= 0.05 + 1e-12)
    want = base.covariance_enu_m2[0] + k @ c_l @ k.T
    got = with_sigma.covariance_enu_m2[0]
    scale = np.sqrt(np.outer(np.diag(want), np.diag(want)))
    assert np.max(np.abs(got - want) / scale) < 0.02
    # and the growth is real: the vertical variance (the downward lever arm maps 1:1 to up) about doubles
    assert got[2, 2] - base.covariance_enu_m2[0, 2, 2] > 0.5 * base.covariance_enu_m2[0, 2, 2]
    assert with_sigma.extra["lever_arm_prior_sigma_m"] == [0.05, 0.05, 0.05]


def test_calibration_recovers_a_lever_arm_offset(survey):
    """The configuration's lever arm is off by (10, -8, 15) cm; calibrating it (prior 1 m) with the
    heading variation of the loops brings each component within 3 sigma of the truth, and the horizontal
    sigmas are small enough that the offset is resolved (more than 3 sigma away)."""
    truth, f = survey
    d0 = load_gnatss_input(f.config, pxp_tt=f.pxp_tt, antenna=f.antenna_csv)
    offset = np.array([0.10, -0.08, 0.15])
    wrong = dataclasses.replace(d0.antenna, lever_arm_frd_m=truth.lever_arm_frd_m + offset)
    res = localize_gnatss_input(
        dataclasses.replace(d0, antenna=wrong),
        options=GnssaArrayOptions(solution="common_shift", estimate_lever_arm=True),
    )
    est = np.array(res.extra["lever_arm_body_m"])
    sig = np.array(res.extra["lever_arm_sigma_m"])
    assert res.extra["lever_arm_estimated"] and res.extra["lever_arm_prior_sigma_m"] == [1.0, 1.0, 1.0]
    assert np.all(np.abs(est - truth.lever_arm_frd_m) < 3.0 * sig)
    assert np.all(np.abs(offset[:2]) > 3.0 * sig[:2])
    assert res.extra["lever_arm_determined"][:2] == [True, True]


def test_lever_arm_options_need_antenna_input_and_oceanloc(survey):
    _, f = survey
    with pytest.raises(ConfigError, match="--lever-arm-sigma needs --antenna"):
        load_gnatss_input(f.config, pxp_tt=f.pxp_tt, positions=f.pos_freed_trans_twtt, lever_arm_sigma_m=0.1)
    with pytest.raises(ConfigError, match="--estimate-lever-arm needs --antenna"):
        process_gnatss_survey(
            f.config, pxp_tt=f.pxp_tt, positions=f.pos_freed_trans_twtt, estimate_lever_arm=True
        )
    with pytest.raises(ConfigError, match="need --method oceanloc"):
        process_gnatss_survey(
            f.config, pxp_tt=f.pxp_tt, antenna=f.antenna_csv, method="gnatss", estimate_lever_arm=True
        )
    with pytest.raises(ConfigError, match="exactly one of them"):
        load_gnatss_input(f.config, pxp_tt=f.pxp_tt, antenna=f.antenna_csv, attitude=f.roll_pitch_heading)
    with pytest.raises(
        ConfigError, match=r"one or three \(forward, rightward, downward\) values in \[0, 10\] m"
    ):
        load_gnatss_input(f.config, pxp_tt=f.pxp_tt, antenna=f.antenna_csv, lever_arm_sigma_m=[0.1, 0.2])
