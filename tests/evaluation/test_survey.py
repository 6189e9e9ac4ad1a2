import dataclasses

import numpy as np
import pytest

from oceanloc.config.survey import PlannerSettings, load_survey_scenario
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.evaluation.survey import survey_monte_carlo


@pytest.fixture(scope="module")
def scenario():
    base = load_survey_scenario("garcia2019-m4")
    return dataclasses.replace(base.with_planner(PlannerSettings(kind="lookahead", horizon=1)), epochs=6)


def _same(a, b):
    np.testing.assert_array_equal(a.rmsee_m, b.rmsee_m)
    np.testing.assert_array_equal(a.log_det.mean, b.log_det.mean)
    np.testing.assert_array_equal(a.log_det.std, b.log_det.std)
    np.testing.assert_array_equal(a.nees, b.nees)
    np.testing.assert_array_equal(a.sites_enu_m, b.sites_enu_m)


def test_same_numbers_whatever_the_chunking_or_executor(scenario):
    ref = survey_monte_carlo(scenario, 7, seed=21)
    _same(ref, survey_monte_carlo(scenario, 7, seed=21, chunk_size=2))
    with open_executor(None, 2) as pool:
        _same(ref, survey_monte_carlo(scenario, 7, seed=21, executor=pool, chunk_size=3))


def test_dask_local_cluster_gives_the_local_result_exactly(scenario):
    ref = survey_monte_carlo(scenario, 5, seed=8)
    with open_executor("local:2") as client_executor:
        distributed = survey_monte_carlo(scenario, 5, seed=8, executor=client_executor, chunk_size=2)
    _same(ref, distributed)


def test_summary_shapes_and_sample_run(scenario):
    mc = survey_monte_carlo(scenario, 4, seed=2)
    assert mc.rmsee_m.shape == (6, 4) and mc.log_det.mean.shape == (6,) and mc.nees.shape == (4, 6)
    assert mc.nees_final.dof == 12
    run = mc.sample_run(3)
    np.testing.assert_array_equal(run.sites_enu_m[0], mc.sites_enu_m[3])
