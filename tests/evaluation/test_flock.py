"""Flock Monte Carlo orchestration: chunk independence, records and datasets (short scenarios)."""

import dataclasses
import json

import numpy as np
import pytest

from oceanloc.config.flock import load_flock_scenario
from oceanloc.errors import ConfigError
from oceanloc.evaluation.flock import filter_monte_carlo, filter_variants, tracking_hdop_monte_carlo
from oceanloc.io.records import make_provenance, write_netcdf


@pytest.fixture(scope="module")
def short_filters():
    sc = load_flock_scenario("dillard-filters").with_overrides(duration_s=2.0, runs=3)
    return sc, filter_monte_carlo(sc, filter_variants(sc, controls=False), chunk_size=1)


def test_filter_results_do_not_depend_on_chunking(short_filters):
    sc, one = short_filters
    three = filter_monte_carlo(sc, filter_variants(sc, controls=False), chunk_size=3)
    for key in ("ekf", "ukf"):
        a, b = one.variants[key], three.variants[key]
        np.testing.assert_allclose(a.mse_per_run, b.mse_per_run, rtol=1e-12)
        np.testing.assert_allclose(a.rmse_time, b.rmse_time, rtol=1e-12)
        np.testing.assert_allclose(a.nees_per_run, b.nees_per_run, rtol=1e-12)
        # Equal to rounding: NumPy's stacked matmul may round the last bit differently per batch size.
        np.testing.assert_allclose(a.example_estimates, b.example_estimates, rtol=1e-12, atol=1e-12)
    assert one.variants["ekf"].mse_per_run.shape == (3, 6)
    assert one.variants["ekf"].example_estimates.shape == (one.example_times_s.size, 6)


def test_filter_record_and_dataset(short_filters, tmp_path):
    _, mc = short_filters
    record = mc.to_record()
    assert record["runs"] == 3 and record["seed"] == 2014 and set(record["filters"]) == {"ekf", "ukf"}
    ekf = record["filters"]["ekf"]
    assert ekf["position_mse_m2"] == pytest.approx(ekf["mse_x_m2"] + ekf["mse_y_m2"])
    json.dumps(record)  # plain JSON, no numpy
    ds = mc.to_dataset()
    assert dict(ds.sizes) == {"filter": 2, "run": 3, "epoch": mc.example_times_s.size, "state": 6}
    assert ds["mse"].dims == ("filter", "run", "state") and ds["pcrlb_position"].attrs["units"] == "m2"
    path = write_netcdf(tmp_path / "f.nc", ds, make_provenance(seed=2014, scenario="dillard-filters"))
    assert path.stat().st_size > 0


def test_filter_monte_carlo_needs_a_straight_target():
    with pytest.raises(ConfigError, match="straight"):
        filter_monte_carlo(load_flock_scenario("dillard-lab-tdoa"))


def test_tracking_results_do_not_depend_on_chunking(tmp_path):
    sc = load_flock_scenario("dillard-lab-tdoa").with_overrides(duration_s=3.0, runs=2)
    one = tracking_hdop_monte_carlo(sc, chunk_size=1)
    two = tracking_hdop_monte_carlo(sc, chunk_size=2)
    np.testing.assert_allclose(one.mse_xy_m2, two.mse_xy_m2, rtol=1e-12)
    np.testing.assert_allclose(one.residual_m, two.residual_m, rtol=1e-12)
    np.testing.assert_array_equal(one.truth, two.truth)
    assert one.residual_m.shape == (2, one.times_s.size) and one.truth.shape == (one.times_s.size, 6)
    record = one.to_record()
    assert record["runs"] == 2 and "mean_abs_noise_s" in record
    ds = one.to_dataset()
    assert ds["residual"].dims == ("run", "epoch") and ds["mean_abs_noise"].attrs["units"] == "s"
    write_netcdf(tmp_path / "t.nc", ds)
    with pytest.raises(ConfigError, match="convergence"):
        tracking_hdop_monte_carlo(sc.with_overrides(duration_s=2.0))


def test_a_four_state_constant_velocity_scenario_runs():
    sc = load_flock_scenario("dillard-filters")
    f = dataclasses.replace(
        sc.filters,
        initial_state=sc.filters.initial_state[:4],
        initial_cov=sc.filters.initial_cov[:4, :4],
        process_noise=sc.filters.process_noise[:4, :4],
        ekf_motion="constant-velocity",
        ukf_motion="constant-velocity",
    )
    sc = dataclasses.replace(sc, filters=f, duration_s=1.0, runs=2)
    mc = filter_monte_carlo(sc, filter_variants(sc))
    assert set(mc.variants) == {"ekf", "ukf"}  # no controls when both use the same model
    assert mc.truth.shape == (mc.times_s.size, 4) and mc.variants["ukf"].mse_per_run.shape == (2, 4)
    assert list(mc.to_dataset()["state"].values) == ["x", "y", "u", "v"]


def test_gate_and_divergence_reach_records_and_datasets(tmp_path):
    # The thesis' bearing scenario has R = (1e-3 rad)^2 for noise of 0.0316 rad: NIS ~ 1000 x dof at every
    # epoch, so every run is flagged diverged at its first epoch. With the default gate (0.999) the first
    # 19 epochs are rejected; the 20th completes the streak and the gate reopens (re-acquisition); the
    # block boundary (block = 2000 epochs) does not reset the streak.
    sc = load_flock_scenario("dillard-filters").with_overrides(duration_s=11.0, runs=2)
    sc = dataclasses.replace(sc, filters=dataclasses.replace(sc.filters, gate_probability=0.999))
    mc = filter_monte_carlo(sc, filter_variants(sc, controls=False))
    ekf = mc.to_record()["filters"]["ekf"]
    assert ekf["diverged_runs"] == 2 and ekf["first_divergence_s"] == pytest.approx(sc.dt_s)
    assert ekf["gated_epochs_mean"] == 19 and mc.to_record()["gate_probability"] == 0.999
    ds = mc.to_dataset()
    assert ds["diverged"].values.tolist() == [[1, 1], [1, 1]]
    assert ds["gated_epochs"].attrs["units"] == "1" and ds["divergence_time"].attrs["units"] == "s"
    write_netcdf(tmp_path / "mc.nc", ds, make_provenance(seed=sc.seed))
    lab = load_flock_scenario("dillard-lab-tdoa").with_overrides(duration_s=3.0, runs=2)
    rec = tracking_hdop_monte_carlo(lab, settle_s=1.0).to_record()
    assert rec["gate_probability"] == 0.0 and rec["gated_epochs"]["mean"] == 0.0
    assert rec["diverged_runs"] == len(rec["diverged_run_indices"])
