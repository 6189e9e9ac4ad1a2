"""Drift/hop lattice search: dynamic programming over drift trajectories and straight flights.

Drifting costs no energy and flying costs energy in proportion to the distance flown (IV.14), so the
cheapest way from any point to the goal is a value function ``V`` satisfying

    V(p) = min( 0 if the drift from p enters the goal disk,
                min over points s of the drift from p, landing points q:  |s - q| + V(q) )

(drift from ``p``, take off at some point ``s`` of the drift, fly straight to ``q``; the goal is a landing
point with ``V = 0``). This module solves it on a lattice of landing points ``q`` of spacing ``h``:

1. every lattice node (and the start) is drifted with the problem's own propagator, all at once
   (:meth:`DriftPropagator.rollout`), recording its trajectory every ``stride`` steps and its closest
   approach to the goal;
2. value iteration: the flight envelope ``D(z) = min_q |z - q| + V(q)`` is computed on the lattice (exactly
   with a dense distance matrix for coarse lattices, or by relaxing a stencil of straight moves for fine
   ones) and ``V(p) = min_s |s - n(s)| + D(n(s))`` over the samples ``s`` of ``p``'s drift, snapped to their
   nearest node ``n(s)``, until ``V`` stops changing (each sweep allows one more flight);
3. the plan is extracted from the start with exact distances (take-off sample and landing point by exact
   minimization), then refined: candidate landing points on a fine local grid around each landing point
   are drifted and a backward dynamic programme over these clouds picks the best combination; this repeats
   on a finer cloud. The refined plan replaces the lattice plan only if its exact flight distance is
   smaller.

Every plan is re-simulated step by step with the propagator: its energy is exact for the problem's dynamics,
and only its optimality depends on the lattice. Flights go straight; with ``problem.max_leg_m`` they are
made of legs of at most that length landing on free lattice nodes.

In a time-varying field (:func:`oceanloc.models.currents.is_steady` false: a double gyre with
``epsilon > 0``, a gridded product with a time axis) the lattice values are computed from the problem's
start time and only rank the landing points: the plan is read out in time (every leg's drift is integrated
from the time the vehicle lands, :func:`~.lattice_values.extract_in_time`), the steady-field refinement is
skipped, and the path is rebuilt by :func:`~.resimulate.resimulate_plan`, so the reported energy is what the
plan costs when flown.
"""

from __future__ import annotations

import math
import time

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError
from oceanloc.models.currents import is_steady
from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.direct import prefer_direct
from oceanloc.planning.drift_rrt.lattice_refine import refine_plan
from oceanloc.planning.drift_rrt.lattice_values import (
    EnvelopeKind,
    LatticeOptions,
    Leg,
    SampledDrift,
    ValueLattice,
    extract_in_time,
    extract_plan,
    legs_objective,
    sample_drift,
)
from oceanloc.planning.drift_rrt.problem import (
    DriftPlanResult,
    DriftProblem,
    PlanBudget,
    PlanStatus,
    arrived_result,
)
from oceanloc.planning.drift_rrt.resimulate import resimulate_plan

__all__ = [
    "EnvelopeKind",
    "LatticeOptions",
    "check_lattice_memory",
    "lattice_memory_bytes",
    "objective",
    "plan_lattice",
]

GIB = 2.0**30
BYTES_PER_SAMPLE = 88
"""Working bytes per drift sample and particle: positions in the rollout and in the sampled drift (2 x 16),
step counts, time and goal prices, snapped node index, snap distance and flight cost (6 x 8)."""
BYTES_PER_DENSE_PAIR = 16
"""Working bytes per (node, landing) pair of the dense flight envelope (float32 distances and two
temporaries, and the validity mask)."""


def lattice_memory_bytes(problem: DriftProblem, options: LatticeOptions) -> tuple[float, float, float]:
    """Estimated working memory of the lattice search, bytes, and its two drivers.

    Returns ``(bytes, nodes, samples)``: lattice nodes over the map (its extent divided by the spacing) and
    drift samples per node (horizon steps divided by the stride). Computed in floating point, so a map of
    1e300 m gives ``inf`` rather than an overflow.
    """
    x0, x1, y0, y1 = (float(v) for v in problem.space.bounds_m)
    h = options.spacing_m
    nodes = (math.floor((x1 - x0) / h) + 1.0) * (math.floor((y1 - y0) / h) + 1.0)
    samples = problem.horizon_s / problem.propagator.dt_s / options.stride + 2.0
    total = BYTES_PER_SAMPLE * samples * (nodes + 1.0)
    if options.envelope == "dense":
        total += BYTES_PER_DENSE_PAIR * nodes * (nodes + 1.0)
    return total, nodes, samples


def check_lattice_memory(problem: DriftProblem, options: LatticeOptions) -> None:
    """Raise a ConfigError, before allocating, when the search would need more than
    ``options.max_memory_gib``; the message names the map, step and horizon to change."""
    total, nodes, samples = lattice_memory_bytes(problem, options)
    if total <= options.max_memory_gib * GIB:
        return
    raise ConfigError(
        f"the lattice planner would need about {total / GIB:.3g} GiB (at most {options.max_memory_gib:g}): "
        f"{nodes:.3g} lattice nodes {options.spacing_m:g} m apart over the map, {samples:.3g} drift samples "
        f"each (horizon {problem.horizon_s / 3600:g} h, step {problem.propagator.dt_s:g} s); shrink [map] "
        "bounds_m, raise [drift] dt_s or shorten [drift] horizon_h"
    )


