"""The best achievable flight energy on a drift problem: the lattice search at fine resolution.

Used as the yardstick every planner's energy is divided by. It is the same dynamic programme as the
oceanloc planner (:mod:`oceanloc.planning.drift_rrt.lattice`) run where its discretization no longer
matters: landing points 50 m apart, take-off candidates every second drift step, a stencil flight
envelope (moves up to 6 cells, so straight flights are approximated within 0.5 %), value iteration to
convergence and three rounds of local refinement (down to a few metres). Its plan is re-simulated with the
problem's own dynamics, so its energy is achievable; on the thesis scenario it changes by less than 0.1 %
between 100 m and 50 m lattices. Flights may be any length (the thesis' accounting of merged hops).
"""

from __future__ import annotations

import numpy as np

from oceanloc.planning.drift_rrt.lattice import LatticeOptions, plan_lattice
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem

REFERENCE_OPTIONS = LatticeOptions(
    spacing_m=50.0,
    stride=2,
    envelope="stencil",
    stencil_radius=6,
    max_value_iterations=40,
    refine_rounds=3,
    cloud_half_width=4,
    random_offset=False,
)


def best_achievable(problem: DriftProblem, options: LatticeOptions | None = None) -> DriftPlanResult:
    """Plan with the fine reference lattice (deterministic: no random offset).

    Parameters
    ----------
    problem : DriftProblem
        ``max_leg_m`` must be ``None`` (flights of any length, as the thesis accounts them).
    options : LatticeOptions, optional
        A coarser setting for quick checks; :data:`REFERENCE_OPTIONS` by default.
    """
    return plan_lattice(problem, np.random.default_rng(0), None, options or REFERENCE_OPTIONS)
