"""Posterior Cramer-Rao bound (Tichavsky recursion) and the information behind HDOP."""

import numpy as np

from oceanloc.estimation.bounds import expected_measurement_information, measurement_information, pcrlb
from oceanloc.estimation.gaussian import Gaussian
from oceanloc.estimation.kalman import kf_update, predict
from oceanloc.estimation.tracking import run_filter
from oceanloc.models.motion import constant_velocity
from tests.estimation.flock_cases import SENSORS, consistent_bearing_problem


def test_pcrlb_equals_kalman_covariance_on_a_linear_problem():
    # For linear-Gaussian models the KF is efficient: its covariance is the bound at every epoch.
    motion = constant_velocity(0.5, 0.4)
    h = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    r = np.diag([2.0, 3.0])
    p0 = np.diag([50.0, 50.0, 5.0, 5.0])
    info = np.broadcast_to(measurement_information(h, r), (25, 4, 4))
    bound = pcrlb(p0, motion.transition, motion.process_noise, info)
    state = Gaussian.from_single(np.zeros(4), p0)
    for k in range(25):
        state = kf_update(predict(state, motion), np.zeros((1, 2)), h, r).state
        np.testing.assert_allclose(bound[k], state.cov[0], rtol=1e-9, atol=1e-12)


def test_pcrlb_with_deterministic_motion_and_missing_rows():
    motion = constant_velocity(1.0, 0.0)  # Q = 0: the covariance-form recursion needs no Q^-1
    h = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    avail = np.array([[[True, False]], [[True, True]]])  # (R=2, T=1, m=2)
    info = expected_measurement_information(np.broadcast_to(h, (2, 1, 2, 4)), np.eye(2), avail)
    np.testing.assert_allclose(info[0, :2, :2], np.diag([1.0, 0.5]))
    bound = pcrlb(np.eye(4) * 100.0, motion.transition, motion.process_noise, np.repeat(info, 30, axis=0))
    assert np.all(np.diff(np.trace(bound, axis1=1, axis2=2)) < 0)


def test_filters_on_bearings_are_efficient_at_high_snr():
    # Position MSE over 400 runs against the PCRLB evaluated on the same truth trajectories.
    # At one epoch the relative standard error of the MSE is at most sqrt(2 / 400) = 0.07 (two squared
    # Gaussian components); averaging over correlated epochs cannot make it larger. Allow 3 SE.
    motion, model, init, truth, z = consistent_bearing_problem(400, 40, seed=3)
    info = expected_measurement_information(model.jacobian(truth, SENSORS), model.noise_cov)
    bound = pcrlb(init.cov[0], motion.transition, motion.process_noise, info)
    bound_pos = np.trace(bound[:, :2, :2], axis1=1, axis2=2)
    for filt in ("ekf", "ukf"):
        res = run_filter(filt, init, motion, model, z, np.broadcast_to(SENSORS, (40, 4, 2)))
        mse = np.sum((truth - res.estimates)[..., :2] ** 2, axis=-1).mean(axis=0)
        ratio = mse.mean() / bound_pos.mean()
        assert abs(ratio - 1.0) < 3 * np.sqrt(2 / 400), (filt, ratio)
