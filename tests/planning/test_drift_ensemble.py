"""Planning on an ensemble forecast: the plan of least expected objective, and each plan's spread."""

from __future__ import annotations

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.models.currents import TidalCurrent
from oceanloc.models.energy import EnergyBudget
from oceanloc.models.obstacles import ObstacleMap
from oceanloc.planning.drift_rrt.ensemble import plan_for_ensemble
from oceanloc.planning.drift_rrt.problem import DriftProblem
from oceanloc.planning.drift_rrt.propagation import DriftPropagator
from oceanloc.planning.drift_rrt.resimulate import resimulate_plan
from oceanloc.planning.drift_rrt.space import DriftSpace
from oceanloc.planning.drift_rrt.time_plan import plan_in_time
from oceanloc.planning.drift_rrt.time_values import TimeLatticeOptions

OPTIONS = TimeLatticeOptions(spacing_m=500.0, slice_s=1800.0, refine_rounds=2)


def _members() -> list[TidalCurrent]:
    """A tidal stream toward the goal whose strength and timing differ from member to member."""
    return [
        TidalCurrent(mean_mps=(0.25 * s, 0.0), amplitude_mps=(0.0, 0.2), period_s=21_600.0, phase_rad=ph)
        for s, ph in ((0.6, 0.0), (1.0, 0.5), (1.4, 1.0))
    ]


def _problem(field) -> DriftProblem:
    return DriftProblem(
        space=DriftSpace(obstacles=ObstacleMap(bounds_m=(-1000.0, 9000.0, -3000.0, 3000.0))),
        propagator=DriftPropagator(field=field, dt_s=300.0, method="rk4"),
        start_m=np.array([0.0, 0.0]),
        goal_m=np.array([7000.0, 0.0]),
        goal_tolerance_m=150.0,
        energy=EnergyBudget(),
        horizon_s=12 * 3600.0,
        time_weight_wh_per_h=0.5,
    )


def test_the_chosen_plan_has_the_least_mean_objective_and_the_spread_is_its_flights():
    members = _members()
    mean = TidalCurrent(mean_mps=(0.25, 0.0), amplitude_mps=(0.0, 0.2), period_s=21_600.0, phase_rad=0.5)
    problem = _problem(mean)

    def planner(p, rng):
        return plan_in_time(p, rng, None, OPTIONS)

    ens = plan_for_ensemble(problem, members, planner, np.random.default_rng(0))
    assert ens.labels == ("mean", "member 0", "member 1", "member 2")
    assert ens.objective.shape == (4, 3) and np.isfinite(ens.objective).all()
    means = ens.objective.mean(axis=1)
    assert ens.chosen == int(np.argmin(means))
    assert ens.result.cost == pytest.approx(means[ens.chosen])
    # Each entry is the plan flown in that member (open loop, finishing with a flight to the goal).
    member = _problem(members[2])
    flown = resimulate_plan(member, ens.result.path, finish_to_goal=True)
    assert ens.energy_wh[ens.chosen, 2] == pytest.approx(flown.flight_energy_wh)
    row = ens.spread()[ens.chosen]
    assert row["chosen"] and row["energy_wh_min"] <= row["energy_wh_mean"] <= row["energy_wh_max"]
    # A plan made for one member alone is no better on average than the chosen one, by construction, and
    # the members' spreads are real: the weakest and strongest streams cost differently.
    assert all(row["energy_wh_max"] > row["energy_wh_min"] for row in ens.spread())


def test_an_ensemble_needs_two_members():
    with pytest.raises(ConfigError, match="at least two members"):
        plan_for_ensemble(
            _problem(_members()[0]), _members()[:1], lambda p, r: None, np.random.default_rng(0)
        )
