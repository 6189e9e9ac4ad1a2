"""Two drifters swapping positions (Dillard, Chapter V.D, Figs. 68-71).

Each drifter plans from its own start to the other's start in the same current and obstacle field; the
thesis' vortex is symmetric under a half turn, so with symmetric obstacles the two plans mirror each other
("opposing trees with similar shapes"). The planned schedules are compared to report how close the two
drifters come to each other.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem
from oceanloc.sim.path_following import Replanner


@dataclass(frozen=True, slots=True, kw_only=True)
class SwapResult:
    """Plans of both drifters.

    Attributes
    ----------
    problems : tuple of DriftProblem
        Drifter 1 (start -> goal) and drifter 2 (goal -> start).
    results : tuple of DriftPlanResult
    min_separation_m : float
        Closest approach of the two planned schedules (``inf`` if a plan failed).
    """

    problems: tuple[DriftProblem, DriftProblem]
    results: tuple[DriftPlanResult, DriftPlanResult]
    min_separation_m: float

    def to_record(self) -> dict[str, Any]:
        """Both drifters' start, goal (m) and plan, and the closest approach (m; ``None`` if a plan
        failed)."""
        return {
            "min_separation_m": self.min_separation_m,
            "drifters": [
                {"start_m": p.start_m.tolist(), "goal_m": p.goal_m.tolist(), "plan": r.to_record()}
                for p, r in zip(self.problems, self.results, strict=True)
            ],
        }


def swap_positions(
    problem: DriftProblem, planner: Replanner, rngs: tuple[np.random.Generator, np.random.Generator]
) -> SwapResult:
    """Plan drifter 1 from ``problem.start_m`` to ``problem.goal_m`` and drifter 2 the other way."""
    other = dataclasses.replace(problem, start_m=problem.goal_m, goal_m=problem.start_m)
    r1 = planner(problem, rngs[0])
    r2 = planner(other, rngs[1])
    sep = float("inf")
    if r1.path is not None and r2.path is not None:
        t_end = max(r1.path.times_s[-1], r2.path.times_s[-1])
        t = np.linspace(problem.t0_s, t_end, 2000)
        sep = float(np.min(np.linalg.norm(r1.path.position_at(t) - r2.path.position_at(t), axis=1)))
    return SwapResult(problems=(problem, other), results=(r1, r2), min_separation_m=sep)
