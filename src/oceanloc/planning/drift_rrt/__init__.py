"""Energy-aware drift planning (Dillard, "AquaQuad", Chapter IV.B-C): OMPL-style parts and planners.

- :mod:`.space` (bounds, obstacles, validity), :mod:`.propagation` (drifting in the current),
  :mod:`.objective` (the thesis' weighted cost and its HDOP term), :mod:`.problem` (problem, budget, result),
  :mod:`.planner` (the planner names, :data:`.planner.PLANNER_NAMES`, and the one factory); drift/flight paths
  and their energy are :mod:`oceanloc.models.paths`;
- planners, each ``plan(problem, rng, budget) -> DriftPlanResult``: :func:`.thesis.plan_thesis` (DR-RRT*,
  single solution or optimality-seeking), :func:`.oceanloc_planner.plan_oceanloc` (drift/hop lattice
  search), :func:`.reference.best_achievable` (the fine-lattice yardstick).
"""

from oceanloc.models.paths import DriftPath, PathEnergy
from oceanloc.planning.drift_rrt.planner import PLANNER_NAMES, make_planner
from oceanloc.planning.drift_rrt.problem import (
    DriftPlanResult,
    DriftProblem,
    PlanBudget,
    PlanStatus,
    SearchTree,
)

__all__ = [
    "PLANNER_NAMES",
    "DriftPath",
    "DriftPlanResult",
    "DriftProblem",
    "PathEnergy",
    "PlanBudget",
    "PlanStatus",
    "SearchTree",
    "make_planner",
]