def _build_path(problem: DriftProblem, legs: list[Leg]) -> DriftPath:
    prop, space = problem.propagator, problem.space
    t = problem.t0_s
    pos = problem.start_m
    segments: list[tuple[FloatArray, bool]] = []
    for leg in legs:
        # Each leg drifts from its own start time (the clock runs through drifts and flights).
        drift = prop.drift_polyline(space, pos, leg.drift_steps, t0_s=t)
        segments.append((drift, False))
        pos = drift[-1]
        t += prop.dt_s * (drift.shape[0] - 1)
        if leg.landing is None:
            break
        segments.append((np.vstack([pos, leg.landing]), True))
        t += float(np.linalg.norm(np.asarray(leg.landing) - pos)) / problem.energy.flight_speed_mps
        pos = np.asarray(leg.landing, dtype=float)
        if leg.to_goal:
            break
    path = DriftPath.from_segments(
        segments, t0_s=problem.t0_s, dt_s=prop.dt_s, flight_speed_mps=problem.energy.flight_speed_mps
    )
    # Flights of any length: consecutive flights are one straight flight (unless obstacles are no-fly zones,
    # where the chain goes around them). With legs, each leg lands.
    return path.merged() if problem.max_leg_m is None and not space.flights_avoid_obstacles else path


def plan_lattice(
    problem: DriftProblem,
    rng: np.random.Generator,
    budget: PlanBudget | None = None,
    options: LatticeOptions | None = None,
) -> DriftPlanResult:
    """Plan with the drift/hop lattice search (see the module docstring).

    Parameters
    ----------
    problem : DriftProblem
    rng : numpy.random.Generator
        Draws the random offset of the lattice (if enabled).
    budget : PlanBudget, optional
        Unused: the search is deterministic given the lattice; its effort is set by ``options``.
    options : LatticeOptions, optional

    Returns
    -------
    DriftPlanResult
    """
    opts = options or LatticeOptions()
    check_lattice_memory(problem, opts)
    tic = time.perf_counter()
    direct = problem.direct_flight_wh
    invalid = problem.validate_endpoints()
    if invalid is not None:
        return DriftPlanResult(
            status=PlanStatus.FAILED,
            path=None,
            flight_energy_wh=math.inf,
            direct_flight_wh=direct,
            compute_s=0.0,
            message=invalid,
        )
    if problem.starts_in_goal:
        return arrived_result(problem)
    offset = rng.uniform(0.0, opts.spacing_m, 2) if opts.random_offset else np.zeros(2)
    lattice = ValueLattice(problem, opts, offset)
    points = np.concatenate([lattice.nodes[lattice.free_idx], problem.start_m[None]], axis=0)
    traj = sample_drift(problem, points, opts.stride)
    lattice.solve(traj)
    start = points.shape[0] - 1
    steady = is_steady(problem.propagator.field)
    if steady:
        legs = extract_plan(lattice, traj, start, traj, opts.max_flights)
    else:
        legs = extract_in_time(lattice, opts.max_flights)
    if legs is None:
        failed = DriftPlanResult(
            status=PlanStatus.FAILED,
            path=None,
            flight_energy_wh=math.inf,
            direct_flight_wh=direct,
            compute_s=time.perf_counter() - tic,
            message="no drift/flight sequence reaches the goal from the start",
        )
        return prefer_direct(problem, failed, objective)
    start_traj = SampledDrift(
        points=points[start:],
        samples=traj.samples[:, start:],
        steps=traj.steps[:, start:],
        reaches=traj.reaches[start:],
        goal_step=traj.goal_step[start:],
        time_cost=traj.time_cost[:, start:],
        finish=traj.finish[start:],
        goal_cost=traj.goal_cost[:, start:],
    )
    best_cost = legs_objective(problem, legs)
    extent = opts.spacing_m
    for _ in range(opts.refine_rounds if steady else 0):
        refined = refine_plan(lattice, problem, start_traj, traj, legs, opts, extent)
        extent /= 4.0
        if refined is None:
            continue
        cost = legs_objective(problem, refined)
        if cost < best_cost - 1e-9:
            legs, best_cost = refined, cost
    best_path = _build_path(problem, legs)
    if not steady:
        # Merging flights changes the clock of what follows: the path is the one flown.
        best_path = resimulate_plan(problem, best_path).path
    ok = _reaches(problem, best_path)
    energy = float(problem.energy.flight_energy_wh(best_path.flight_distance_m))
    result = DriftPlanResult(
        status=PlanStatus.EXACT if ok else PlanStatus.APPROXIMATE,
        path=best_path,
        flight_energy_wh=energy,
        direct_flight_wh=direct,
        compute_s=time.perf_counter() - tic,
        iterations=int(lattice.free_idx.size),
        solutions=1 if ok else 0,
        cost=objective(problem, best_path),
        message=f"lattice {opts.spacing_m:g} m ({lattice.free_idx.size} free nodes), "
        f"{best_path.hops_m().shape[0]} flight(s), "
        f"lattice value {problem.energy.flight_energy_wh(lattice.values[-1]):.2f} Wh",
    )
    # Flying straight is always a candidate: never return a plan that costs more.
    return prefer_direct(problem, result, objective)


def objective(problem: DriftProblem, path: DriftPath) -> float:
    """What the lattice planner minimizes: flight energy plus the price of time, Wh."""
    return (
        float(problem.energy.flight_energy_wh(path.flight_distance_m))
        + problem.time_weight_wh_per_h * path.duration_s / 3600.0
    )


def _reaches(problem: DriftProblem, path: DriftPath) -> bool:
    return bool(
        np.linalg.norm(path.end_m - problem.goal_m) < problem.goal_tolerance_m
        or np.allclose(path.end_m, problem.goal_m)
    )
