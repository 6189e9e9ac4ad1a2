"""The linearization check of range estimates (estimation/consistency.py) on simulated surveys."""

import numpy as np
import pytest
from scipy import stats

from oceanloc.errors import ConfigError
from oceanloc.estimation.consistency import range_linearization_check
from oceanloc.estimation.map_gauss_newton import GaussianPrior, RangeProblem, solve_map

TRUTH = np.array([[17.0, 15.0, -6.0], [-2.0, -1.0, -7.0], [5.0, 5.0, -10.0]])
PRIOR_SIGMA = np.array([100.0, 100.0, 2.0])
SIGMA = 0.12


def _survey(seed, runs, epochs):
    """Three transponders surveyed by a random-yaw track (3 m/s, T = 1 s, yaw rate U(-30, 30) deg/s),
    prior N(truth + noise, diag(100, 100, 2)^2); per epoch the MAP estimate, its NEES and the check."""
    rng = np.random.default_rng(seed)
    b = runs * len(TRUTH)
    yaw = rng.uniform(-np.pi, np.pi, (runs, 1)) + np.cumsum(
        rng.uniform(-1, 1, (runs, max(epochs))) * np.radians(30), axis=1
    )
    track = np.stack([np.cumsum(3 * np.cos(yaw), 1), np.cumsum(3 * np.sin(yaw), 1), 0 * yaw], -1)
    truth = np.tile(TRUTH, (runs, 1))
    sensors = np.repeat(track, len(TRUTH), axis=0)
    ranges = np.linalg.norm(sensors - truth[:, None], axis=-1) + rng.normal(0, SIGMA, sensors.shape[:2])
    mean = truth + rng.normal(0, 1, (b, 3)) * PRIOR_SIGMA
    mean[:, 2] = np.minimum(mean[:, 2], -0.5)
    out = {}
    for n in epochs:
        res = solve_map(
            RangeProblem.build(sensors[:, :n], ranges[:, :n], SIGMA),
            GaussianPrior(mean=mean, cov=np.diag(PRIOR_SIGMA**2)),
        )
        err = res.estimate - truth
        nees = np.einsum("bi,bij,bj->b", err, np.linalg.inv(res.covariance), err)
        check = range_linearization_check(
            res.estimate,
            res.covariance,
            sensors[:, :n],
            ranges[:, :n],
            np.ones((b, n), bool),
            SIGMA,
            mean,
            np.diag(PRIOR_SIGMA**2),
        )
        out[n] = (nees, check)
    return out


def test_flags_overconfident_early_epochs_and_passes_late_ones():
    # Seed 1, 200 runs x 3 transponders (600 estimates). Measured: at epoch 10, 20 % of the estimates
    # have NEES above the 95 % chi-square(3) quantile and the check flags 91 % of them (seed 2: 93 %);
    # at epoch 40 it trusts 86 % of all estimates (seed 2: 87 %) and 95 % of those with NEES below the
    # quantile. Bounds: the measured rates less 4 binomial standard errors (about 0.04 on ~120 flagged
    # estimates, 0.015 on 600).
    out = _survey(1, 200, (10, 40))
    q = stats.chi2.ppf(0.95, 3)
    nees, early = out[10]
    bad = nees > q
    assert bad.mean() > 0.1  # the linearized covariance is overconfident early
    assert np.mean(~early.trusted[bad]) >= 0.75
    nees, late = out[40]
    assert late.trusted.mean() >= 0.8
    assert np.mean(late.trusted[nees <= q]) >= 0.9
    messages = early.messages()
    assert any(m.startswith("ellipse not trusted: over the 95% ellipsoid") for m in messages)
    assert messages[int(np.argmax(early.trusted))] == "ellipse trusted: the range model is linear over it"


def test_linear_model_gives_ratio_one():
    # Ranges from sensors 1 km away along three orthogonal axes: over a 1 m ellipsoid the range model
    # is linear to 1e-3 relative, so every cost ratio is 1 to that order and the statistic ~0.
    p = np.array([[0.0, 0.0, -10.0]])
    sensors = p[:, None, :] + 1000.0 * np.array([[[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]]])
    ranges = np.full((1, 5), 1000.0)
    cov = np.linalg.inv(np.diag([2.0, 2.0, 1.0]) / 0.1**2 + np.eye(3) * 1e-6)
    check = range_linearization_check(
        p, cov[None], sensors, ranges, np.ones((1, 5), bool), 0.1, p, np.eye(3) * 1e6
    )
    np.testing.assert_allclose(check.ratio, 1.0, atol=1e-3)
    assert check.trusted[0] and check.statistic[0] < 1e-3


def test_invalid_band_and_confidence_raise():
    args = (np.zeros((1, 3)), np.eye(3)[None], np.ones((1, 4, 3)), np.ones((1, 4)), np.ones((1, 4), bool))
    with pytest.raises(ConfigError, match="confidence"):
        range_linearization_check(*args, 0.1, np.zeros((1, 3)), np.eye(3), confidence=1.5)
    with pytest.raises(ConfigError, match="band"):
        range_linearization_check(*args, 0.1, np.zeros((1, 3)), np.eye(3), band=(1.5, 2.0))


def test_ratios_are_the_cost_evaluated_point_by_point():
    """The expanded distances (``|p - s|^2 + 2 D.(p - s) + |D|^2``) against the cost evaluated directly at
    each sigma point, on poor and good geometries, some ranges unused: ratios equal to 1e-9."""
    rng = np.random.default_rng(12)
    b, n, d = 6, 40, 3
    sensors = rng.normal(0.0, [5.0, 5.0, 0.1], (b, n, d))
    sensors[:3] *= [[[0.05, 1.0, 1.0]]]  # nearly collinear tracks
    p = rng.normal(0.0, [10.0, 10.0, 1.0], (b, d)) + np.array([0.0, 0.0, -20.0])
    ranges = np.linalg.norm(sensors - p[:, None], axis=-1) + rng.normal(0, SIGMA, (b, n))
    used = rng.random((b, n)) > 0.2
    cov = np.stack([np.diag(rng.uniform(0.01, 4.0, d)) for _ in range(b)])
    mean, p_cov = p + 1.0, np.diag(PRIOR_SIGMA**2)
    check = range_linearization_check(p, cov, sensors, ranges, used, SIGMA, mean, p_cov)
    c = np.sqrt(stats.chi2.ppf(0.95, d))
    info_prior = np.linalg.inv(p_cov)

    def cost(k, x):
        r = (ranges[k] - np.linalg.norm(x - sensors[k], axis=1))[used[k]] / SIGMA
        return 0.5 * r @ r + 0.5 * (x - mean[k]) @ info_prior @ (x - mean[k])

    for k in range(b):
        lam, vec = np.linalg.eigh(cov[k])
        los = (p[k] - sensors[k])[used[k]] / np.linalg.norm(p[k] - sensors[k], axis=1)[used[k], None]
        info = los.T @ los / SIGMA**2 + info_prior
        steps = [s * c * np.sqrt(lam[j]) * vec[:, j] for s in (1.0, -1.0) for j in range(d)]
        want = [(cost(k, p[k] + dx) - cost(k, p[k])) / (0.5 * dx @ info @ dx) for dx in steps]
        np.testing.assert_allclose(check.ratio[k], want, rtol=1e-9)
