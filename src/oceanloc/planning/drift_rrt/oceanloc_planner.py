"""oceanloc's drift planner: a drift/hop lattice search refined locally, in time when the field changes.

The thesis' DR-RRT* explores with random full-length hops from a single drifting chain, and its cost
(IV.15) mixes energy with distance-to-goal and HDOP terms; on the thesis scenario it saves about 40 % of
the direct-flight energy. This planner solves the energy problem itself: the cheapest sequence of drifts
and straight flights (:mod:`oceanloc.planning.drift_rrt.lattice`): every node of a 300 m lattice is
drifted at once, value iteration gives each node the least flight distance to the goal, the plan is read
off from the start with exact distances, and one round of local refinement moves each landing point (and
the final approach to the goal disk) on a finer grid around it. On the thesis scenario it saves about
54.7 % of the direct-flight energy, 1.3 % above the best achievable, within 100 ms. The lattice offset
is drawn from the planner's generator, so repeated runs sample different lattices.

When the current changes in time, or the objective is time or energy with a deadline, or the vehicle moves
through the water, the plan is made with the value over (node, time)
(:func:`oceanloc.planning.drift_rrt.time_plan.plan_in_time`): the steady lattice would choose the plan as
if the field were frozen at the start time (:func:`needs_time`).
"""

from __future__ import annotations

import numpy as np

from oceanloc.models.currents import is_steady
from oceanloc.planning.drift_rrt.lattice import LatticeOptions, plan_lattice
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem, PlanBudget
from oceanloc.planning.drift_rrt.time_plan import DEFAULT_TIME_OPTIONS, plan_in_time
from oceanloc.planning.drift_rrt.time_values import TimeLatticeOptions

DEFAULT_OPTIONS = LatticeOptions(
    spacing_m=300.0, stride=4, envelope="dense", refine_rounds=1, cloud_half_width=4
)
"""The settings measured in the benchmark and the reproduction."""


def needs_time(problem: DriftProblem) -> bool:
    """Whether ``problem`` is planned in time: a field that changes in time, the time objective, a
    deadline, or powered legs through the water (the steady lattice flies through the air only)."""
    return (
        not is_steady(problem.propagator.field)
        or problem.objective != "energy"
        or problem.max_duration_s is not None
        or problem.propulsion != "air"
    )


def plan_oceanloc(
    problem: DriftProblem,
    rng: np.random.Generator,
    budget: PlanBudget | None = None,
    options: LatticeOptions | TimeLatticeOptions | None = None,
) -> DriftPlanResult:
    """Plan with the oceanloc planner: the steady lattice (``DEFAULT_OPTIONS``) or, when
    :func:`needs_time`, the planner in time (``DEFAULT_TIME_OPTIONS``); ``options`` of the matching kind
    override them."""
    if needs_time(problem):
        opts = options if isinstance(options, TimeLatticeOptions) else DEFAULT_TIME_OPTIONS
        return plan_in_time(problem, rng, budget, opts)
    return plan_lattice(
        problem, rng, budget, options if isinstance(options, LatticeOptions) else DEFAULT_OPTIONS
    )
