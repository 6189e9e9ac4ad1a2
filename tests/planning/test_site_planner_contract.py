"""The contract every measurement-site planner meets, whatever its kind (one parametrized suite).

Each planner is built through the one factory (:func:`make_site_planner`) from the one vocabulary
(:func:`parse_site_planner`), on the same random but realistic problems (1 and 4 transponders).
"""

import numpy as np
import pytest

from oceanloc._random import run_generators
from oceanloc.errors import ConfigError
from oceanloc.planning.information import information_gain_reference
from oceanloc.planning.measurement_sites import PlanningState, SitePlanResult
from oceanloc.planning.random_problems import random_planning_states
from oceanloc.planning.site_planners import (
    SITE_PLANNER_KINDS,
    PlannerSettings,
    make_site_planner,
    parse_site_planner,
    site_planner_label,
    site_planner_name,
)
from oceanloc.planning.status import PlanStatus
from oceanloc.units import DEG

W_MAX = 30 * DEG
SPEED, PERIOD, SIGMA, REACH = 3.0, 1.0, 0.12, 5.0
BATCH = 6

# Every kind, the look-ahead with one and two steps.
SETTINGS = {
    "random-yaw": PlannerSettings(kind="random-yaw"),
    "random-disk": PlannerSettings(kind="random-disk", max_distance_m=REACH),
    "greedy": PlannerSettings(kind="greedy", max_distance_m=REACH),
    "lookahead-1": PlannerSettings(kind="lookahead", horizon=1),
    "lookahead-2": PlannerSettings(kind="lookahead", horizon=2),
}


def _planner(settings):
    return make_site_planner(
        settings, max_yaw_rate_rad_s=W_MAX, speed_mps=SPEED, period_s=PERIOD, sigma_range_m=SIGMA
    )


def _state(m, seed=11):
    return random_planning_states(np.random.default_rng(seed + m), BATCH, m)


def _rows(state, rows):
    return PlanningState(
        pos_enu_m=state.pos_enu_m[rows],
        yaw_rad=state.yaw_rad[rows],
        estimates_m=state.estimates_m[rows],
        covariances_m2=state.covariances_m2[rows],
    )


def _plan(settings, state, seed=3, runs=None):
    runs = range(state.batch) if runs is None else runs
    return _planner(settings).plan(state, run_generators(seed, runs))


def test_the_suite_covers_every_kind():
    assert {s.kind for s in SETTINGS.values()} == set(SITE_PLANNER_KINDS)


@pytest.mark.parametrize("m", [1, 4])
@pytest.mark.parametrize("name", list(SETTINGS))
def test_result_shapes(name, m):
    settings = SETTINGS[name]
    plan = _plan(settings, _state(m))
    k = settings.horizon if settings.kind == "lookahead" else 1
    assert isinstance(plan, SitePlanResult) and plan.status is PlanStatus.EXACT
    assert plan.next_pos_enu_m.shape == (BATCH, 3) and plan.next_yaw_rad.shape == (BATCH,)
    assert plan.waypoints_enu_m.shape == (BATCH, k, 3) and plan.objective.shape == (BATCH,)
    np.testing.assert_array_equal(plan.waypoints_enu_m[:, 0], plan.next_pos_enu_m)
    if settings.kind in ("random-yaw", "lookahead"):
        assert plan.yaw_rates_rad_s.shape == (BATCH, k)
    else:
        assert plan.yaw_rates_rad_s is None
    assert plan.solve_time_s >= 0.0


@pytest.mark.parametrize("name", list(SETTINGS))
def test_sites_are_within_reach_and_yaw_rate_bounds(name):
    settings = SETTINGS[name]
    state = _state(4)
    plan = _plan(settings, state)
    steps = np.diff(np.concatenate([state.pos_enu_m[:, None], plan.waypoints_enu_m], axis=1), axis=1)
    horizontal = np.hypot(steps[..., 0], steps[..., 1])
    np.testing.assert_array_equal(steps[..., 2], 0.0)  # the vehicle stays on the surface
    if plan.yaw_rates_rad_s is not None:
        # Unicycle (eq. 1): every step is speed * period long, every yaw rate within [-w_max, w_max].
        assert np.all(np.abs(plan.yaw_rates_rad_s) <= W_MAX + 1e-12)
        np.testing.assert_allclose(horizontal, SPEED * PERIOD, rtol=1e-12)
        yaw = state.yaw_rad[:, None] + np.cumsum(plan.yaw_rates_rad_s, axis=1) * PERIOD
        np.testing.assert_allclose(plan.next_yaw_rad, yaw[:, 0], rtol=0, atol=1e-12)
    else:
        assert np.all(horizontal <= REACH + 1e-9)


