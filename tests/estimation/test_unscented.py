"""UKF steps: FilterPy agreement, linear problem = KF, angles on the circle, Cholesky fallback."""

import numpy as np
import pytest
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

from oceanloc.errors import ConfigError
from oceanloc.estimation.gaussian import Gaussian, robust_cholesky
from oceanloc.estimation.kalman import ekf_update, kf_update, predict
from oceanloc.estimation.unscented import SigmaPointParams, sigma_points, ukf_predict, ukf_update
from oceanloc.models.measurements import bearing_rad, wrap_angle_rad
from oceanloc.models.motion import constant_acceleration, constant_velocity

SENSORS = np.array([[1000.0, 0.0], [0.0, 1000.0], [-1000.0, 0.0], [0.0, -1000.0]])
ANGLES = np.ones(4, dtype=bool)


def _centred_mean(sigmas, wm):
    return sigmas[0] + wm @ (sigmas - sigmas[0])


def _circular_mean(sigmas, wm):
    return wrap_angle_rad(sigmas[0] + wm @ wrap_angle_rad(sigmas - sigmas[0]))


def test_sigma_point_weights_are_the_thesis_listing():
    # Appendix B: lambda = alpha^2 (L + kappa) - L, Wm = [lambda/c, 0.5/c ...], Wc(1) += 1 - alpha^2 + beta.
    wm, wc = SigmaPointParams().weights(6)
    lam = 1e-6 * 6 - 6
    assert wm[0] == pytest.approx(lam / (6 + lam)) and wm[1] == pytest.approx(0.5 / (6 + lam))
    assert wc[0] == pytest.approx(wm[0] + 1 - 1e-6 + 2)
    assert wm.sum() == pytest.approx(1.0, abs=1e-9)
    ref = MerweScaledSigmaPoints(6, alpha=1e-3, beta=2.0, kappa=0.0)
    np.testing.assert_allclose(wm, ref.Wm, rtol=1e-14)
    np.testing.assert_allclose(wc, ref.Wc, rtol=1e-14)
    with pytest.raises(ConfigError, match="alpha"):
        SigmaPointParams(alpha=0.0)


@pytest.mark.parametrize("alpha", [1e-3, 0.3])
def test_ukf_matches_filterpy_on_six_state_bearings(alpha):
    # Identical configuration: same sigma-point parameters, FilterPy given our centred state mean,
    # circular measurement mean and wrapped residual. FilterPy redraws the sigma points after predict, as
    # our update does by default. With alpha = 1e-3 the weights are ~1e6 and both sides carry round-off of
    # ~1e-16 * 1e6 * |x|; agreement to 1e-8 relative to the state scale (1000 m).
    motion = constant_acceleration(1.0).with_process_noise(1e-2 * np.diag([10, 10, 1, 1, 1, 1]))
    r = 0.01**2 * np.eye(4)
    params = SigmaPointParams(alpha=alpha, beta=2.0, kappa=0.0)
    x0 = np.array([100.0, 100.0, 20.0, 20.0, 0.0, 0.0])
    p0 = np.diag([100.0, 100.0, 10.0, 10.0, 1.0, 1.0]) ** 2
    ref = UnscentedKalmanFilter(
        6,
        4,
        1.0,
        hx=lambda x: bearing_rad(x, SENSORS),
        fx=lambda x, dt: motion.transition @ x,
        points=MerweScaledSigmaPoints(6, alpha=alpha, beta=2.0, kappa=0.0),
        x_mean_fn=_centred_mean,
        z_mean_fn=_circular_mean,
        residual_z=lambda a, b: wrap_angle_rad(a - b),
    )
    ref.x, ref.P, ref.Q, ref.R = x0.copy(), p0.copy(), motion.process_noise, r
    ours = Gaussian.from_single(x0, p0)
    rng = np.random.default_rng(0)
    truth = np.array([0.0, 0.0, 10.0, 2.0, 0.0, 0.0])
    for _ in range(60):
        truth = motion.transition @ truth
        z = bearing_rad(truth, SENSORS) + 0.01 * rng.standard_normal(4)
        ref.predict()
        ref.update(z)
        pred = ukf_predict(ours, lambda x: x @ motion.transition.T, motion.process_noise, params)
        upd = ukf_update(pred.state, z[None], lambda x: bearing_rad(x, SENSORS), r, params, angle_mask=ANGLES)
        ours = upd.state
        np.testing.assert_allclose(ours.mean[0], ref.x, rtol=0, atol=1e-8 * 1000)
        np.testing.assert_allclose(ours.cov[0], ref.P, rtol=0, atol=1e-8 * np.abs(ref.P).max())
        np.testing.assert_allclose(upd.innovation[0], ref.y, atol=1e-8)


