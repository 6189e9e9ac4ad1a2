import math

import numpy as np
import pytest

from oceanloc.config.drift import FollowingSettings, load_drift_scenario
from oceanloc.errors import ConfigError
from oceanloc.evaluation.montecarlo import concat_runs
from oceanloc.evaluation.path_following import (
    FollowingTask,
    drift_follow_study,
    drift_swap_study,
    following_monte_carlo,
    summarize_following,
)
from oceanloc.planning.drift_rrt.planner import make_planner
from tests.planning.drift_fixtures import fixed_field


def test_a_perturbed_current_costs_replans_but_arrives():
    problem = fixed_field()
    planner = make_planner("oceanloc")
    plan = planner(problem, np.random.default_rng(0))
    settings = FollowingSettings(current_scale=1.15, current_rotation_rad=math.radians(8.0), noise_mps=0.05)
    task = FollowingTask(problem, plan.path, settings, planner, seed=5, keep_tracks=2)
    # Chunks of one run each: the tracks of runs 0 and 1 come from two chunks and are both kept.
    res = concat_runs([task(np.arange(i, i + 1)) for i in range(6)], keep=("planned_energy_wh",))
    summary = summarize_following(res)
    assert summary.runs == 6 and summary.arrival_rate == 1.0
    assert res.replans.sum() >= 1
    assert res.kept_runs().tolist() == [0, 1]
    assert len(res.tracks()) == 2 and all(t.shape[0] > 10 for t in res.tracks())
    # Chunking does not change the numbers (one generator per run), nor does the runner's chunk size.
    again = following_monte_carlo(problem, plan.path, settings, planner, 6, 5, keep_tracks=2, chunk_size=4)
    np.testing.assert_allclose(again.flight_energy_wh, res.flight_energy_wh)
    np.testing.assert_allclose(again.track_xy_m, res.track_xy_m)
    np.testing.assert_array_equal(again.flight_run, res.flight_run)


def test_follow_study_records_and_dataset():
    sc = load_drift_scenario("dillard-drift-fixed")
    study = drift_follow_study(sc, runs=2, seed=3)
    rec = study.to_record()
    assert rec["scenario"] == "dillard-drift-fixed" and rec["runs"] == 2 and rec["seed"] == 3
    assert len(rec["per_run"]["arrived"]) == 2 and rec["plan"]["status"] == "exact"
    assert rec["settings"]["current_rotation_deg"] == pytest.approx(
        sc.following.current_rotation_rad * 180 / math.pi
    )
    ds = study.to_dataset()
    assert ds.sizes["run"] == 2
    assert ds["flight_energy"].attrs["units"] == "W h" and ds["duration"].attrs["units"] == "s"


def test_follow_study_rejects_an_unknown_planner():
    with pytest.raises(ConfigError, match="--planner must be one of"):
        drift_follow_study(load_drift_scenario("dillard-drift-fixed"), runs=1, planner="astar")


def test_swap_study_plans_and_follows_both_drifters():
    study = drift_swap_study(load_drift_scenario("dillard-drift-swap"))
    assert all(r.success for r in study.swap.results)
    assert all(f is not None and f.runs == 1 for f in study.followed)
    rec = study.to_record()
    assert [d["drifter"] for d in rec["drifters"]] == [1, 2]
    swap_rec = study.swap.to_record()
    assert swap_rec["drifters"][1]["start_m"] == swap_rec["drifters"][0]["goal_m"]
    assert rec["min_separation_m"] >= 0.0 and "followed" in rec["drifters"][1]
