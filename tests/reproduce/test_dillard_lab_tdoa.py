"""Lab TDOA reproduction on a shortened run."""

import numpy as np
import pytest

from oceanloc.config.flock import load_flock_scenario
from oceanloc.errors import ConfigError
from oceanloc.reproduce.dillard_lab_tdoa import reproduce_dillard_lab_tdoa


def test_short_lab_run_statistics():
    sc = load_flock_scenario("dillard-lab-tdoa").with_overrides(duration_s=6.0)
    res = reproduce_dillard_lab_tdoa(sc, runs=2)
    # Injected noise: mean |N(0, s^2)| = s sqrt(2/pi) = 1.128 ms; its SE over 2 x 1200 x 3 draws is
    # s sqrt(1 - 2/pi) / sqrt(7200) = 0.9% of the mean; allow 4 SE.
    assert np.mean(res.mean_abs_noise_s) == pytest.approx(1.4142e-3 * np.sqrt(2 / np.pi), rel=0.036)
    # The filter's R is half the injected variance: NIS / dof ~ 2 (SE ~3% per run).
    assert np.mean(res.nis_ratio) == pytest.approx(2.0, rel=0.15)
    assert res.residual_m.shape == res.hdop_m.shape == (2, res.times_s.size)
    assert np.all(np.isfinite(res.pearson)) and np.all(np.abs(res.spearman) <= 1)
    payload = res.to_json()
    assert payload["thesis_mse_x_m2"] == 0.21 and payload["runs"] == 2


def test_lab_needs_tdoa():
    sc = load_flock_scenario("dillard-filters")
    with pytest.raises(ConfigError, match="TDOA"):
        reproduce_dillard_lab_tdoa(sc, runs=1)
