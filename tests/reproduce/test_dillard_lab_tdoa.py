"""Lab TDOA reproduction on a shortened run."""

import dataclasses

import numpy as np
import pytest

from oceanloc.config.flock import load_flock_scenario
from oceanloc.errors import ConfigError
from oceanloc.reproduce.dillard_lab_tdoa import reproduce_dillard_lab_tdoa


def test_short_lab_run_statistics():
    sc = load_flock_scenario("dillard-lab-tdoa").with_overrides(duration_s=6.0)
    res = reproduce_dillard_lab_tdoa(sc, runs=2)
    mc = res.monte_carlo
    # Injected noise: mean |N(0, s^2)| = s sqrt(2/pi) = 1.128 ms; its SE over 2 x 1200 x 3 draws is
    # s sqrt(1 - 2/pi) / sqrt(7200) = 0.9% of the mean; allow 4 SE.
    assert np.mean(mc.mean_abs_noise) == pytest.approx(1.4142e-3 * np.sqrt(2 / np.pi), rel=0.036)
    # The filter's R is half the injected variance: NIS / dof ~ 2 (SE ~3% per run).
    assert np.mean(mc.nis_ratio) == pytest.approx(2.0, rel=0.15)
    assert mc.residual_m.shape == mc.hdop_m.shape == (2, mc.times_s.size)
    assert np.all(np.isfinite(mc.pearson)) and np.all(np.abs(mc.spearman) <= 1)
    record = res.to_record()
    assert record["thesis_mse_x_m2"] == 0.21 and record["runs"] == 2
    assert res.checks[0].passed  # the noise is the thesis' 1.1 ms within 10 %
    assert [r.thesis for r in res.rows][:2] == ["0.21", "0.88"]


def test_another_scenario_gets_no_thesis_values():
    sc = dataclasses.replace(load_flock_scenario("dillard-lab-tdoa"), name="my-lab", duration_s=3.0)
    res = reproduce_dillard_lab_tdoa(sc, runs=1)
    assert not res.is_thesis and all(r.thesis is None for r in res.rows)
    assert "thesis_mse_x_m2" not in res.to_record() and len(res.checks) == 1


def test_lab_needs_tdoa():
    sc = load_flock_scenario("dillard-filters")
    with pytest.raises(ConfigError, match="TDOA"):
        reproduce_dillard_lab_tdoa(sc, runs=1)
