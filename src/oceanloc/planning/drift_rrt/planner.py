"""Planner registry: every drift planner is ``plan(problem, rng, budget) -> DriftPlanResult``.

``make_planner(name)`` returns a picklable callable (a :class:`NamedPlanner`), so Monte Carlo runs can ship
it to worker processes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from oceanloc.errors import ConfigError
from oceanloc.planning.drift_rrt.oceanloc_planner import plan_oceanloc
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem, PlanBudget
from oceanloc.planning.drift_rrt.thesis import ThesisOptions, plan_thesis

DriftPlannerName = Literal["thesis-single", "thesis-optimality-seeking", "oceanloc"]
"""``thesis-single``: DR-RRT* stopping at its first solution; ``thesis-optimality-seeking``: DR-RRT* over
25,000 iterations keeping the cheapest solution; ``oceanloc``: the drift/hop lattice planner."""
PLANNER_NAMES: tuple[DriftPlannerName, ...] = get_args(DriftPlannerName)


def parse_planner_name(text: str, where: str = "planner") -> DriftPlannerName:
    """``text`` as a drift planner name; the one check every command, file and factory uses.

    Raises a :class:`~oceanloc.errors.ConfigError` that starts with ``where`` (an option such as
    ``--planner``, or a scenario field) and lists the names accepted.
    """
    name = text.strip().lower()
    if name not in PLANNER_NAMES:
        raise ConfigError(f"{where} must be one of {', '.join(PLANNER_NAMES)}; got '{text}'")
    return name  # type: ignore[return-value]


@dataclass(frozen=True, slots=True)
class NamedPlanner:
    """A planner by name, with an optional iteration budget for the sampling planners."""

    name: DriftPlannerName
    iterations: int | None = None

    def __post_init__(self) -> None:
        parse_planner_name(self.name)

    def __call__(
        self, problem: DriftProblem, rng: np.random.Generator, budget: PlanBudget | None = None
    ) -> DriftPlanResult:
        if self.name == "oceanloc":
            return plan_oceanloc(problem, rng, budget)
        mode = "single" if self.name == "thesis-single" else "optimality-seeking"
        if budget is None and self.iterations is not None:
            budget = PlanBudget(max_iterations=self.iterations)
        return plan_thesis(problem, rng, budget, ThesisOptions(mode=mode))


def make_planner(name: str, iterations: int | None = None) -> NamedPlanner:
    """The planner called ``name`` (one of :data:`PLANNER_NAMES`)."""
    return NamedPlanner(parse_planner_name(name), iterations)
