import numpy as np
import pytest

from oceanloc._random import run_generators
from oceanloc.reproduce.dillard_drrt import (
    THESIS_TABLE4,
    planned_runs,
    reproduce_dillard_drrt,
    thesis_problem,
    thesis_random_obstacles,
)


def test_thesis_problem_units():
    p = thesis_problem()
    assert p.direct_flight_wh == pytest.approx(49.497, abs=1e-3)  # the thesis' red line, 49.5 Wh
    assert p.max_leg_m is None
    assert "2000 m" in p.energy.convention
    assert THESIS_TABLE4["thesis-single"]["energy_wh_mean"] == 38.69


def test_random_fields_follow_the_thesis_generator():
    p = thesis_problem()
    for rng in run_generators(4, range(30)):
        obs = thesis_random_obstacles(rng, p)
        r = obs.rectangles_m
        assert r.shape == (2, 4)
        # Whole 500 m cells of the 21 x 21 grid, 1 to 5 cells wide and high.
        assert np.allclose((r + 5500.0) % 500.0, 0.0)
        sizes = np.column_stack([r[:, 1] - r[:, 0], r[:, 3] - r[:, 2]]) / 500.0
        assert sizes.min() >= 1 and sizes.max() <= 5
        assert obs.is_free(p.start_m) and obs.is_free(p.goal_m)
    a = thesis_random_obstacles(np.random.default_rng(9), p).rectangles_m
    b = thesis_random_obstacles(np.random.default_rng(9), p).rectangles_m
    assert np.array_equal(a, b)


def test_small_reproduction_json_has_the_issue_shape():
    done = []
    report = reproduce_dillard_drrt(
        runs=3, seed=1, fields=1, iterations=2000, reference_spacing_m=200.0, progress=done.append
    )
    # Every part scales with runs: 3 runs per planner on the fixed field and 3 across the random field.
    assert sum(done) == planned_runs(3, 1) == 18
    assert report.random_fields.n_runs == 3 and report.fixed.n_runs == 3
    payload = report.to_record()
    assert {"direct_flight_wh", "planners", "best_achievable_wh"} <= set(payload)
    assert set(payload["planners"]) == {"thesis-single", "thesis-optimality-seeking", "oceanloc"}
    for stats in payload["planners"].values():
        assert set(stats) == {
            "success_rate",
            "energy_wh_mean",
            "energy_wh_std",
            "saving_mean",
            "compute_s_median",
        }
        assert 0.0 <= stats["success_rate"] <= 1.0
    ours = report.planners["oceanloc"]
    assert ours.success_rate == 1.0 and ours.saving_mean > 0.5
    assert payload["best_achievable_wh"] < report.planners["thesis-single"].energy_wh_mean
    assert report.field_best_wh.shape == (1,)
    assert set(report.fields) == set(report.planners)
    ds = report.to_dataset()
    assert ds.sizes["planner"] == 3 and ds.sizes["run"] == 3 and ds.sizes["field_run"] == 3
    assert ds["field_flight_energy"].attrs["units"] == "W h"


def test_the_default_random_fields_scale_with_runs():
    from oceanloc.reproduce.dillard_drrt import default_fields

    assert [default_fields(r) for r in (1, 20, 50, 51, 1000, 5000)] == [1, 1, 1, 2, 20, 20]
    # --runs 20: 60 runs on the fixed field and 60 across one random field, nothing else.
    assert planned_runs(20) == 120 and planned_runs(20, 0) == 60


def test_random_fields_never_outnumber_runs():
    done = []
    report = reproduce_dillard_drrt(
        runs=2, seed=1, fields=20, iterations=500, reference_spacing_m=400.0, progress=done.append
    )
    assert report.field_best_wh.shape == (2,) and sum(done) == planned_runs(2, 20) == 12
