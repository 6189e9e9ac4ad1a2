"""GNSS-A array localization (:mod:`oceanloc.estimation.gnssa_array`) on synthetic surveys with a known
truth (:mod:`oceanloc.sim.gnssa_array`)."""

import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.stats import chi2

from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.gnssa_array import (
    ArrayGeometry,
    GnssaArrayOptions,
    _refresh_bending,
    _setup,
    _whitening,
    gnatss_like_options,
    hat_pairs,
    localize_gnssa_array,
    serial_correlation_test,
)
from oceanloc.models.sound_profile import SoundSpeedProfile
from oceanloc.sim.gnssa_array import simulate_gnssa_array

TRIANGLE = np.array([[500.0, 0.0, -2000.0], [-250.0, 433.0, -2010.0], [-250.0, -433.0, -1990.0]])


def _layout(n: int, depth_m: float, spacing_m: float) -> np.ndarray:
    """``n`` transponders on a circle (one at the centre when n = 1), a few metres apart in depth."""
    if n == 1:
        return np.array([[10.0, -20.0, -depth_m]])
    ang = 2.0 * np.pi * np.arange(n) / n
    return np.stack(
        [spacing_m * np.cos(ang), spacing_m * np.sin(ang), -depth_m + 5.0 * np.sin(3.0 * ang)], axis=1
    )


def _fd_jacobian(problem, x, eps):
    cols = []
    for k in range(x.size):
        dx = np.zeros(x.size)
        dx[k] = eps[k]
        cols.append((problem.model(x + dx)[0] - problem.model(x - dx)[0]) / (2.0 * eps[k]))
    return np.stack(cols, axis=1)


@pytest.mark.parametrize("solution", ["independent", "common_shift"])
@pytest.mark.parametrize("model", ["straight", "harmonic", "ray"])
def test_model_jacobian_matches_central_differences(solution, model):
    rng = np.random.default_rng(3)
    survey, truth = simulate_gnssa_array(
        rng, positions_enu_m=TRIANGLE, n_pings=120, lever_arm_body_m=(0.4, -0.3, 1.8), reply_probability=0.7
    )
    survey = dataclasses.replace(survey, lever_arm_cov_m2=0.05**2 * np.eye(3))
    opts = GnssaArrayOptions(solution=solution, acoustic_model=model, knot_spacing_s=300.0, prescreen=False)
    geometry = ArrayGeometry(positions_enu_m=TRIANGLE + 0.3)
    setup = _setup(survey, opts, truth.profile, geometry)
    problem = setup.problem
    x = setup.prior.mean[0].copy()
    x[: problem.n_pos] += 0.5
    x[problem.col_gradient : problem.col_gradient + 2] = (4e-4, -7e-4)  # per km, a strong gradient
    x[problem.first_knot :] += np.linspace(-1.0, 1.0, x.size - problem.first_knot)
    _refresh_bending(problem, x, force=True)
    _, jac = problem.model(x)
    eps = np.full(x.size, 1e-3)
    fd = _fd_jacobian(problem, x, eps)
    scale = np.max(np.abs(fd), axis=0) + 1e-12
    # The bending correction is frozen between solves (its derivative, < 1e-4 of the straight leg's, is
    # left out), so the ray model's position and lever-arm columns agree to 1e-4 relative; every other
    # column, and every column of the other models, to 1e-6.
    tol = np.full(x.size, 1e-6)
    if model == "ray":
        tol[: problem.first_knot] = 1e-4
        tol[problem.col_gradient : problem.col_gradient + 2] = 1e-6
    err = np.max(np.abs(jac - fd), axis=0) / scale
    assert np.all(err < tol), err
    assert problem.lever and jac.shape == (survey.n_replies, x.size)


