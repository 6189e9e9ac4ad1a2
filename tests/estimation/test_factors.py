"""The factor layer: stacking, held components, and the survey's range problem rebuilt on it unchanged."""

from dataclasses import dataclass

import numpy as np
import pytest

from oceanloc.config.survey import load_survey_scenario
from oceanloc.errors import ConfigError
from oceanloc.estimation.factors import (
    DepthFactor,
    FactorGraph,
    HeldModel,
    ParameterBlock,
    ParameterLayout,
    PriorFactor,
    RangeFactor,
)
from oceanloc.estimation.map_gauss_newton import GaussianPrior, MapOptions, RangeProblem, solve_map
from oceanloc.models.measurements import range_jacobian, range_m
from oceanloc.reproduce.garcia2019 import PAPER_RUNS, PAPER_TABLES, TABLE_RMSE_TRANSPONDER, horizon_scenario
from oceanloc.reproduce.survey_tables import table_rows


@dataclass(frozen=True, slots=True)
class LegacyRangeProblem:
    """The survey's range problem as it was before the factor layer (the reference of 'unchanged')."""

    sensor_m: np.ndarray
    ranges_m: np.ndarray
    sigma_m: np.ndarray
    mask: np.ndarray

    @classmethod
    def build(cls, sensor_m, ranges_m, sigma_m, mask=None):
        new = RangeProblem.build(sensor_m, ranges_m, sigma_m, mask)
        return cls(new.sensor_m, new.ranges_m, new.sigma_m, new.mask)

    @property
    def batch_size(self):
        return self.ranges_m.shape[0]

    def evaluate(self, x, rows):
        sensors = self.sensor_m[rows]
        weight = np.where(self.mask[rows], 1.0 / self.sigma_m[rows], 0.0)
        target = x[:, None, :]
        resid = (self.ranges_m[rows] - range_m(target, sensors)) * weight
        jac = range_jacobian(target, sensors) * weight[..., None]
        return resid, jac


def _range_data(seed=0, batch=7, n=9):
    rng = np.random.default_rng(seed)
    sensors = rng.normal(0, 20, (batch, n, 3))
    sensors[..., 2] = 0.0
    truth = rng.normal(0, 10, (batch, 3))
    z = range_m(truth[:, None], sensors) + 0.1 * rng.standard_normal((batch, n))
    mask = rng.random((batch, n)) > 0.2
    return sensors, z, mask, truth


def test_range_problem_on_the_factor_gives_the_same_numbers_bit_for_bit():
    sensors, z, mask, truth = _range_data()
    new, old = RangeProblem.build(sensors, z, 0.1, mask), LegacyRangeProblem.build(sensors, z, 0.1, mask)
    x = truth + 0.5
    rows = np.arange(7)
    for a, b in zip(new.evaluate(x, rows), old.evaluate(x, rows), strict=True):
        np.testing.assert_array_equal(a, b)
    prior = GaussianPrior(mean=truth + 3.0, cov=np.diag([100.0, 100.0, 4.0]))
    r_new, r_old = solve_map(new, prior), solve_map(old, prior)
    for name in ("estimate", "covariance", "iterations", "cost"):
        np.testing.assert_array_equal(getattr(r_new, name), getattr(r_old, name))


