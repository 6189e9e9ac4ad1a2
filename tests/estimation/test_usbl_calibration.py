"""USBL calibration by MAP: recovery, consistency, observability (held parameters named), bad input."""

import numpy as np
import pytest

from oceanloc._random import run_generators
from oceanloc.errors import ConfigError
from oceanloc.estimation.consistency import chi_square_check
from oceanloc.estimation.usbl_calibration import (
    CalibrationOptions,
    CalibrationPrior,
    UsblNoise,
    UsblPings,
    apparent_positions,
    calibrate_usbl,
)
from oceanloc.planning.calibration_tracks import box_in_track, casius_track, line_track
from oceanloc.sim.usbl_calibration import UsblTruth, simulate_pings
from oceanloc.units import DEG

DEPTH = 20.0
TRUTH = UsblTruth(beacon_ids=np.array([1]), beacon_enu_m=np.array([[0.0, 0.0, -DEPTH]]))
NOISE = UsblNoise()
PRIOR_SIGMA = dict(
    beacon_sigma_m=[[5.0, 5.0, 3.0]],
    misalignment_sigma_rad=np.array([3.0, 3.0, 10.0]) * DEG,
    lever_arm_sigma_m=np.full(3, 0.1),
    scale_sigma=0.01,
    delay_sigma_s=1e-3,
)


def _prior_draws(runs: int, seed: int, options: CalibrationOptions):
    """Each run's prior mean drawn about the truth with the prior's own covariance (for NEES)."""
    rng = np.random.default_rng(seed)
    base = CalibrationPrior(beacon_ids=[1], beacon_enu_m=TRUTH.beacon_enu_m, **PRIOR_SIGMA)
    truth = TRUTH.state(options)
    from oceanloc.estimation.usbl_calibration import build_calibration_graph

    dummy = UsblPings.build([1], np.zeros((1, 3)), np.zeros((1, 3)), [np.nan], [[np.nan, np.nan]])
    _, cov = build_calibration_graph(dummy, base, NOISE, options).prior_arrays()
    draws = truth + rng.standard_normal((runs, truth.size)) * np.sqrt(np.diag(cov[0]))
    return draws


def _prior_from_state(x, options):
    """The CalibrationPrior whose mean is the state x (one per run: the beacon batched, the rest shared)."""
    return CalibrationPrior(
        beacon_ids=[1],
        beacon_enu_m=x[:, None, :3],
        **PRIOR_SIGMA,
        misalignment_rad=x[0, 3:6],
        lever_arm_m=x[0, 6:9],
        scale=float(x[0, 9]),
        delay_s=float(x[0, 10]),
    )


def test_casius_pattern_recovers_the_truth_consistently():
    # 24 runs of the CASIUS pattern at 20 m, the prior's calibration terms drawn once, the beacon's per run.
    opts = CalibrationOptions()
    track = casius_track(DEPTH, 1.5, 1.0)
    runs = 24
    x0 = _prior_draws(runs, 3, opts)
    prior = _prior_from_state(x0, opts)
    pings = simulate_pings(
        track.pos_enu_m,
        track.heading_rad,
        np.ones(track.pings, int),
        TRUTH,
        NOISE,
        run_generators(7, range(runs)),
    )
    res = calibrate_usbl(pings, prior, NOISE, opts)
    assert np.all(res.status == "converged") and np.all(res.trusted)
    # only the lever arm's down component is unseen (it moves with the beacon's depth), and it is named
    names = res.layout.component_names()
    assert [names[i] for i in np.flatnonzero(res.held[0])] == ["lever_arm down"]
    assert "not separable from beacon 1 up" in res.notes[0][0]
    # NEES over the calibration parameters that are estimated (the held one's error is the prior's draw,
    # common to every run here): chi-square with 7 dof, mean within 3 Monte Carlo standard errors.
    idx = [i for i in res.calibration_index() if not res.held[0, i]]
    check = chi_square_check(res.nees(TRUTH.state(opts), idx), len(idx))
    assert check.mean_within_band, check
    # heading misalignment to better than 0.1 degree (1 sigma) in 400 pings at 20 m
    assert res.block_sigma("misalignment")[:, 2].max() < 0.1 * DEG
    # the fixes seen with the calibrated values gather on the beacon; with the prior's they do not
    after = apparent_positions(pings, res, prior, opts)
    before = apparent_positions(pings, res, prior, opts, calibrated=False)
    spread_after = np.sqrt(np.mean(np.sum((after - TRUTH.beacon_enu_m[0]) ** 2, axis=-1)))
    spread_before = np.sqrt(np.mean(np.sum((before - TRUTH.beacon_enu_m[0]) ** 2, axis=-1)))
    assert spread_after < 0.5 * spread_before