@pytest.mark.parametrize("solution", ["independent", "common_shift"])
def test_structured_normal_equations_equal_the_dense_jacobian_products(solution):
    """The solver's ``J^T J`` and ``J^T r``, formed blockwise from the hat basis's two knots per reply,
    equal the dense whitened Jacobian's products to rounding (1e-12 of the largest entry), with partial
    replies, a lever arm in the state, a gradient, 1 to 4 knots per ping's replies and masked replies."""
    rng = np.random.default_rng(5)
    survey, truth = simulate_gnssa_array(
        rng, positions_enu_m=TRIANGLE, n_pings=150, lever_arm_body_m=(0.4, -0.3, 1.8), reply_probability=0.7
    )
    survey = dataclasses.replace(survey, lever_arm_cov_m2=0.05**2 * np.eye(3))
    opts = GnssaArrayOptions(solution=solution, knot_spacing_s=60.0, min_pings_per_knot=1, prescreen=False)
    setup = _setup(survey, opts, truth.profile, ArrayGeometry(positions_enu_m=TRIANGLE + 0.3))
    problem = setup.problem
    x = setup.prior.mean[0].copy()
    x[problem.col_gradient : problem.col_gradient + 2] = (4e-4, -7e-4)
    x[problem.first_knot :] += np.linspace(-1.0, 1.0, x.size - problem.first_knot)
    problem.mask = rng.random(survey.n_replies) > 0.1
    problem.whiten, _ = _whitening(problem, x, np.full(survey.n_replies, 0.01))
    problem.invalidate()
    rows = np.zeros(1, dtype=np.int64)
    resid, jac = problem.evaluate(x[None], rows)
    ne = problem.normal_equations(x[None], rows)
    dense_normal = jac[0].T @ jac[0]
    assert problem.n_knots > 10 and np.all(np.abs(problem.residuals(x[None], rows) - resid) == 0.0)
    assert np.max(np.abs(ne.normal[0] - dense_normal)) < 1e-12 * np.max(np.abs(dense_normal))
    grad = jac[0].T @ resid[0]
    assert np.max(np.abs(ne.gradient[0] - grad)) < 1e-12 * np.max(np.abs(grad))
    assert np.all(ne.normal[0] == ne.normal[0].T) and not ne.blind.any()
    # the knot block is banded: each reply touches two neighbouring knots
    k0 = problem.first_knot
    band = np.abs(np.subtract.outer(np.arange(problem.n_knots), np.arange(problem.n_knots))) > 1
    assert np.all(ne.normal[0, k0:, k0:][band] == 0.0)


def test_hat_pairs_read_the_two_neighbouring_knots_of_each_time():
    from oceanloc.estimation.gnssa import hat_basis

    knots = np.array([0.0, 10.0, 30.0, 60.0])
    t = np.array([-5.0, 0.0, 4.0, 10.0, 29.0, 60.0, 75.0])
    basis = hat_basis(t, knots)
    first, weight = hat_pairs(basis)
    assert first.tolist() == [0, 0, 0, 1, 1, 2, 2]
    rebuilt = np.zeros_like(basis)
    rebuilt[np.arange(t.size), first] += weight[:, 0]
    rebuilt[np.arange(t.size), first + 1] += weight[:, 1]
    assert np.array_equal(rebuilt, basis)
    one_first, one_weight = hat_pairs(hat_basis(t, knots[:1]))
    assert np.all(one_first == 0) and np.all(one_weight == [1.0, 0.0])
    with pytest.raises(ValueError, match="not a hat basis"):
        hat_pairs(np.ones((2, 3)))


def test_noise_free_survey_is_recovered_to_a_tenth_of_a_millimetre_through_the_ray_traced_profile():
    rng = np.random.default_rng(11)
    survey, truth = simulate_gnssa_array(
        rng,
        positions_enu_m=TRIANGLE,
        n_pings=400,
        drift_ppm_per_h=100.0,
        lever_arm_body_m=(0.5, -0.3, 2.0),
        gnss_sigma_enu_m=(1e-6, 1e-6, 1e-6),
        twtt_sigma_s=1e-10,
    )
    opts = GnssaArrayOptions(
        prescreen=False, estimate_noise=False, sigma_path_m=1e-4, jackknife_blocks=0, surface_height_m=0.0
    )
    result = localize_gnssa_array(survey, opts, profile=truth.profile)
    assert np.max(np.abs(result.positions_enu_m - TRIANGLE)) < 1e-4
    # the profile's speed drifts by 100 ppm per hour: the knots recover it
    drift_ppm = 1e6 * (result.sound_speed_knots_mps / result.reference_speed_mps - 1.0)
    expected = 100.0 * (result.knot_times_s - survey.t_transmit_s[0]) / 3600.0
    assert np.max(np.abs(drift_ppm - expected)) < 1.0
    assert result.exclusions == () and result.converged


