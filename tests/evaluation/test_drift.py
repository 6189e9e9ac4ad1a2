import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.evaluation.drift import drift_monte_carlo, run_planner, summarize
from tests.planning.drift_fixtures import uniform_problem


def test_monte_carlo_is_independent_of_chunks_and_has_planner_run_dims():
    problems = [uniform_problem(), uniform_problem(goal=(3000.0, 800.0))]
    mc = drift_monte_carlo(problems, 4, 11, planners=("oceanloc", "thesis-single"))
    assert mc.planners == ("oceanloc", "thesis-single") and mc.n_runs == 4
    assert mc.runs["oceanloc"].field.tolist() == [0, 1, 0, 1]
    one = run_planner("oceanloc", problems, 4, 11)
    np.testing.assert_allclose(one.energy_wh, mc.runs["oceanloc"].energy_wh)
    ds = mc.to_dataset()
    assert dict(ds.sizes) == {"planner": 2, "run": 4, "problem_index": 2}
    assert ds["flight_energy"].attrs["units"] == "W h" and ds["compute_time"].attrs["units"] == "s"
    assert list(ds["planner"].values) == ["oceanloc", "thesis-single"]
    rec = mc.to_record()
    assert len(rec["planners"]["thesis-single"]["success"]) == 4
    s = summarize(mc.runs["oceanloc"], problems[0].direct_flight_wh, 1.0)
    assert s.success_rate == 1.0 and 0.0 < s.saving_mean < 1.0


def test_unknown_planner_is_a_config_error():
    with pytest.raises(ConfigError, match="must be one of"):
        drift_monte_carlo([uniform_problem()], 1, 0, planners=("rrt",))
