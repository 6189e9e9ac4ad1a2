"""KF and EKF steps: FilterPy agreement, Joseph form, missing and sequential measurements."""

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter, KalmanFilter

from oceanloc.estimation.gaussian import Gaussian
from oceanloc.estimation.kalman import ekf_update, ekf_update_sequential, kf_update, predict
from oceanloc.models.measurements import bearing_jacobian, bearing_rad, wrap_angle_rad
from oceanloc.models.motion import constant_acceleration, constant_velocity

SENSORS = np.array([[1000.0, 0.0], [0.0, 1000.0], [-1000.0, 0.0], [0.0, -1000.0]])


def test_ekf_matches_filterpy_on_six_state_bearings():
    # Thesis' 6-state CA model and four bearings; FilterPy's EKF uses the Joseph form too, and is given
    # the same wrapped residual. Agreement to 1e-8 relative to the state's scale.
    motion = constant_acceleration(1.0).with_process_noise(1e-2 * np.diag([10, 10, 1, 1, 1, 1]))
    r = 0.01**2 * np.eye(4)
    x0 = np.array([100.0, 100.0, 20.0, 20.0, 0.0, 0.0])
    p0 = np.diag([100.0, 100.0, 10.0, 10.0, 1.0, 1.0]) ** 2
    ref = ExtendedKalmanFilter(6, 4)
    ref.x, ref.P, ref.F, ref.Q, ref.R = x0.copy(), p0.copy(), motion.transition, motion.process_noise, r
    ours = Gaussian.from_single(x0, p0)
    rng = np.random.default_rng(0)
    truth = np.array([0.0, 0.0, 10.0, 2.0, 0.0, 0.0])
    for _ in range(60):
        truth = motion.transition @ truth
        z = bearing_rad(truth, SENSORS) + 0.01 * rng.standard_normal(4)
        ref.predict()
        ref.update(
            z,
            lambda x: bearing_jacobian(x, SENSORS),
            lambda x: bearing_rad(x, SENSORS),
            residual=lambda a, b: wrap_angle_rad(a - b),
        )
        ours = ekf_update(
            predict(ours, motion),
            z[None],
            lambda x: bearing_rad(x, SENSORS),
            lambda x: bearing_jacobian(x, SENSORS),
            r,
            angle_mask=np.ones(4, bool),
        ).state
        np.testing.assert_allclose(ours.mean[0], ref.x, rtol=0, atol=1e-8 * 1000)
        np.testing.assert_allclose(ours.cov[0], ref.P, rtol=1e-8, atol=1e-8 * np.abs(ref.P).max())


def test_kf_matches_filterpy_kalman_filter():
    motion = constant_velocity(0.5, 0.2)
    h = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    r = np.diag([4.0, 9.0])
    ref = KalmanFilter(4, 2)
    ref.x, ref.P, ref.F, ref.Q, ref.H, ref.R = (
        np.zeros(4),
        25 * np.eye(4),
        motion.transition,
        motion.process_noise,
        h,
        r,
    )
    ours = Gaussian.from_single(np.zeros(4), 25 * np.eye(4))
    rng = np.random.default_rng(1)
    for _ in range(30):
        z = rng.normal(size=2) * 3
        ref.predict()
        ref.update(z)
        ours = kf_update(predict(ours, motion), z[None], h, r).state
    np.testing.assert_allclose(ours.mean[0], ref.x, atol=1e-10)
    np.testing.assert_allclose(ours.cov[0], ref.P, atol=1e-10)


def test_joseph_form_stays_symmetric_positive_definite_with_tiny_noise():
    # A nearly noise-free measurement of a large-prior state: the simple (I - KH) P loses symmetry and
    # definiteness in round-off; the Joseph form keeps every eigenvalue non-negative.
    state = Gaussian.from_single(np.zeros(4), np.diag([1e8, 1e8, 1e2, 1e2]))
    h = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    for _ in range(50):
        state = kf_update(state, np.array([[1.0, 2.0]]), h, 1e-12 * np.eye(2)).state
    assert np.all(np.linalg.eigvalsh(state.cov) >= 0)
    np.testing.assert_array_equal(state.cov, np.swapaxes(state.cov, 1, 2))


def test_missing_measurements_equal_dropping_rows():
    rng = np.random.default_rng(5)
    prior = Gaussian.from_single([30.0, -20.0, 1.0, 0.0], np.diag([400.0, 400.0, 4.0, 4.0]), 3)
    z = bearing_rad(np.array([35.0, -10.0]), SENSORS) + 0.01 * rng.standard_normal(4)
    zs = np.tile(z, (3, 1))
    zs[1, 2] = np.nan  # track 1 loses sensor 2
    zs[2, :] = np.nan  # track 2 hears nothing
    r = np.diag([1e-4, 2e-4, 3e-4, 4e-4])
    res = ekf_update(
        prior,
        zs,
        lambda x: bearing_rad(x, SENSORS),
        lambda x: bearing_jacobian(x, SENSORS),
        r,
        angle_mask=np.ones(4, bool),
    )
    keep = [0, 1, 3]
    dropped = ekf_update(
        prior[1],
        z[None, keep],
        lambda x: bearing_rad(x, SENSORS[keep]),
        lambda x: bearing_jacobian(x, SENSORS[keep]),
        r[np.ix_(keep, keep)],
        angle_mask=np.ones(3, bool),
    )
    np.testing.assert_allclose(res.state.mean[1], dropped.state.mean[0], rtol=1e-12)
    np.testing.assert_allclose(res.state.cov[1], dropped.state.cov[0], rtol=1e-10)
    assert res.nis[1] == pytest.approx(dropped.nis[0], rel=1e-10)
    np.testing.assert_array_equal(res.dof, [4, 3, 0])
    np.testing.assert_allclose(res.state.mean[2], prior.mean[2])
    np.testing.assert_allclose(res.state.cov[2], prior.cov[2])


def test_sequential_update_equals_batch_for_linear_model():
    prior = Gaussian.from_single([1.0, 2.0, 0.5, -0.5], np.diag([9.0, 4.0, 1.0, 1.0]), 2)
    h = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [1.0, -1.0, 0, 0]])
    var = np.array([0.5, 0.7, 0.9])
    z = np.array([[1.5, 1.0, 0.2], [0.0, np.nan, 1.0]])
    batch = kf_update(prior, z, h, np.diag(var))
    seq = ekf_update_sequential(prior, z, lambda x: x @ h.T, lambda x: np.broadcast_to(h, (2, 3, 4)), var)
    np.testing.assert_allclose(seq.state.mean, batch.state.mean, rtol=1e-12)
    np.testing.assert_allclose(seq.state.cov, batch.state.cov, rtol=1e-10, atol=1e-14)
    # The sequential NIS sums scalar NIS values of whitened innovations: equal to the batch NIS.
    np.testing.assert_allclose(seq.nis, batch.nis, rtol=1e-10)