def test_range_problem_as_a_one_factor_graph_gives_the_same_numbers():
    sensors, z, mask, truth = _range_data(1)
    problem = RangeProblem.build(sensors, z, 0.1, mask)
    layout = ParameterLayout((ParameterBlock("transponder", ("east", "north", "up"), ("m", "m", "m")),))
    graph = FactorGraph(
        layout, [problem.factor()], [PriorFactor(key="transponder", mean=truth, cov=np.eye(3))]
    )
    rows = np.arange(7)
    for a, b in zip(graph.evaluate(truth + 1.0, rows), problem.evaluate(truth + 1.0, rows), strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(graph.residuals(truth, rows), problem.evaluate(truth, rows)[0])


@pytest.mark.parametrize(("table", "scenario"), [("III", "garcia2019-m1"), ("V", "garcia2019-m4")])
def test_survey_tables_unchanged_by_the_factor_layer(monkeypatch, table, scenario):
    """Tables III and V (k = 0 and the k = 1 planner, 6 runs of 50 epochs) with the legacy problem and with
    the factor-built one: every number the tables are made of is identical."""
    import oceanloc.sim.survey as survey_sim
    from oceanloc.evaluation.survey import survey_monte_carlo

    base = load_survey_scenario(scenario)

    def study():
        return {k: survey_monte_carlo(horizon_scenario(base, k), 6, seed=5) for k in (0, 1)}

    new = study()
    monkeypatch.setattr(survey_sim, "RangeProblem", LegacyRangeProblem)
    old = study()
    for k in (0, 1):
        np.testing.assert_array_equal(new[k].log_det_runs, old[k].log_det_runs)
        np.testing.assert_array_equal(new[k].nees, old[k].nees)
        np.testing.assert_array_equal(new[k].rmsee_m, old[k].rmsee_m)
    rows_new = table_rows(PAPER_TABLES[table], new, TABLE_RMSE_TRANSPONDER[table], PAPER_RUNS)
    rows_old = table_rows(PAPER_TABLES[table], old, TABLE_RMSE_TRANSPONDER[table], PAPER_RUNS)
    assert [r.to_record() for r in rows_new] == [r.to_record() for r in rows_old]


def _two_block_graph():
    sensors, z, mask, truth = _range_data(2, batch=3, n=6)
    layout = ParameterLayout(
        (
            ParameterBlock("a", ("east", "north", "up"), ("m", "m", "m")),
            ParameterBlock("b", ("east", "north", "up"), ("m", "m", "m")),
        )
    )
    f_a = RangeFactor(target="a", ranges_m=z, sigma_m=np.full(z.shape, 0.1), mask=mask, sensor_m=sensors)
    f_b = RangeFactor(
        target="b", ranges_m=z + 1.0, sigma_m=np.full(z.shape, 0.2), mask=mask, sensor_m=sensors
    )
    depth = DepthFactor(beacon="b", depth_m=np.full((3, 1), 12.0), sigma_m=np.full((3, 1), 0.5))
    priors = [PriorFactor(key=k, mean=truth, cov=np.eye(3) * 25.0) for k in ("a", "b")]
    return FactorGraph(layout, [f_a, f_b, depth], priors), truth


def test_stacked_jacobian_matches_central_differences_of_the_stacked_residuals():
    graph, truth = _two_block_graph()
    x = np.concatenate([truth + 1.0, truth - 2.0], axis=1)
    rows = np.arange(3)
    resid, jac = graph.evaluate(x, rows)
    assert resid.shape == (3, graph.rows) and jac.shape == (3, graph.rows, 6)
    np.testing.assert_array_equal(resid, graph.residuals(x, rows))
    eps = 1e-6
    for k in range(6):
        e = np.zeros(6)
        e[k] = eps
        fd = -(graph.residuals(x + e, rows) - graph.residuals(x - e, rows)) / (2 * eps)
        np.testing.assert_allclose(jac[:, :, k], fd, atol=1e-6)
    # block b's columns are zero in block a's rows and vice versa
    assert np.all(jac[:, : graph.factors[0].rows, 3:] == 0.0)
    mean, cov = graph.prior_arrays()
    assert mean.shape == (3, 6) and np.all(cov[:, :3, 3:] == 0.0)


def test_held_model_solves_the_free_components_only():
    graph, truth = _two_block_graph()
    x = np.concatenate([truth + 1.0, truth - 2.0], axis=1)
    held = np.array([False, False, False, True, True, True])
    model = HeldModel(graph, held, x)
    rows = np.arange(3)
    r, j = model.evaluate(truth + 0.3, rows)
    full_r, full_j = graph.evaluate(np.concatenate([truth + 0.3, truth - 2.0], axis=1), rows)
    n_a = graph.factors[0].rows  # the rows of block b's factors depend on held components only: left out
    np.testing.assert_array_equal(r, full_r[:, :n_a])
    np.testing.assert_array_equal(j, full_j[:, :n_a, :3])
    prior = GaussianPrior(mean=truth, cov=np.eye(3) * 25.0)
    res = solve_map(model, prior, MapOptions(surface_z_m=None), initial=truth + 0.3)
    assert np.all(res.converged)
    np.testing.assert_array_equal(model.expand(res.estimate, rows)[:, 3:], x[:, 3:])


def test_graph_refuses_missing_priors_unknown_keys_and_batch_mismatch():
    graph, _ = _two_block_graph()
    with pytest.raises(ConfigError, match="exactly one prior"):
        FactorGraph(graph.layout, graph.factors, graph.priors[:1])
    with pytest.raises(ConfigError, match="no parameter block 'c'"):
        FactorGraph(
            graph.layout,
            [DepthFactor(beacon="c", depth_m=np.ones((3, 1)), sigma_m=np.ones((3, 1)))],
            graph.priors,
        )
    with pytest.raises(ConfigError, match="batch size"):
        FactorGraph(
            graph.layout,
            [DepthFactor(beacon="a", depth_m=np.ones((2, 1)), sigma_m=np.ones((2, 1)))],
            graph.priors,
        )
    with pytest.raises(ConfigError, match="unique"):
        ParameterLayout((graph.layout.blocks[0], graph.layout.blocks[0]))
    with pytest.raises(ConfigError, match="either known sensor positions or a lever-arm block"):
        RangeFactor(target="a", ranges_m=np.ones((1, 1)), sigma_m=np.ones((1, 1)), mask=np.ones((1, 1), bool))
