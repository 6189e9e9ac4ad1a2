"""Energy-aware drift planning (Dillard, "AquaQuad", Chapter IV.B-C): OMPL-style parts and planners.

- :mod:`.space` (bounds, obstacles, validity), :mod:`.propagation` (drifting in the current),
  :mod:`.objective` (the thesis' weighted cost and its HDOP term), :mod:`.problem` (problem, budget, result),
  :mod:`.path` (drift/flight paths and their energy);
- planners, each ``plan(problem, rng, budget) -> PlanResult``: :func:`.thesis.plan_thesis` (DR-RRT*, single
  solution or optimality-seeking), :func:`.oceanloc_planner.plan_oceanloc` (drift/hop lattice search),
  :func:`.reference.best_achievable` (the fine-lattice yardstick).
"""

from oceanloc.models.paths import DriftPath, PathEnergy
from oceanloc.planning.drift_rrt.planner import PLANNER_NAMES, make_planner
from oceanloc.planning.drift_rrt.problem import DriftProblem, PlanBudget, PlanResult, PlanStatus, SearchTree

__all__ = [
    "PLANNER_NAMES",
    "DriftPath",
    "DriftProblem",
    "PathEnergy",
    "PlanBudget",
    "PlanResult",
    "PlanStatus",
    "SearchTree",
    "make_planner",
]
