import dataclasses

import numpy as np
import pytest

from oceanloc.config.survey import PlannerSettings, load_survey_scenario
from oceanloc.evaluation.montecarlo import concat_runs
from oceanloc.sim.survey import simulate_surveys


def _scenario(name="garcia2019-m4", kind="random-yaw", horizon=1, epochs=8):
    base = load_survey_scenario(name)
    return dataclasses.replace(base.with_planner(PlannerSettings(kind=kind, horizon=horizon)), epochs=epochs)


def test_epoch_convention_measures_at_start_then_moves_by_eq1():
    sc = _scenario(kind="lookahead", horizon=2)
    runs = simulate_surveys(sc, [0, 1], seed=3)
    np.testing.assert_array_equal(runs.sites_enu_m[:, 0], np.broadcast_to(sc.start_enu_m, (2, 3)))
    assert runs.yaw_rad[0, 0] == pytest.approx(sc.start_yaw_rad)
    step = np.diff(runs.sites_enu_m, axis=1)
    heading = runs.yaw_rad[:, 1:]
    expected = 3.0 * np.stack([np.cos(heading), np.sin(heading), 0 * heading], -1)
    np.testing.assert_allclose(step, expected, atol=1e-12)  # p(n+1) = p(n) + Rz(phi(n+1)) v T
    assert np.all(np.abs(np.diff(runs.yaw_rad, axis=1)) <= sc.max_yaw_rate_rad_s * sc.period_s + 1e-12)
    assert runs.plan_objective.shape == (2, sc.epochs - 1)


def test_runs_do_not_depend_on_their_batch():
    sc = _scenario(epochs=6)
    whole = simulate_surveys(sc, np.arange(6), seed=11)
    part = simulate_surveys(sc, [4, 5], seed=11)
    for field in (
        "prior_mean_m",
        "sites_enu_m",
        "ranges_m",
        "estimates_m",
        "covariances_m2",
        "log_det",
        "nees",
    ):
        np.testing.assert_array_equal(getattr(whole, field)[4:], getattr(part, field), err_msg=field)
    joined = concat_runs(
        [simulate_surveys(sc, [0, 1, 2], 11), simulate_surveys(sc, [3, 4, 5], 11)],
        keep=("transponders_enu_m",),
    )
    np.testing.assert_array_equal(joined.estimates_m, whole.estimates_m)


def test_range_noise_and_prior_draws_have_the_scenario_statistics():
    # 400 runs x 4 transponders: the prior-draw mean error per axis has standard error sigma/sqrt(1600);
    # the range-noise std over 400 x 2 x 4 draws has relative standard error 1/sqrt(2 * 3200). 4 SE each.
    sc = _scenario(epochs=2)
    runs = simulate_surveys(sc, np.arange(400), seed=5)
    prior_err = (runs.prior_mean_m - sc.transponders_enu_m).reshape(-1, 3)
    sig = np.sqrt(np.diag(sc.prior_cov_m2))
    assert np.all(np.abs(prior_err.mean(axis=0)) < 4 * sig / np.sqrt(prior_err.shape[0]))
    true = np.linalg.norm(sc.transponders_enu_m[None, None] - runs.sites_enu_m[:, :, None], axis=-1)
    noise = runs.ranges_m - true
    assert abs(noise.std() / sc.sigma_range_m - 1) < 4 / np.sqrt(2 * noise.size)


def test_estimates_stay_below_the_surface_and_are_consistent():
    # Mean NEES over 300 runs at n = N = 50 (where the paper shows chi2(3)): standard error sqrt(6/300) =
    # 0.14; 3 SE band. (Earlier, a random track close to a straight line leaves the mirror image of the
    # transponder across it almost as likely, and the NEES is not chi-square.)
    sc = _scenario("garcia2019-m1", epochs=50)
    runs = simulate_surveys(sc, np.arange(300), seed=7)
    assert np.all(runs.estimates_m[..., 2] < 0.0)
    assert abs(runs.nees[:, -1].mean() - 3.0) < 3 * np.sqrt(6 / 300)
    assert runs.converged.mean() > 0.999


def test_greedy_scenario_moves_within_reach():
    sc = _scenario("garcia2018-greedy-m4", kind="greedy", epochs=5)
    runs = simulate_surveys(sc, [0, 1, 2], seed=1)
    hops = np.linalg.norm(np.diff(runs.sites_enu_m, axis=1), axis=-1)
    assert np.all(hops <= sc.planner.max_distance_m + 1e-9)
    assert np.all(hops > 0.0)
