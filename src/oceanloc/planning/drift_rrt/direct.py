"""The direct flight as every drift planner's floor: never return a plan that costs more than flying straight.

Flying straight from the start to the goal is always a candidate plan when it is feasible: inside the map,
with every flight leg at most ``problem.max_leg_m`` long and landing on a free point, and (when obstacles
are no-fly zones) with no leg crossing an obstacle. :func:`direct_flight_path` builds it (equal legs along
the straight line, one more leg at a time until the landings are free, as a vehicle would shorten its hops
around an island); :func:`prefer_direct` returns whichever of a planner's result and the direct flight is
cheaper in the planner's own measure, and says so in the result's message.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem, PlanStatus

__all__ = ["direct_flight_path", "prefer_direct"]

MAX_EXTRA_LEGS = 8
"""Extra legs tried beyond the fewest that respect the longest leg, to step over obstacles."""


def direct_flight_path(problem: DriftProblem) -> tuple[DriftPath | None, str]:
    """The straight flight from start to goal as a path, or ``None`` and the reason it is not feasible."""
    start, goal = problem.start_m, problem.goal_m
    dist = float(np.linalg.norm(goal - start))
    space = problem.space
    speed = problem.energy.flight_speed_mps
    fewest = 1 if problem.max_leg_m is None else max(1, math.ceil(dist / problem.max_leg_m - 1e-12))
    tries = 1 if problem.max_leg_m is None and not space.flights_avoid_obstacles else MAX_EXTRA_LEGS + 1
    reason = "a landing point lies outside the map or inside an obstacle"
    for extra in range(tries):
        k = fewest + extra
        frac = np.arange(0, k + 1)[:, None] / k
        points = start[None, :] + frac * (goal - start)[None, :]
        if k > 1 and not bool(np.all(space.is_valid(points[1:-1]))):
            continue
        if (space.flights_avoid_obstacles or problem.in_water) and not bool(
            np.all(space.flight_valid(points[:-1], points[1:]))
        ):
            reason = "it crosses a no-fly obstacle" if not problem.in_water else "it crosses land"
            continue
        if not problem.in_water:
            times = problem.t0_s + frac[:, 0] * dist / speed
        else:
            times = [problem.t0_s]
            for i in range(k):
                tau, ok = problem.leg_times_s(points[i], points[i + 1], times[-1])
                if not bool(ok):
                    return None, "the current does not let the vehicle hold the straight course"
                times.append(times[-1] + float(tau))
            times = np.asarray(times)
        return DriftPath(points_m=points, times_s=times, flight=np.ones(k, dtype=bool)), ""
    return None, reason


def prefer_direct(
    problem: DriftProblem,
    result: DriftPlanResult,
    measure: Callable[[DriftProblem, DriftPath], float] | None = None,
    *,
    replace_unsolved: bool = True,
) -> DriftPlanResult:
    """``result``, or the direct flight if that is feasible and cheaper (or the planner found no plan).

    Parameters
    ----------
    problem : DriftProblem
    result : DriftPlanResult
        A planner's result.
    measure : callable, optional
        ``measure(problem, path) -> float``: the planner's measure of a path (flight energy, Wh, by
        default; the lattice planner adds its price of time).
    replace_unsolved : bool
        Also return the direct flight when the planner reached no goal (``False`` keeps such results as
        they are, so success rates of a planner stay its own).

    Returns
    -------
    DriftPlanResult
        The better of the two; when the planner's plan is kept although it costs more than flying straight
        (the direct flight is not feasible), the message says so.
    """
    if problem.validate_endpoints() is not None or (not replace_unsolved and not result.success):
        return result
    own_cost = measure is not None
    if measure is None:

        def measure(p: DriftProblem, path: DriftPath) -> float:
            return p.powered_energy_wh(path)

    direct, why = direct_flight_path(problem)
    direct_wh = problem.direct_flight_wh
    plan_measure = measure(problem, result.path) if result.path is not None else math.inf
    if direct is None:
        if result.path is not None and result.flight_energy_wh > direct_wh:
            note = (
                f"; the plan costs {result.flight_energy_wh:.2f} Wh, more than a straight flight "
                f"({direct_wh:.2f} Wh), which is not feasible: {why}"
            )
            return dataclasses.replace(result, message=result.message + note)
        return result
    direct_measure = measure(problem, direct)
    if not math.isfinite(direct_measure) or (result.success and plan_measure <= direct_measure + 1e-9):
        # (A direct flight that misses a deadline is no plan.)
        return result
    was = (
        f"the planner's plan ({result.flight_energy_wh:.2f} Wh) costs more"
        if result.path is not None and result.success
        else f"the planner did not reach the goal ({result.status.value})"
    )
    return dataclasses.replace(
        result,
        status=PlanStatus.EXACT,
        path=direct,
        flight_energy_wh=problem.powered_energy_wh(direct),
        solutions=max(result.solutions, 1),
        cost=direct_measure if own_cost else math.nan,
        direct_chosen=True,
        message=f"direct flight ({direct_wh:.2f} Wh) returned: {was}; planner: {result.message}",
    )
