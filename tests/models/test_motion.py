"""CV and CA motion models: transition from the matrix exponential, matching process noise."""

import numpy as np
import pytest

from oceanloc.models.motion import (
    LinearMotionModel,
    constant_acceleration,
    constant_velocity,
    discretize,
    kinematic_system_matrix,
)


def test_ca_transition_is_the_kinematic_polynomial():
    dt = 0.7
    f = constant_acceleration(dt).transition
    per_axis = np.array([[1, dt, dt**2 / 2], [0, 1, dt], [0, 0, 1]])
    np.testing.assert_allclose(f[0::2, 0::2], per_axis, atol=1e-14)
    np.testing.assert_allclose(f[1::2, 1::2], per_axis, atol=1e-14)
    assert np.all(f[0::2, 1::2] == 0)


@pytest.mark.parametrize("dt", [0.005, 0.5, 3.0])
def test_process_noise_closed_forms(dt):
    q = 0.3
    cv = constant_velocity(dt, q).process_noise
    np.testing.assert_allclose(
        cv[0::2, 0::2], q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]]), rtol=1e-12
    )
    ca = constant_acceleration(dt, q).process_noise
    ref = q * np.array(
        [
            [dt**5 / 20, dt**4 / 8, dt**3 / 6],
            [dt**4 / 8, dt**3 / 3, dt**2 / 2],
            [dt**3 / 6, dt**2 / 2, dt],
        ]
    )
    np.testing.assert_allclose(ca[0::2, 0::2], ref, rtol=1e-10)
    assert np.all(ca[0::2, 1::2] == 0)


def test_noise_matches_monte_carlo_of_the_sde():
    # Euler-Maruyama with 200 sub-steps over one dt: the empirical covariance of 20000 endpoints agrees
    # with Van Loan's Q; each variance's relative standard error is sqrt(2/20000) = 1%, allow 5%.
    dt, q, sub, runs = 1.0, 2.0, 200, 20000
    rng = np.random.default_rng(4)
    a = kinematic_system_matrix(2)
    x = np.zeros((runs, 4))
    h = dt / sub
    for _ in range(sub):
        x = x + h * x @ a.T
        x[:, 2:] += np.sqrt(q * h) * rng.standard_normal((runs, 2))
    emp = np.cov(x.T)
    ref = constant_velocity(dt, q).process_noise
    np.testing.assert_allclose(np.diag(emp), np.diag(ref), rtol=0.05)


def test_discretize_semigroup():
    # Two half steps equal one full step: F(dt) = F(dt/2)^2 and Q(dt) = F Q F^T + Q at dt/2.
    a = kinematic_system_matrix(3)
    g = np.zeros((6, 6))
    g[4:, 4:] = 0.7 * np.eye(2)
    f1, q1 = discretize(a, g, 2.0)
    fh, qh = discretize(a, g, 1.0)
    np.testing.assert_allclose(f1, fh @ fh, atol=1e-12)
    np.testing.assert_allclose(q1, fh @ qh @ fh.T + qh, rtol=1e-10, atol=1e-12)


def test_model_validation_and_propagation():
    m = constant_velocity(1.0)
    np.testing.assert_allclose(m.propagate(np.array([[1.0, 2.0, 3.0, -1.0]])), [[4.0, 1.0, 3.0, -1.0]])
    assert m.with_process_noise(np.eye(4)).process_noise[0, 0] == 1.0
    with pytest.raises(ValueError, match="symmetric"):
        LinearMotionModel(transition=np.eye(2), process_noise=np.array([[1.0, 0.5], [0.0, 1.0]]), dt_s=1.0)
    with pytest.raises(ValueError, match="positive"):
        constant_velocity(0.0)