@pytest.mark.parametrize(
    ("n_transponders", "depth_m", "reply_probability", "drift_ppm_per_h"),
    [(1, 1500.0, 1.0, 0.0), (2, 3000.0, 0.6, 50.0), (4, 800.0, 0.5, -80.0), (6, 150.0, 0.4, 120.0)],
)
def test_synthetic_arrays_are_recovered_within_their_sigmas(
    n_transponders, depth_m, reply_probability, drift_ppm_per_h
):
    rng = np.random.default_rng(n_transponders)
    truth_pos = _layout(n_transponders, depth_m, 0.3 * depth_m)
    survey, truth = simulate_gnssa_array(
        rng,
        positions_enu_m=truth_pos,
        n_pings=400,
        reply_probability=reply_probability,
        drift_ppm_per_h=drift_ppm_per_h,
        lever_arm_body_m=(0.2, 0.1, 1.2),
    )
    assert survey.n_replies < 400 * n_transponders or reply_probability == 1.0  # partial replies
    result = localize_gnssa_array(survey, GnssaArrayOptions(), profile=truth.profile)
    err = result.positions_enu_m - truth_pos
    # 4 sigma per axis: a 1e-4 chance per axis for a consistent covariance
    assert np.all(np.abs(err) < 4.0 * result.sigma_enu_m), (err, result.sigma_enu_m)
    assert np.all(result.sigma_enu_m < 0.1)
    assert result.positions_geodetic is None and result.converged
    record = result.to_record()
    assert [t["id"] for t in record["transponders"]] == list(survey.transponder_ids)
    assert sum(t["replies_used"] for t in record["transponders"]) == int(result.used.sum())


def test_nees_of_both_solutions_matches_chi_square_over_seeded_runs():
    """Formal covariance (no jackknife, no survey-wide GNSS term: the simulated GNSS noise is independent
    from ping to ping): the mean NEES of R runs is within 3 Monte Carlo standard errors, sqrt(2 d / R), of
    its degrees of freedom d (6 for two transponders, 3 for the common shift)."""
    truth_pos = np.array([[400.0, 0.0, -1500.0], [-400.0, 0.0, -1510.0]])
    offset = np.array([1.0, -2.0, 0.5])
    geometry = ArrayGeometry(positions_enu_m=truth_pos + offset)
    opts = GnssaArrayOptions(jackknife_blocks=0, gnss_common_mode=False)
    runs = 16
    nees, nees_shift = [], []
    for r in range(runs):
        rng = np.random.default_rng([7, r])
        survey, truth = simulate_gnssa_array(
            rng, positions_enu_m=truth_pos, n_pings=240, drift_ppm_per_h=80.0, reply_probability=0.8
        )
        res = localize_gnssa_array(survey, opts, profile=truth.profile)
        e = (res.positions_enu_m - truth_pos).reshape(-1)
        nees.append(e @ np.linalg.solve(res.covariance_m2, e))
        shift = localize_gnssa_array(
            survey,
            dataclasses.replace(opts, solution="common_shift"),
            profile=truth.profile,
            geometry=geometry,
        )
        es = shift.shift_enu_m + offset
        nees_shift.append(es @ np.linalg.solve(shift.shift_covariance_m2, es))
        np.testing.assert_allclose(shift.positions_enu_m, geometry.positions_enu_m + shift.shift_enu_m)
    for values, dof in ((nees, 6), (nees_shift, 3)):
        se = np.sqrt(2.0 * dof / runs)
        assert abs(np.mean(values) - dof) < 3.0 * se, (np.mean(values), dof)
    # and the NEES are chi-square distributed: at most 2 of the 16 beyond the 95 % point (binomial, p = 0.99)
    assert np.sum(np.array(nees) > chi2.ppf(0.95, 6)) <= 3