@pytest.mark.parametrize("alpha", [1e-3, 0.5, 1.0])
def test_kf_ekf_ukf_agree_on_a_linear_problem(alpha):
    motion = constant_velocity(1.0, 0.3)
    h = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0.5, 0.5, 1.0, 0]])
    r = np.diag([4.0, 2.0, 1.0])
    params = SigmaPointParams(alpha=alpha, kappa=3.0 - 4 if alpha == 1.0 else 0.0)
    rng = np.random.default_rng(2)
    z = rng.normal(scale=5.0, size=(3, 20, 3))
    kf = ekf = ukf = Gaussian.from_single([1.0, -1.0, 0.5, 0.2], np.diag([25.0, 25.0, 4.0, 4.0]), 3)
    for k in range(20):
        kf = kf_update(predict(kf, motion), z[:, k], h, r).state
        ekf = ekf_update(
            predict(ekf, motion), z[:, k], lambda x: x @ h.T, lambda x: np.broadcast_to(h, (3, 3, 4)), r
        ).state
        pred = ukf_predict(ukf, lambda x: x @ motion.transition.T, motion.process_noise, params)
        ukf = ukf_update(pred.state, z[:, k], lambda x: x @ h.T, r, params).state
    np.testing.assert_allclose(ekf.mean, kf.mean, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ukf.mean, kf.mean, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(ukf.cov, kf.cov, rtol=1e-8, atol=1e-8)


def _rotate(theta):
    return np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])


def test_bearings_across_pi_are_handled_on_the_circle():
    # One sensor east of the target sees it at ~180 degrees: sigma points straddle +-pi. The same geometry
    # rotated by 90 degrees has no wrap. Rotation invariance: the posteriors must be rotations of each other.
    sensors = np.array([[400.0, 0.0], [0.0, 400.0]])
    prior = Gaussian.from_single([0.0, 0.0, 0.0, 0.0], np.diag([400.0, 400.0, 1.0, 1.0]))
    truth = np.array([-5.0, 8.0])
    z = bearing_rad(truth, sensors)
    assert z[0] > 3.1  # measured just below +pi, predictions at the mean are exactly pi
    r = 1e-4 * np.eye(2)
    params = SigmaPointParams(alpha=0.5)
    out = ukf_update(
        prior, z[None], lambda x: bearing_rad(x, sensors), r, params, angle_mask=np.ones(2, bool)
    )
    rot = _rotate(np.pi / 2)
    rot4 = np.kron(np.eye(2), rot)
    sensors_r = sensors @ rot.T
    z_r = bearing_rad(truth @ rot.T, sensors_r)
    prior_r = Gaussian(mean=prior.mean @ rot4.T, cov=rot4 @ prior.cov @ rot4.T)
    out_r = ukf_update(
        prior_r, z_r[None], lambda x: bearing_rad(x, sensors_r), r, params, angle_mask=np.ones(2, bool)
    )
    np.testing.assert_allclose(out_r.state.mean[0], rot4 @ out.state.mean[0], atol=1e-9)
    np.testing.assert_allclose(out_r.state.cov[0], rot4 @ out.state.cov[0] @ rot4.T, atol=1e-9)
    assert np.all(np.abs(out.innovation) < 0.2)


def test_non_positive_definite_covariance_is_repaired_and_flagged():
    good = np.diag([4.0, 1.0, 1.0, 1.0])
    bad = np.array([[1.0, 2.0, 0, 0], [2.0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]])  # eigenvalue -1
    state = Gaussian(mean=np.zeros((2, 4)), cov=np.stack([good, bad]))
    pred = ukf_predict(state, lambda x: x, np.zeros((4, 4)), SigmaPointParams(alpha=0.5))
    np.testing.assert_array_equal(pred.repaired, [False, True])
    assert np.all(np.isfinite(pred.state.cov))
    assert np.all(np.linalg.eigvalsh(pred.state.cov[1]) > -1e-12)
    np.testing.assert_allclose(pred.state.cov[0], good, atol=1e-12)
    chol, flags = robust_cholesky(np.stack([good, bad, np.zeros((4, 4))]))
    np.testing.assert_array_equal(flags, [False, True, True])
    assert np.all(np.isfinite(chol))


def test_sigma_points_reproduce_mean_and_covariance():
    rng = np.random.default_rng(8)
    a = rng.normal(size=(5, 6, 6))
    cov = a @ np.swapaxes(a, 1, 2) + np.eye(6)
    state = Gaussian(mean=rng.normal(size=(5, 6)), cov=cov)
    params = SigmaPointParams(alpha=0.1)
    pts, _ = sigma_points(state, params)
    wm, wc = params.weights(6)
    assert pts.shape == (5, 13, 6)
    np.testing.assert_allclose(np.einsum("s,bsi->bi", wm, pts), state.mean, atol=1e-10)
    dev = pts - state.mean[:, None]
    np.testing.assert_allclose(np.einsum("s,bsi,bsj->bij", wc, dev, dev), cov, rtol=1e-8)
