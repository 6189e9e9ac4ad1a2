"""Beacon localization from GPS + USBL logs: white (journal) and Gauss-Markov GPS error models."""

from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.estimation.map_gauss_newton import MapOptions, RangeProblem, solve_map
from oceanloc.estimation.range_logs import (
    CorrelatedRangeProblem,
    beacon_prior,
    localize_beacons,
    robust_white_fit,
)
from oceanloc.io.nmea import read_nmea
from oceanloc.io.usbl import align_ranges, read_usbl
from oceanloc.sim.logs import PIER_ORIGIN, PierLogSettings, simulate_pier_logs


@pytest.mark.slow  # a Monte Carlo of simulated pier logs (15-35 s): `make test-slow`
def test_correlated_gps_model_makes_the_horizontal_covariance_consistent(tmp_path: Path):
    # The simulated DGPS error is Gauss-Markov (1 m, 60 s). Horizontal NEES of beacon 1 over 8 seeded
    # 20-minute logs: chi-square with 2 dof, so the mean of 8 has standard error 2 / sqrt(8) = 0.71;
    # the correlated model's mean must lie within 3 standard errors of 2, the white model's (the
    # journal's) is far above it (measured 44 over 10 seeds).
    white, corr = [], []
    for seed in range(8):
        logs = simulate_pier_logs(
            tmp_path / str(seed),
            PierLogSettings(duration_s=1200.0, bias_m=(0.0, 0.0)),
            np.random.default_rng(seed),
        )
        aligned = align_ranges(read_nmea(logs.nmea_path), read_usbl(logs.ranges_path), origin=PIER_ORIGIN)
        for model, acc in ((None, white), (60.0, corr)):
            est = localize_beacons(aligned, gps_correlation_s=model)[0]
            err = (est.position_enu_m - logs.beacons_enu_m[0])[:2]
            acc.append(err @ np.linalg.solve(est.covariance_m2[:2, :2], err))
    assert abs(np.mean(corr) - 2.0) < 3 * 2.0 / np.sqrt(8)
    assert np.mean(white) > 10.0


def _dense_covariance(point, sensors, t, sigma_white, sigma_gps, tau):
    """The reference: the full n x n covariance h_i D h_j^T exp(-|t_i - t_j| / tau) + s^2 I."""
    h = (point - sensors) / np.linalg.norm(point - sensors, axis=1)[:, None]
    cov = (h * np.square(sigma_gps)) @ h.T * np.exp(-np.abs(t[:, None] - t[None, :]) / tau)
    return cov + sigma_white**2 * np.eye(t.size)


@pytest.mark.parametrize("n, duplicate", [(12, False), (60, False), (40, True)])
def test_banded_gls_equals_the_dense_gauss_markov_covariance(n, duplicate):
    # Sigma^-1 through Woodbury and the banded Cholesky of M = Q + H^T H / s^2 against the dense
    # covariance's Cholesky: the Gram matrix [J r]^T Sigma^-1 [J r] to 1e-9 relative. Times are
    # unsorted, some 0.01 s apart, and (duplicate) two ranges share an epoch (one GPS-error state).
    rng = np.random.default_rng(n)
    sensors = np.column_stack([rng.uniform(-20, 20, (n, 2)), rng.normal(0.0, 0.2, n)])
    t = rng.permutation(np.cumsum(rng.choice([0.01, 1.0, 3.0, 200.0], n)))
    if duplicate:
        t[5] = t[9]
    point = np.array([1.0, 2.0, -1.5])
    ranges = np.linalg.norm(sensors - point, axis=1) + rng.normal(0.0, 0.3, n)
    used = np.ones(n, dtype=bool)
    used[4] = False
    sig_gps = np.array([1.0, 1.0, 0.5])
    p = CorrelatedRangeProblem.at(
        point, sensors, ranges, t, used, sigma_white_m=0.1, sigma_gps_enu_m=sig_gps, correlation_s=60.0
    )
    cov = _dense_covariance(point, sensors[used], t[used], 0.1, sig_gps, 60.0)
    x = point + np.array([0.3, -0.2, 0.1])
    diff = x - sensors[used]
    rho = np.linalg.norm(diff, axis=1)
    v = np.column_stack([diff / rho[:, None], ranges[used] - rho])
    dense = v.T @ np.linalg.solve(cov, v)
    np.testing.assert_allclose(p.gram(x), dense, rtol=1e-9, atol=1e-9 * np.abs(dense).max())
    # The four rows handed to solve_map carry the same cost, gradient (and a Hessian whose GN part is
    # the dense one).
    resid, jac = p.evaluate(x[None], np.array([0]))
    assert resid[0] @ resid[0] == pytest.approx(dense[3, 3], rel=1e-9)
    np.testing.assert_allclose(jac[0].T @ resid[0], dense[:3, 3], rtol=1e-9, atol=1e-9 * dense[3, 3])