def test_formal_covariance_is_the_cramer_rao_bound_with_known_noise():
    """Straight rays, a fixed speed and a fixed noise: the formal covariance equals the inverse Fisher
    information computed independently here (finite-difference Jacobian of the two-way straight-ray time,
    each ping's replies correlated through the transmit position)."""
    rng = np.random.default_rng(5)
    iso = SoundSpeedProfile(depth_m=np.array([0.0, 5000.0]), speed_mps=np.array([1500.0, 1500.0]))
    survey, _ = simulate_gnssa_array(
        rng, positions_enu_m=TRIANGLE, n_pings=150, reply_probability=0.7, profile=iso
    )
    sigma_path = 0.03
    opts = GnssaArrayOptions(
        acoustic_model="straight",
        sound_speed_mps=1500.0,
        estimate_sound_speed=False,
        estimate_gradient=False,
        estimate_noise=False,
        sigma_path_m=sigma_path,
        jackknife_blocks=0,
        gnss_common_mode=False,
        prescreen=False,
        sigma_position_prior_m=1e6,
    )
    res = localize_gnssa_array(survey, opts)
    assert res.exclusions == () or len(res.exclusions) < 5
    p = res.positions_enu_m
    tx, rx = survey.transmit_enu_m(), survey.receive_enu_m()
    info = np.zeros((9, 9))
    for i in range(survey.n_pings):
        replies = np.flatnonzero((survey.reply_ping == i) & res.used)
        if replies.size == 0:
            continue
        jt = survey.reply_transponder[replies]
        h = np.zeros((replies.size, 9))
        u_tx = np.zeros((replies.size, 3))
        cov = np.zeros((replies.size, replies.size))
        for k, (o, j) in enumerate(zip(replies, jt, strict=True)):
            for axis in range(3):
                d = np.zeros(3)
                d[axis] = 1e-4
                f = [np.linalg.norm(q - tx[i]) + np.linalg.norm(q - rx[o]) for q in (p[j] + d, p[j] - d)]
                h[k, 3 * j + axis] = (f[0] - f[1]) / 2e-4
            u_tx[k] = (tx[i] - p[j]) / np.linalg.norm(tx[i] - p[j])
            u_rx = (rx[o] - p[j]) / np.linalg.norm(rx[o] - p[j])
            cov[k, k] = u_rx @ survey.receive_antenna_cov_m2[o] @ u_rx + sigma_path**2
        cov += u_tx @ survey.transmit_antenna_cov_m2[i] @ u_tx.T
        info += h.T @ np.linalg.solve(cov, h)
    np.testing.assert_allclose(res.covariance_formal_m2, np.linalg.inv(info), rtol=2e-3)


def _lever_survey(pattern: str, seed: int, attitude_deg: tuple[float, float]):
    rng = np.random.default_rng(seed)
    survey, truth = simulate_gnssa_array(
        rng,
        positions_enu_m=TRIANGLE,
        n_pings=500,
        pattern=pattern,
        lever_arm_body_m=(1.5, -0.8, 2.5),
        attitude_amplitude_deg=attitude_deg,
    )
    # the estimator is told a lever arm 30 cm off in every component, with a 1 m prior
    told = dataclasses.replace(
        survey, lever_arm_body_m=np.array([1.8, -0.5, 2.8]), lever_arm_cov_m2=np.eye(3)
    )
    return told, truth


def test_lever_arm_is_calibrated_when_heading_and_attitude_vary():
    survey, truth = _lever_survey("rosette", 21, (10.0, 6.0))
    opts = GnssaArrayOptions(estimate_lever_arm=True)
    res = localize_gnssa_array(survey, opts, profile=truth.profile)
    sigma = np.sqrt(np.diag(res.lever_arm_covariance_m2))
    err = res.lever_arm_body_m - truth.lever_arm_body_m
    assert res.lever_arm_estimated and res.lever_arm_determined.tolist() == [True, True, True]
    # horizontal components: the heading turns through 360 deg, so they are well determined
    assert np.all(sigma[:2] < 0.05) and np.all(np.abs(err[:2]) < 4.0 * sigma[:2]), (err, sigma)
    # the vertical one only through roll and pitch: weaker, but still within its sigma's reach
    assert abs(err[2]) < 4.0 * sigma[2] and sigma[2] < 0.5
    assert np.all(np.abs(res.positions_enu_m - TRIANGLE) < 4.0 * res.sigma_enu_m)


