"""Numerical honesty of the filters: a non-symmetric or indefinite covariance given to an update comes back
symmetric positive definite with a non-negative NIS and ``repaired`` set; a valid one is used as it is."""

import numpy as np
import pytest

from oceanloc.estimation.gaussian import Gaussian, repair_covariance
from oceanloc.estimation.kalman import ekf_update, ekf_update_sequential, kf_update
from oceanloc.estimation.unscented import SigmaPointParams, ukf_predict, ukf_update
from oceanloc.models.measurements import bearing_jacobian, bearing_rad

SENSORS = np.array([[1000.0, 0.0], [0.0, 1000.0], [-1000.0, 0.0]])
GOOD = np.diag([400.0, 300.0, 10.0, 10.0])
BAD_COVARIANCES = {
    "non-symmetric": GOOD + np.array([[0, 150.0, 0, 0], [-150.0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]),
    "indefinite": np.array([[100.0, 300.0, 0, 0], [300.0, 100.0, 0, 0], [0, 0, 10.0, 0], [0, 0, 0, 10.0]]),
    "negative diagonal": np.diag([400.0, -300.0, 10.0, 10.0]),
    "non-symmetric and indefinite": np.array(
        [[100.0, 500.0, 0, 0], [100.0, 100.0, 0, 0], [0, 0, 10.0, 0], [0, 0, 0, -1.0]]
    ),
    "zero": np.zeros((4, 4)),
}
MEAN = np.array([30.0, -20.0, 1.0, 0.5])
TRUTH = np.array([35.0, -10.0, 1.0, 0.5])


def _z() -> np.ndarray:
    return bearing_rad(TRUTH, SENSORS)[None] + np.array([[2e-3, -1e-3, 1.5e-3]])


def _assert_spd(cov: np.ndarray) -> None:
    np.testing.assert_array_equal(cov, np.swapaxes(cov, -1, -2))
    assert np.all(np.linalg.eigvalsh(cov) > 0.0)
    np.linalg.cholesky(cov)  # does not raise


def _updates(p: np.ndarray, r: np.ndarray) -> dict:
    state = Gaussian(mean=MEAN[None], cov=p[None])
    hx, jac = (lambda x: bearing_rad(x, SENSORS)), (lambda x: bearing_jacobian(x, SENSORS))
    am = np.ones(3, bool)
    ukf_hx = lambda x: bearing_rad(x, SENSORS)  # noqa: E731
    return {
        "ekf": ekf_update(state, _z(), hx, jac, r, angle_mask=am),
        "ekf sequential": ekf_update_sequential(state, _z(), hx, jac, np.diag(r), angle_mask=am),
        "ukf": ukf_update(state, _z(), ukf_hx, r, SigmaPointParams(alpha=1e-3), angle_mask=am),
        "ukf alpha 0.5": ukf_update(state, _z(), ukf_hx, r, SigmaPointParams(alpha=0.5), angle_mask=am),
    }


@pytest.mark.parametrize("name", BAD_COVARIANCES)
def test_a_bad_prediction_covariance_is_repaired_and_flagged(name: str):
    for kind, res in _updates(BAD_COVARIANCES[name], 1e-4 * np.eye(3)).items():
        assert res.repaired.tolist() == [True], (name, kind)
        _assert_spd(res.state.cov[0])
        assert np.all(res.nis >= 0.0) and np.all(np.isfinite(res.state.mean)), (name, kind)


def test_an_indefinite_measurement_noise_is_repaired_and_flagged():
    r = np.diag([1e-4, -1e-4, 1e-4])
    for kind, res in _updates(GOOD, r).items():
        if kind == "ekf sequential":  # one scalar variance at a time: S = h P h^T + r > 0 here anyway
            continue
        assert res.repaired.tolist() == [True], kind
        _assert_spd(res.state.cov[0])
        _assert_spd(res.innovation_cov[0])
        assert res.nis[0] >= 0.0


def test_a_valid_covariance_is_used_as_it_is_and_not_flagged():
    for kind, res in _updates(GOOD, 1e-4 * np.eye(3)).items():
        assert res.repaired.tolist() == [False], kind
        _assert_spd(res.state.cov[0])
    # Linear update against the textbook formulas: bit for bit the unrepaired arithmetic, to round-off.
    h = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    r = np.diag([4.0, 9.0])
    res = kf_update(Gaussian(mean=MEAN[None], cov=GOOD[None]), np.array([[31.0, -18.0]]), h, r)
    s = h @ GOOD @ h.T + r
    k = GOOD @ h.T @ np.linalg.inv(s)
    np.testing.assert_allclose(res.state.cov[0], (np.eye(4) - k @ h) @ GOOD, rtol=1e-12, atol=1e-12)
    assert res.nis[0] == pytest.approx(1.0 / 404.0 + 4.0 / 309.0, rel=1e-12)


def test_the_old_failure_negative_nis_and_indefinite_posteriors_are_gone():
    """The issue's case: with P indefinite, S = H P H^T + R was indefinite, the NIS negative, and the
    posterior kept a negative eigenvalue while ``repaired`` said False (EKF) or True (UKF)."""
    p = BAD_COVARIANCES["indefinite"]
    h = np.array([[1.0, 1.0, 0, 0]]) / np.sqrt(2.0)
    res = kf_update(Gaussian(mean=MEAN[None], cov=p[None]), np.array([[10.0]]), h, np.array([[1.0]]))
    assert (h @ p @ h.T)[0, 0] == pytest.approx(400.0) and np.linalg.eigvalsh(p)[0] == pytest.approx(-200.0)
    assert res.repaired[0] and res.nis[0] >= 0.0
    _assert_spd(res.state.cov[0])


def test_ukf_predict_returns_a_positive_definite_covariance_for_a_bad_prior():
    state = Gaussian(
        mean=np.zeros((2, 4)), cov=np.stack([GOOD, BAD_COVARIANCES["non-symmetric and indefinite"]])
    )
    pred = ukf_predict(state, lambda x: x, np.zeros((4, 4)), SigmaPointParams(alpha=0.5))
    np.testing.assert_array_equal(pred.repaired, [False, True])
    for cov in pred.state.cov:
        _assert_spd(cov)


def test_repair_covariance_keeps_valid_matrices_bit_for_bit():
    mats = np.stack([GOOD, *BAD_COVARIANCES.values(), np.full((4, 4), np.nan)])
    out, flags = repair_covariance(mats)
    assert flags.tolist() == [False, True, True, True, True, True, True]
    np.testing.assert_array_equal(out[0], GOOD)
    for cov in out[1:-1]:
        _assert_spd(cov)
    # Symmetrizing is enough for the non-symmetric but definite one: its symmetric part, unchanged.
    np.testing.assert_allclose(out[1], GOOD, rtol=0, atol=1e-12)
    assert np.all(np.isnan(out[-1]))  # nothing can repair NaN: returned as it is, and flagged