@pytest.mark.parametrize("name", list(SETTINGS))
def test_a_fixed_rng_gives_the_same_plan(name):
    state = _state(4)
    first, second = _plan(SETTINGS[name], state), _plan(SETTINGS[name], state)
    np.testing.assert_array_equal(first.next_pos_enu_m, second.next_pos_enu_m)
    np.testing.assert_array_equal(first.objective, second.objective)


@pytest.mark.parametrize("m", [1, 4])
@pytest.mark.parametrize("name", list(SETTINGS))
def test_objective_is_the_finite_nonnegative_gain_of_the_planned_sites(name, m):
    # The reported objective is eq. (29)'s gain of all planned sites, recomputed the slow way.
    state = _state(m)
    plan = _plan(SETTINGS[name], state)
    assert np.all(np.isfinite(plan.objective)) and np.all(plan.objective >= 0.0)
    for b in range(BATCH):
        ref = information_gain_reference(
            plan.waypoints_enu_m[b], state.estimates_m[b], state.covariances_m2[b], SIGMA
        )
        assert plan.objective[b] == pytest.approx(ref, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("m", [1, 4])
@pytest.mark.parametrize(("optimal", "baseline"), [("lookahead-1", "random-yaw"), ("greedy", "random-disk")])
def test_d_optimal_planners_beat_their_random_baseline(optimal, baseline, m):
    # Same feasible set (one yaw rate in [-w_max, w_max]; one point in the d_max disk): the global
    # optimum is at least any random draw from it, problem by problem, for several draws.
    state = _state(m)
    best = _plan(SETTINGS[optimal], state).objective
    for seed in range(5):
        drawn = _plan(SETTINGS[baseline], state, seed=seed).objective
        assert np.all(best >= drawn - 1e-9 * np.abs(best))


@pytest.mark.parametrize("name", list(SETTINGS))
def test_a_batch_equals_its_problems_one_by_one(name):
    state = _state(4)
    whole = _plan(SETTINGS[name], state)
    for b in range(BATCH):
        one = _plan(SETTINGS[name], _rows(state, [b]), runs=[b])
        np.testing.assert_allclose(one.next_pos_enu_m[0], whole.next_pos_enu_m[b], rtol=0, atol=1e-9)
        np.testing.assert_allclose(one.objective[0], whole.objective[b], rtol=1e-9)


@pytest.mark.parametrize(
    ("text", "kind", "horizon", "name", "label"),
    [
        ("k0", "random-yaw", 3, "k0", "k = 0 (random yaw)"),
        ("RANDOM-YAW", "random-yaw", 3, "k0", "k = 0 (random yaw)"),
        ("k2", "lookahead", 2, "k2", "k = 2"),
        ("K10", "lookahead", 10, "k10", "k = 10"),
        ("lookahead", "lookahead", 3, "k3", "k = 3"),
        ("greedy", "greedy", 3, "greedy", "greedy"),
        ("random-disk", "random-disk", 3, "random-disk", "random disk"),
        ("random", "random-disk", 3, "random-disk", "random disk"),
    ],
)
def test_parse_name_and_label(text, kind, horizon, name, label):
    settings = parse_site_planner(text, horizon=3, max_distance_m=7.5)
    assert (settings.kind, settings.horizon, settings.max_distance_m) == (kind, horizon, 7.5)
    assert site_planner_name(settings) == name and site_planner_label(settings) == label
    assert parse_site_planner(name, horizon=horizon, max_distance_m=7.5) == settings


@pytest.mark.parametrize("text", ["k11", "k-1", "best", "", "k"])
def test_unknown_planner_names_list_the_accepted_ones(text):
    with pytest.raises(
        ConfigError, match=r"unknown planner .*k0 \(random yaw\), k1\.\.k10.*greedy.*random-disk"
    ):
        parse_site_planner(text)


def test_invalid_settings_raise():
    with pytest.raises(ConfigError, match="planner kind must be one of random-yaw, random-disk"):
        PlannerSettings(kind="spiral")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="horizon must be at least 1"):
        parse_site_planner("lookahead", horizon=0)
    with pytest.raises(ConfigError, match="max_distance_m must be positive"):
        parse_site_planner("greedy", max_distance_m=0.0)
