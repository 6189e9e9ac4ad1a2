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


def test_records_and_dataset_of_a_monte_carlo(scenario):
    import json

    result = survey_monte_carlo(scenario, 5, seed=8)
    record = result.to_record()
    json.dumps(record, allow_nan=False)  # plain JSON, no numpy
    assert record["planner"] == "k1" and record["planner_label"] == "k = 1"
    assert len(record["rmsee_m"]) == 6 and len(record["rmsee_m"][0]) == 4
    cons = record["consistency_by_epoch"]
    assert cons["dof"] == 12 and cons["chi2_quantile"] == pytest.approx(21.026, abs=1e-3)
    np.testing.assert_allclose(cons["mean_nees"], result.nees.mean(axis=0))
    ds = result.to_dataset()
    assert dict(ds.sizes) == {"epoch": 6, "transponder": 4, "run": 5}
    assert all("units" in ds[v].attrs and "long_name" in ds[v].attrs for v in ds.data_vars)
    np.testing.assert_array_equal(ds["nees"].values, result.nees)
    np.testing.assert_array_equal(ds["log_det_mean"].values, result.log_det.mean)


def test_planners_dataset_stacks_planners_per_group(scenario):
    from oceanloc.evaluation.survey import planners_dataset

    studies = [survey_monte_carlo(scenario.with_overrides(planner=p), 3, seed=8) for p in ("k0", "k1")]
    ds = planners_dataset({"M4": studies})
    assert list(ds["planner_M4"].values) == ["k0", "k1"]
    assert ds["M4_rmsee"].dims == ("planner_M4", "epoch", "transponder_M4")
    assert ds["M4_rmsee"].attrs["units"] == "m"


def test_single_survey_record_is_plain_json():
    import json

    from oceanloc.evaluation.survey import single_survey

    survey = single_survey(load_survey_scenario("garcia2018-greedy-m4").with_overrides(epochs=4), seed=1)
    record = survey.to_record()
    json.dumps(record, allow_nan=False)
    assert record["planner"] == "greedy" and len(record["transponders"]) == 4
    assert len(record["sites_enu_m"]) == 4 and record["nees_dof"] == 12