def test_white_gps_part_is_plain_weighted_least_squares():
    rng = np.random.default_rng(1)
    sensors = np.column_stack([rng.uniform(-20, 20, (10, 2)), np.zeros(10)])
    point = np.array([1.0, 2.0, -1.5])
    ranges = np.linalg.norm(sensors - point, axis=1) + 0.1
    p = CorrelatedRangeProblem.at(
        point, sensors, ranges, np.arange(10.0), np.ones(10, dtype=bool), sigma_white_m=0.5,
        sigma_gps_enu_m=np.zeros(3), correlation_s=60.0,
    )  # fmt: skip
    assert p.gram(point)[3, 3] == pytest.approx(10 * 0.01 / 0.25, rel=1e-12)


def _original_outlier_rule(sensors, z, sigma, prior, opts, threshold=3.0, fraction=0.25):
    """The authors' rule as first written: a full solve_map after every removal (the reference)."""
    used = np.ones(z.size, dtype=bool)
    x = prior.mean
    for _ in range(int(fraction * z.size) + 1):
        problem = RangeProblem.build(sensors[None], z[None], sigma, used[None])
        res = solve_map(problem, prior, opts, initial=x)
        x = res.estimate
        resid = z - np.linalg.norm(sensors - x[0], axis=1)
        scale = max(np.sqrt(np.mean(resid[used] ** 2)), sigma)
        normalized = np.where(used, np.abs(resid) / scale, 0.0)
        worst = int(np.argmax(normalized))
        if normalized[worst] <= threshold:
            break
        used[worst] = False
    return used, x[0]


@pytest.mark.parametrize("seed, duration_s", [(0, 600.0), (1, 600.0), (2, 1800.0), (3, 3600.0)])
def test_downdated_outlier_rule_excludes_what_the_one_solve_per_removal_rule_excludes(
    tmp_path: Path, seed, duration_s
):
    # On simulated pier logs (5 % multipath outliers of +5..+30 m): the same exclusions, range for range,
    # and, on the same mask, the estimate of a full solve (both are full solves; they differ only where
    # the 10-minute problem has several minima the two paths reach, so positions are compared on the
    # long logs).
    logs = simulate_pier_logs(tmp_path, PierLogSettings(duration_s=duration_s), np.random.default_rng(seed))
    aligned = align_ranges(read_nmea(logs.nmea_path), read_usbl(logs.ranges_path, beacons=(1, 2)))
    surface = float(np.median(aligned.vehicle_enu_m[:, 2]))
    for beacon in (1, 2):
        sel = aligned.select(beacon)
        sensors, z = aligned.vehicle_enu_m[sel], aligned.range_m[sel]
        prior = beacon_prior(sensors, z, surface, (100.0, 100.0, 10.0), 2.0)
        opts = MapOptions(surface_z_m=surface)
        used, x = _original_outlier_rule(sensors, z, 1.006, prior, opts)
        fit = robust_white_fit(sensors, z, 1.006, prior, opts, initial_m=prior.mean[0])
        assert (~used).sum() > 3
        np.testing.assert_array_equal(fit.used, used)
        if duration_s > 1000.0:
            np.testing.assert_allclose(fit.estimate_m, x, atol=1e-4)


def test_gps_part_must_be_below_the_total_sigma(tmp_path: Path):
    logs = simulate_pier_logs(tmp_path, PierLogSettings(duration_s=600.0), np.random.default_rng(1))
    aligned = align_ranges(read_nmea(logs.nmea_path), read_usbl(logs.ranges_path))
    with pytest.raises(ConfigError, match="below sigma_range_m"):
        localize_beacons(aligned, sigma_range_m=0.5, sigma_gps_m=1.0)
    with pytest.raises(ConfigError, match="gps_correlation_s must be positive"):
        localize_beacons(aligned, gps_correlation_s=0.0)