def test_a_single_straight_line_says_roll_is_not_separable_from_the_cross_track_position():
    opts = CalibrationOptions()
    for heading_deg, cross in ((0.0, "beacon 1 east"), (90.0, "beacon 1 north")):
        track = line_track(2 * DEPTH, 1.5, 1.0, heading_rad=heading_deg * DEG)
        pings = simulate_pings(
            track.pos_enu_m,
            track.heading_rad,
            np.ones(track.pings, int),
            TRUTH,
            NOISE,
            run_generators(1, [0]),
        )
        prior = CalibrationPrior(beacon_ids=[1], beacon_enu_m=[[2.0, -1.0, -18.0]], **PRIOR_SIGMA)
        res = calibrate_usbl(pings, prior, NOISE, opts)
        roll = res.layout.component_names().index("misalignment roll")
        assert res.held[0, roll]
        note = next(n for n in res.notes[0] if n.startswith("misalignment roll held"))
        assert cross in note
        # held: no number of its own, its prior's value and sigma
        assert res.estimate[0, roll] == prior.misalignment_rad[0]
        assert res.sigma[0, roll] == pytest.approx(prior.misalignment_sigma_rad[0])


def test_delay_and_bias_together_one_is_held():
    opts = CalibrationOptions(estimate_bias=True)
    track = box_in_track(DEPTH, 1.5, 1.0)
    pings = simulate_pings(
        track.pos_enu_m, track.heading_rad, np.ones(track.pings, int), TRUTH, NOISE, run_generators(2, [0])
    )
    prior = CalibrationPrior(
        beacon_ids=[1], beacon_enu_m=[[1.0, 1.0, -19.0]], **PRIOR_SIGMA, bias_sigma_m=0.5
    )
    res = calibrate_usbl(pings, prior, NOISE, opts)
    names = res.layout.component_names()
    held = {names[i] for i in np.flatnonzero(res.held[0])}
    assert "bias" in held and "delay" not in held
    assert any("bias held at its prior: not separable from delay" in n for n in res.notes[0])


def test_a_measured_depth_makes_the_lever_arm_down_observable():
    opts = CalibrationOptions(depths=((1, DEPTH, 0.01),))
    track = casius_track(DEPTH, 1.5, 1.0)
    pings = simulate_pings(
        track.pos_enu_m, track.heading_rad, np.ones(track.pings, int), TRUTH, NOISE, run_generators(3, [0])
    )
    prior = CalibrationPrior(beacon_ids=[1], beacon_enu_m=[[1.0, 1.0, -19.0]], **PRIOR_SIGMA)
    res = calibrate_usbl(pings, prior, NOISE, opts)
    assert not res.held.any()
    down = res.layout.component_names().index("lever_arm down")
    assert abs(res.estimate[0, down] - TRUTH.lever_arm_m[2]) < 3 * res.sigma[0, down]
    assert res.sigma[0, down] < 0.03


def test_residuals_are_reported_per_ping_and_whitened():
    opts = CalibrationOptions()
    track = box_in_track(DEPTH, 1.5, 1.0)
    pings = simulate_pings(
        track.pos_enu_m, track.heading_rad, np.ones(track.pings, int), TRUTH, NOISE, run_generators(4, [0])
    )
    prior = CalibrationPrior(beacon_ids=[1], beacon_enu_m=[[1.0, 1.0, -19.0]], **PRIOR_SIGMA)
    res = calibrate_usbl(pings, prior, NOISE, opts)
    assert res.range_residual_m.shape == (1, track.pings)
    assert res.direction_residual_rad.shape == (1, track.pings, 2)
    # whitened residuals of a consistent fit: unit variance within sampling error (3 SE of a variance)
    var = np.nanvar(res.normalized_residual[0], axis=0)
    assert np.all(np.abs(var - 1.0) < 3 * np.sqrt(2.0 / track.pings) + 0.1)
    assert np.nanmax(np.abs(res.range_residual_m)) < 5 * NOISE.sigma_range_m


def test_missing_pings_and_bad_inputs():
    opts = CalibrationOptions()
    track = box_in_track(DEPTH, 1.5, 1.0)
    pings = simulate_pings(
        track.pos_enu_m, track.heading_rad, np.ones(track.pings, int), TRUTH, NOISE, run_generators(5, [0])
    )
    rng = pings.range_m.copy()
    rng[0, ::3] = np.nan
    dirs = pings.direction_rad.copy()
    dirs[0, 1::3] = np.nan
    gappy = UsblPings.build(pings.beacon, pings.antenna_enu_m, pings.attitude_rad, rng, dirs)
    prior = CalibrationPrior(beacon_ids=[1], beacon_enu_m=[[1.0, 1.0, -19.0]], **PRIOR_SIGMA)
    res = calibrate_usbl(gappy, prior, NOISE, opts)
    assert res.status[0] == "converged"
    assert (
        np.isnan(res.range_residual_m[0, ::3]).all() and np.isnan(res.normalized_residual[0, 1::3, 1:]).all()
    )
    with pytest.raises(ConfigError, match="no prior position"):
        calibrate_usbl(
            UsblPings.build(np.full(pings.n, 2), pings.antenna_enu_m, pings.attitude_rad, rng, dirs), prior
        )
    with pytest.raises(ConfigError, match="positive"):
        CalibrationPrior(beacon_ids=[1], beacon_enu_m=[[0.0, 0.0, -1.0]], beacon_sigma_m=[[0.0, 1.0, 1.0]])
    with pytest.raises(ConfigError, match="sound speed"):
        CalibrationOptions(sound_speed_mps=100.0)
    with pytest.raises(ConfigError, match="finite"):
        UsblPings.build([1], [[np.nan, 0.0, 0.0]], np.zeros((1, 3)), [1.0], [[0.0, 0.0]])
