"""Small drift problems shared by the planning tests."""

from __future__ import annotations

import dataclasses

import numpy as np

from oceanloc.models.currents import UniformCurrent
from oceanloc.models.energy import EnergyBudget
from oceanloc.models.obstacles import ObstacleMap
from oceanloc.planning.drift_rrt.objective import HdopTerm
from oceanloc.planning.drift_rrt.problem import DriftProblem
from oceanloc.planning.drift_rrt.propagation import DriftPropagator
from oceanloc.planning.drift_rrt.space import DriftSpace
from oceanloc.reproduce.dillard_drrt import thesis_problem

THESIS_HDOP = HdopTerm(
    others_m=[[5000.0, 5000.0], [5000.0, -5000.0], [-5000.0, -5000.0]], target_m=[3100.0, -2900.0]
)


def uniform_problem(
    velocity=(0.5, 0.0),
    start=(0.0, 0.0),
    goal=(3000.0, 1200.0),
    rectangles=(),
    max_leg_m=None,
    no_fly=False,
    horizon_s=4 * 3600.0,
) -> DriftProblem:
    """A 4 km x 3 km box with a uniform current; drifting east then flying north is optimal."""
    obstacles = ObstacleMap(
        bounds_m=(-500.0, 4000.0, -500.0, 2500.0),
        rectangles_m=np.asarray(rectangles, dtype=float).reshape(-1, 4),
    )
    return DriftProblem(
        space=DriftSpace(obstacles=obstacles, flights_avoid_obstacles=no_fly),
        propagator=DriftPropagator(field=UniformCurrent(velocity_mps=velocity), dt_s=60.0, method="euler"),
        start_m=np.asarray(start, dtype=float),
        goal_m=np.asarray(goal, dtype=float),
        goal_tolerance_m=50.0,
        energy=EnergyBudget(),
        hdop=THESIS_HDOP,
        horizon_s=horizon_s,
        max_leg_m=max_leg_m,
    )


def fixed_field() -> DriftProblem:
    return thesis_problem()


def with_legs(problem: DriftProblem, leg_m: float) -> DriftProblem:
    return dataclasses.replace(problem, max_leg_m=leg_m)
