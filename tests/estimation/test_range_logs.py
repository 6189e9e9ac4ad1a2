"""Beacon localization from GPS + USBL logs: white (journal) and Gauss-Markov GPS error models."""

from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.estimation.range_logs import CorrelatedRangeProblem, localize_beacons
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


def test_correlated_problem_whitens_with_the_gauss_markov_covariance():
    rng = np.random.default_rng(0)
    sensors = np.column_stack([rng.uniform(-20, 20, (12, 2)), np.zeros(12)])
    t = np.arange(12) * 3.0
    point = np.array([1.0, 2.0, -1.5])
    ranges = np.linalg.norm(sensors - point, axis=1) + 0.1
    used = np.ones(12, dtype=bool)
    used[4] = False
    p = CorrelatedRangeProblem.at(
        point,
        sensors,
        ranges,
        t,
        used,
        sigma_white_m=0.1,
        sigma_gps_enu_m=np.array([1.0, 1.0, 0.5]),
        correlation_s=60.0,
    )
    h = (point - sensors[used]) / np.linalg.norm(point - sensors[used], axis=1)[:, None]
    tu = t[used]
    cov = (h * [1.0, 1.0, 0.25]) @ h.T * np.exp(-np.abs(tu[:, None] - tu) / 60.0) + 0.01 * np.eye(11)
    np.testing.assert_allclose(p.chol @ p.chol.T, cov, rtol=1e-12, atol=1e-14)
    resid, jac = p.evaluate(point[None], np.array([0]))
    # whitened residuals r^T C^-1 r and information J^T C^-1 J
    r = np.full(11, 0.1)
    assert resid[0] @ resid[0] == pytest.approx(r @ np.linalg.solve(cov, r), rel=1e-10)
    np.testing.assert_allclose(jac[0].T @ jac[0], -h.T @ np.linalg.solve(cov, -h), rtol=1e-10)


def test_gps_part_must_be_below_the_total_sigma(tmp_path: Path):
    logs = simulate_pier_logs(tmp_path, PierLogSettings(duration_s=600.0), np.random.default_rng(1))
    aligned = align_ranges(read_nmea(logs.nmea_path), read_usbl(logs.ranges_path))
    with pytest.raises(ConfigError, match="below sigma_range_m"):
        localize_beacons(aligned, sigma_range_m=0.5, sigma_gps_m=1.0)
    with pytest.raises(ConfigError, match="gps_correlation_s must be positive"):
        localize_beacons(aligned, gps_correlation_s=0.0)