def test_lever_arm_is_weakly_determined_at_constant_heading_and_level():
    survey, truth = _lever_survey("station", 22, (0.0, 0.0))
    res = localize_gnssa_array(survey, GnssaArrayOptions(estimate_lever_arm=True), profile=truth.profile)
    sigma = np.sqrt(np.diag(res.lever_arm_covariance_m2))
    # at a constant heading, level, a horizontal lever arm is a shift of every transducer: the data cannot
    # tell it from the array's position, so its sigma stays near the 1 m prior (with roll and pitch it
    # would show through the transducer's heave, l_y sin(roll))
    assert np.all(sigma[:2] > 0.5), sigma
    assert res.lever_arm_determined[:2].tolist() == [False, False]
    assert res.to_record()["lever_arm_determined"][:2] == [False, False]
    # and the transponders' horizontal sigmas inherit it
    assert np.all(res.sigma_enu_m[:, :2] > 0.5)


def test_lever_arm_uncertainty_enters_the_covariance_without_calibration():
    rng = np.random.default_rng(4)
    survey, truth = simulate_gnssa_array(
        rng, positions_enu_m=TRIANGLE, n_pings=300, pattern="station", attitude_amplitude_deg=(0.0, 0.0)
    )
    known = localize_gnssa_array(survey, GnssaArrayOptions(), profile=truth.profile)
    uncertain = localize_gnssa_array(
        dataclasses.replace(survey, lever_arm_cov_m2=np.diag([0.1**2, 0.1**2, 0.05**2])),
        GnssaArrayOptions(),
        profile=truth.profile,
    )
    # level, at a constant heading, a 10 cm horizontal lever-arm sigma adds 10 cm to every transponder
    extra = np.sqrt(uncertain.sigma_enu_m[:, :2] ** 2 - known.sigma_enu_m[:, :2] ** 2)
    np.testing.assert_allclose(extra, 0.1, rtol=0.15)
    assert not uncertain.lever_arm_estimated


def test_gross_errors_and_outliers_are_excluded_with_reasons():
    rng = np.random.default_rng(8)
    survey, truth = simulate_gnssa_array(rng, positions_enu_m=TRIANGLE, n_pings=400)
    twtt = survey.twtt_s.copy()
    gross = np.array([10, 200, 555])
    twtt[gross] += 0.05  # 75 m of two-way path
    twtt[[30, 31]] += 2e-4  # 30 cm
    bad = dataclasses.replace(survey, twtt_s=twtt)
    res = localize_gnssa_array(bad, GnssaArrayOptions(), profile=truth.profile)
    excluded = {x.reply: x for x in res.exclusions}
    assert set(gross) <= set(excluded) and {30, 31} <= set(excluded)
    assert all("gross error (pre-screen)" in excluded[i].reason for i in gross)
    assert "sigma" in excluded[30].reason and excluded[30].transponder == "T1"
    assert not res.used[gross].any()
    assert np.all(np.abs(res.positions_enu_m - TRIANGLE) < 4.0 * res.sigma_enu_m)
    # GNATSS's rule: residuals beyond the limit, all at once
    limit = localize_gnssa_array(bad, gnatss_like_options(residual_limit_m=5.0), profile=truth.profile)
    assert {int(x.reply) for x in limit.exclusions} == set(gross)
    assert all("> limit 5 m" in x.reason for x in limit.exclusions)


