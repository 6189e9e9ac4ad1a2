import math

import numpy as np
import pytest

from oceanloc._random import run_generators
from oceanloc.config.drift import FollowingSettings
from oceanloc.planning.drift_rrt.planner import make_planner
from oceanloc.sim.drifters import swap_positions
from oceanloc.sim.path_following import follow_plans, gauss_markov_noise
from tests.planning.drift_fixtures import fixed_field, uniform_problem

EXACT = FollowingSettings(current_scale=1.0, current_rotation_rad=0.0, noise_mps=0.0, watch_circle_m=1.0)


def test_following_in_the_planning_current_reproduces_the_plan():
    problem = fixed_field()
    plan = make_planner("oceanloc")(problem, np.random.default_rng(0))
    res = follow_plans(
        problem, plan.path, EXACT, run_generators(0, [0, 1]), make_planner("oceanloc"), keep_tracks=1
    )
    assert res.arrived.all() and res.replans.tolist() == [0, 0]
    np.testing.assert_allclose(res.flight_energy_wh, plan.flight_energy_wh, rtol=1e-9)
    assert res.duration_s[0] == pytest.approx(plan.path.duration_s, abs=60.0)
    assert res.tracks()[0].shape[1] == 2 and res.track_run.max() == 0


def test_gauss_markov_noise_statistics():
    # Stationary AR(1): std sigma, lag-one correlation a = exp(-dt / tau). With 20000 samples and a = 0.9672
    # the effective sample size is n (1 - a) / (1 + a) = 333, so the std estimate has a standard error of
    # sigma / sqrt(2 * 333) = 3.9 %; we allow 4 standard errors (16 %). The lag-one correlation's standard
    # error is about sqrt((1 - a^2) / n) = 0.0018; we allow 0.01.
    rng = np.random.default_rng(0)
    x = gauss_markov_noise(rng, 20_000, 60.0, 0.05, 1800.0)
    a = math.exp(-60.0 / 1800.0)
    assert np.std(x[:, 0]) == pytest.approx(0.05, rel=0.16)
    r = np.corrcoef(x[:-1, 0], x[1:, 0])[0, 1]
    assert r == pytest.approx(a, abs=0.01)


def test_blocked_drift_triggers_a_replan():
    # Planned without the wall, the plan is a pure drift east into the goal; the wall stops the drift and
    # the follower must replan (a hop over it).
    open_water = uniform_problem(velocity=(0.5, 0.0), goal=(3000.0, 0.0))
    walled = uniform_problem(
        velocity=(0.5, 0.0), goal=(3000.0, 0.0), rectangles=[[600.0, 700.0, -300.0, 300.0]]
    )
    planner = make_planner("oceanloc")
    plan = planner(open_water, np.random.default_rng(0))
    assert plan.path.hops_m().shape[0] == 0
    settings = FollowingSettings(current_scale=1.0, current_rotation_rad=0.0, noise_mps=0.0, stray_m=5000.0)
    res = follow_plans(walled, plan.path, settings, run_generators(1, [0]), planner)
    assert res.arrived[0] and res.replans[0] >= 1
    assert res.flight_energy_wh[0] > 0.0


def test_swapping_drifters_both_reach_their_goals():
    problem = fixed_field()
    swap = swap_positions(problem, make_planner("oceanloc"), tuple(run_generators(3, [0, 1])))
    assert all(r.success for r in swap.results)
    assert np.allclose(swap.problems[1].start_m, problem.goal_m)
    assert 0.0 <= swap.min_separation_m < np.linalg.norm(problem.goal_m - problem.start_m)
