"""Planner registry: every drift planner is ``plan(problem, rng, budget) -> PlanResult``.

``make_planner(name)`` returns a picklable callable (a :class:`NamedPlanner`), so Monte Carlo runs can ship
it to worker processes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from oceanloc.errors import ConfigError
from oceanloc.planning.drift_rrt.oceanloc_planner import plan_oceanloc
from oceanloc.planning.drift_rrt.problem import DriftProblem, PlanBudget, PlanResult
from oceanloc.planning.drift_rrt.thesis import ThesisOptions, plan_thesis

DriftPlannerName = Literal["thesis-single", "thesis-optimality-seeking", "oceanloc"]
PLANNER_NAMES: tuple[str, ...] = get_args(DriftPlannerName)


@dataclass(frozen=True, slots=True)
class NamedPlanner:
    """A planner by name, with an optional iteration budget for the sampling planners."""

    name: str
    iterations: int | None = None

    def __post_init__(self) -> None:
        if self.name not in PLANNER_NAMES:
            raise ConfigError(f"planner must be one of {', '.join(PLANNER_NAMES)}; got '{self.name}'")

    def __call__(
        self, problem: DriftProblem, rng: np.random.Generator, budget: PlanBudget | None = None
    ) -> PlanResult:
        if self.name == "oceanloc":
            return plan_oceanloc(problem, rng, budget)
        mode = "single" if self.name == "thesis-single" else "optimality-seeking"
        if budget is None and self.iterations is not None:
            budget = PlanBudget(max_iterations=self.iterations)
        return plan_thesis(problem, rng, budget, ThesisOptions(mode=mode))


def make_planner(name: str, iterations: int | None = None) -> NamedPlanner:
    """The planner called ``name`` (one of :data:`PLANNER_NAMES`)."""
    return NamedPlanner(name, iterations)