def test_gnatss_like_preset_fixes_the_speed_and_estimates_nothing_else():
    rng = np.random.default_rng(9)
    survey, truth = simulate_gnssa_array(rng, positions_enu_m=TRIANGLE, n_pings=300)
    opts = gnatss_like_options(residual_limit_m=10.0)
    res = localize_gnssa_array(survey, opts, profile=truth.profile)
    assert res.acoustic_model == "harmonic" and res.knot_times_s.size == 0
    assert res.speed_correction_ppm == pytest.approx(0.0, abs=1e-6)
    assert res.sigma_path_m == pytest.approx(0.015) and res.beta_m == 0.0
    assert np.all(res.gradient_per_km == 0.0)
    # given per-transponder speeds replace the profile's harmonic means
    speeds = tuple(float(c) for c in truth.profile.harmonic_mean_mps(np.zeros(3), -TRIANGLE[:, 2]))
    given = localize_gnssa_array(
        survey, gnatss_like_options(transponder_speeds_mps=speeds, residual_limit_m=10.0)
    )
    # the same up to the depth the harmonic means are taken to (the truth here, the first fit's there)
    np.testing.assert_allclose(given.positions_enu_m, res.positions_enu_m, atol=0.1)


def test_settings_that_do_not_fit_the_survey_are_refused():
    rng = np.random.default_rng(10)
    survey, _ = simulate_gnssa_array(rng, positions_enu_m=TRIANGLE, n_pings=60)
    with pytest.raises(ConfigError, match="needs a sound-speed profile"):
        localize_gnssa_array(survey, GnssaArrayOptions(acoustic_model="ray"))
    with pytest.raises(ConfigError, match="needs the array geometry"):
        localize_gnssa_array(survey, GnssaArrayOptions(solution="common_shift"))
    with pytest.raises(ConfigError, match="is none of independent, common_shift"):
        GnssaArrayOptions(solution="both")
    with pytest.raises(ConfigError, match="transponder_speeds_mps needs 3 values"):
        localize_gnssa_array(survey, gnatss_like_options(transponder_speeds_mps=(1500.0,)))
    late = dataclasses.replace(survey, turnaround_s=np.array([0.2, 9.0, 0.2]))
    with pytest.raises(DataError, match="turn-around delay exceeds the travel time"):
        localize_gnssa_array(late, GnssaArrayOptions())


_TIMING_SCRIPT = """
import time
import numpy as np
from oceanloc.estimation.gnssa_array import GnssaArrayOptions, localize_gnssa_array
from oceanloc.sim.gnssa_array import simulate_gnssa_array
truth = np.array([[500.0, 0.0, -2000.0], [-250.0, 433.0, -2010.0], [-250.0, -433.0, -1990.0]])
survey, sim = simulate_gnssa_array(
    np.random.default_rng(12), positions_enu_m=truth, n_pings=10_000, ping_interval_s=3.0,
    drift_ppm_per_h=100.0,
)
localize_gnssa_array(survey, GnssaArrayOptions(), profile=sim.profile)  # imports, caches
start = time.process_time()
res = localize_gnssa_array(survey, GnssaArrayOptions(), profile=sim.profile)
cpu = time.process_time() - start
ok = bool(np.all(np.abs(res.positions_enu_m - truth) < 4.0 * res.sigma_enu_m))
print(survey.n_replies, ok, cpu)
"""


