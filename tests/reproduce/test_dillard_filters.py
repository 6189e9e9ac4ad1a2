"""Table 2 reproduction on a shortened scenario (the full one is the `oceanloc reproduce` command)."""

import dataclasses

import numpy as np
import pytest

from oceanloc.config.flock import load_flock_scenario
from oceanloc.reproduce.dillard_filters import THESIS_TABLE_2, reproduce_dillard_filters


@pytest.fixture(scope="module")
def short():
    # 30 s at a 0.02 s step (the full scenario is 350 s at 0.005 s): the same effects, 60x cheaper.
    sc = load_flock_scenario("dillard-filters").with_overrides(duration_s=30.0, dt_s=0.02)
    return reproduce_dillard_filters(sc, runs=4, chunk_size=4)


def test_record_has_the_thesis_values_beside_ours(short):
    record = short.to_record()
    assert record["runs"] == 4 and record["thesis_applies"] is True
    assert set(record["filters"]) == {"ekf", "ukf", "ekf-control", "ukf-control"}
    assert record["thesis_table_2"] == THESIS_TABLE_2
    rows = {r["state"]: r for r in record["table_2"]}
    assert rows["X"]["thesis_ekf"] == 765.7431 and rows["V"]["thesis_delta"] == pytest.approx(3.544)
    for values in record["filters"].values():
        assert values["rmse_over_sqrt_pcrlb"] > 0 and values["step_time_s"] > 0


def test_ukf_beats_ekf_through_the_motion_model(short):
    # Paired over the same noise: the thesis' UKF (listing motion) has a lower position MSE than its EKF
    # (Phi of the full CA chain), by many paired standard errors; with the same motion model the two filters
    # agree within 2% (alpha = 1e-3 makes the unscented transform a local, nearly linear one).
    mc = short.monte_carlo
    d, se = mc.paired_position_difference("ekf", "ukf")
    assert d > 3 * se
    same = mc.variants["ekf-control"].position_mse_m2 / mc.variants["ukf"].position_mse_m2
    assert same == pytest.approx(1.0, abs=0.02)
    assert [c.passed for c in short.checks] == [True, True, True]


def test_filters_are_above_the_bound(short):
    for v in short.monte_carlo.variants.values():
        assert v.rmse_over_sqrt_pcrlb > 1.0
        assert v.nees_mean > 6  # overconfident: the thesis' R (1 mrad) is far below the 31.6 mrad noise
    assert short.monte_carlo.pcrlb_position_m2.shape == short.monte_carlo.times_s.shape


def test_another_scenario_gets_no_thesis_values():
    sc = load_flock_scenario("dillard-filters")
    sc = dataclasses.replace(sc, name="my-ring", duration_s=2.0)
    res = reproduce_dillard_filters(sc, runs=2, controls=False)
    assert res.is_thesis is False
    assert all(r.thesis_ekf is None and r.thesis_delta is None for r in res.rows)
    record = res.to_record()
    assert "thesis_table_2" not in record and record["thesis_applies"] is False
    assert [c.name for c in res.checks] == ["every filter's position RMSE is at or above sqrt(PCRLB)"]
    assert np.isfinite(res.rows[0].delta)