@pytest.mark.slow
def test_ten_thousand_pings_to_three_transponders_land_within_four_sigma():
    """One solve of a large survey with the defaults (ray tracing, sound speed, gradient, noise, outliers,
    jackknife), in a subprocess with single-threaded BLAS. Its CPU time (about 2 s) is a benchmark's
    business (`make bench BENCH=gnatss`), not this test's: the outcome must not depend on the machine."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    out = subprocess.run(
        [sys.executable, "-c", _TIMING_SCRIPT], capture_output=True, text=True, env=env, check=True
    ).stdout.split()
    assert out[:2] == ["30000", "True"]
    assert float(out[2]) > 0.0


def test_defaults_beat_fixed_profile_speeds_when_the_ocean_drifts():
    """An unmodelled drift of the whole profile (150 ppm per hour) and a horizontal gradient: with the
    profile's speeds fixed (GNATSS's settings) the positions are off by decimetres; oceanloc's defaults
    estimate the drift and the gradient and land within a few centimetres, at least 5 times closer."""
    rng = np.random.default_rng(30)
    survey, truth = simulate_gnssa_array(
        rng, positions_enu_m=TRIANGLE, n_pings=500, drift_ppm_per_h=150.0, gradient_per_km=(4e-4, -3e-4)
    )
    ours = localize_gnssa_array(survey, GnssaArrayOptions(), profile=truth.profile)
    fixed = localize_gnssa_array(survey, gnatss_like_options(residual_limit_m=10.0), profile=truth.profile)
    err_ours = np.linalg.norm(ours.positions_enu_m - TRIANGLE, axis=1)
    err_fixed = np.linalg.norm(fixed.positions_enu_m - TRIANGLE, axis=1)
    assert np.all(err_ours < 0.06) and np.all(err_fixed > 0.15), (err_ours, err_fixed)
    assert np.all(5.0 * err_ours < err_fixed)
    # the profile correction found: 150 ppm per hour, within 3 sigma of the knots' spread
    t = ours.knot_times_s
    slope_ppm_h = np.polyfit((t - t[0]) / 3600.0, 1e6 * (ours.speed_scale(t) - 1.0), 1)[0]
    assert slope_ppm_h == pytest.approx(150.0, abs=15.0)
    np.testing.assert_allclose(ours.gradient_per_km, [4e-4, -3e-4], atol=2e-4)


def _selection_survey(seed: int, **kwargs):
    rng = np.random.default_rng(seed)
    return simulate_gnssa_array(rng, positions_enu_m=TRIANGLE, n_pings=300, **kwargs)


def test_model_selection_drops_the_unused_parameters_of_a_drift_free_survey():
    """No drift, no gradient, the sea surface given (the simulation's, height 0): the three nested tests
    drop the gradient, the knots' variation and the constant scale, each statistic below its BIC
    threshold ``dof ln n``; the positions are within 3 sigma and closer than the full model's, whose
    gradient trades with the horizontal position."""
    survey, truth = _selection_survey(50)
    opts = GnssaArrayOptions(surface_height_m=0.0)
    small = localize_gnssa_array(survey, opts, profile=truth.profile)
    full = localize_gnssa_array(survey, dataclasses.replace(opts, select_model=False), profile=truth.profile)
    names = [t.name for t in small.model_tests]
    assert names == ["gradient", "sound_speed_variation", "sound_speed_scale", "gnss_serial_correlation"]
    n = int(small.used.sum())
    for t in small.model_tests[:3]:
        assert t.threshold == pytest.approx(t.dof * np.log(n))
        assert not t.kept and t.statistic < t.threshold, t
    assert small.knot_times_s.size == 0 and small.speed_correction_ppm == pytest.approx(0.0, abs=1e-6)
    np.testing.assert_array_equal(small.gradient_per_km, [0.0, 0.0])
    # the tested correction is still reported: the constant scale's estimate and sigma, in ppm
    scale = small.model_tests[2]
    assert scale.unit == "ppm" and abs(scale.estimate[0]) < 3.0 * scale.sigma[0]
    err_small = small.positions_enu_m - TRIANGLE
    err_full = full.positions_enu_m - TRIANGLE
    assert np.all(np.abs(err_small) < 3.0 * small.sigma_enu_m)
    assert np.linalg.norm(err_small) < np.linalg.norm(err_full)
    assert [t.name for t in full.model_tests] == ["gnss_serial_correlation"] and full.knot_times_s.size > 1
    rec = small.to_record()["model_tests"]
    assert [r["kept"] for r in rec[:3]] == [False, False, False]


def test_model_selection_keeps_a_drift_and_a_gradient():
    """A drift of 150 ppm per hour and a gradient of (4e-4, -3e-4) per km: both tests keep them, with
    statistics far above their thresholds, and the gradient is recovered within 3 sigma."""
    survey, truth = _selection_survey(51, drift_ppm_per_h=150.0, gradient_per_km=(4e-4, -3e-4))
    res = localize_gnssa_array(survey, GnssaArrayOptions(surface_height_m=0.0), profile=truth.profile)
    tests = {t.name: t for t in res.model_tests}
    assert tests["gradient"].kept and tests["gradient"].statistic > 5.0 * tests["gradient"].threshold
    variation = tests["sound_speed_variation"]
    assert variation.kept and variation.statistic > 10.0 * variation.threshold
    assert "sound_speed_scale" not in tests  # the knots stayed: the constant scale is not tested
    assert res.knot_times_s.size > 1
    assert np.all(np.abs(res.gradient_per_km - [4e-4, -3e-4]) < 3.0 * res.gradient_sigma_per_km)


def test_model_selection_keeps_the_scale_when_the_sea_surface_is_a_guess():
    """Without ``surface_height_m`` the profile's depth zero defaults to the mean transducer height (1.5 m
    above the simulation's surface here): an error collinear with depth, absorbed by the constant
    scale, which is therefore not tested; the BIC and chi-square criteria are both available."""
    survey, truth = _selection_survey(50)
    res = localize_gnssa_array(survey, GnssaArrayOptions(), profile=truth.profile)
    assert [t.name for t in res.model_tests][:2] == ["gradient", "sound_speed_variation"]
    assert "sound_speed_scale" not in [t.name for t in res.model_tests]
    assert res.knot_times_s.size == 1
    lr = localize_gnssa_array(survey, GnssaArrayOptions(selection_criterion="lr"), profile=truth.profile)
    assert lr.model_tests[0].threshold == pytest.approx(chi2.ppf(0.99, 2))
    with pytest.raises(ConfigError, match="selection_criterion 'aic' is none of bic, lr"):
        GnssaArrayOptions(selection_criterion="aic")


def test_serial_correlation_test_tells_white_from_correlated_residuals():
    """Ljung-Box on 10 lags per transponder: white normalized residuals are not flagged, an AR(1) series
    with coefficient 0.5 (GNSS errors correlated from ping to ping) is, far above the 1 % quantile; too
    few replies keep the conservative answer (correlated)."""
    survey, _ = _selection_survey(52)
    rng = np.random.default_rng(53)
    m = survey.n_replies
    used = np.ones(m, dtype=bool)
    sigma = np.full(m, 0.02)
    white = serial_correlation_test(survey, 0.02 * rng.standard_normal(m), sigma, used)
    assert not white.kept and white.dof == 30 and white.statistic < white.threshold
    ar = np.zeros(m)
    for j in range(survey.n_transponders):
        sel = np.flatnonzero(survey.reply_transponder == j)
        sel = sel[np.argsort(survey.t_transmit_s[survey.reply_ping[sel]], kind="stable")]
        e = rng.standard_normal(sel.size)
        for k in range(1, sel.size):
            e[k] += 0.5 * e[k - 1]
        ar[sel] = 0.02 * e
    corr = serial_correlation_test(survey, ar, sigma, used)
    assert corr.kept and corr.statistic > 5.0 * corr.threshold
    few = serial_correlation_test(survey, ar, sigma, np.arange(m) < 100)
    assert few.kept and few.dof == 0


def test_gnss_common_mode_follows_the_serial_test_unless_forced():
    """White GNSS noise (the simulation's): no common-mode term by default; True forces it, and it then
    adds the mean antenna covariance to the shift."""
    survey, truth = _selection_survey(50)
    geometry = ArrayGeometry(positions_enu_m=TRIANGLE + 0.3)
    auto = localize_gnssa_array(
        survey, GnssaArrayOptions(solution="common_shift"), profile=truth.profile, geometry=geometry
    )
    assert not auto.model_tests[-1].kept and np.all(auto.covariance_gnss_m2 == 0.0)
    forced = localize_gnssa_array(
        survey,
        GnssaArrayOptions(solution="common_shift", gnss_common_mode=True),
        profile=truth.profile,
        geometry=geometry,
    )
    assert forced.model_tests[-1].name != "gnss_serial_correlation"
    np.testing.assert_allclose(np.diag(forced.covariance_gnss_m2)[:3], [0.02**2, 0.02**2, 0.04**2], rtol=0.01)
