"""Local refinement of a lattice plan: a backward dynamic programme over clouds of landing points.

Around each landing point of the plan (and around the goal, where a landing just upstream of the goal
disk can drift in) a fine grid of candidates is drifted; the cheapest combination of take-off samples and
candidates is found backwards, with the lattice's values as the fallback at every stage. Private to the
lattice planner (:mod:`oceanloc.planning.drift_rrt.lattice`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.planning.drift_rrt.lattice_values import (
    LatticeOptions,
    Leg,
    SampledDrift,
    ValueLattice,
    extract_plan,
    sample_drift,
)
from oceanloc.planning.drift_rrt.problem import DriftProblem


@dataclass(frozen=True, slots=True, kw_only=True)
class RefineClouds:
    """Candidate landing points: one cloud per landing of the plan, then one around the goal.

    Attributes
    ----------
    clouds : list of (C_i, 2) float
        Valid candidates of each stage, metres (the last is the goal's).
    bounds : (n + 1,) int
        Offsets of each stage's candidates in the stacked non-goal clouds.
    """

    clouds: list[FloatArray]
    bounds: IntArray

    @property
    def n_stages(self) -> int:
        return len(self.clouds)


def landing_clouds(
    problem: DriftProblem, legs: list[Leg], half_width: int, half_extent_m: float
) -> RefineClouds:
    """A ``(2 w + 1)^2`` grid of candidates around each landing point of ``legs`` and around the goal (a
    landing just upstream of the goal disk that drifts in can beat flying to the goal), valid ones only."""
    stages = [leg.landing for leg in legs if leg.landing is not None and not leg.to_goal]
    ticks = np.linspace(-half_extent_m, half_extent_m, 2 * half_width + 1)
    ox, oy = np.meshgrid(ticks, ticks)
    offsets = np.column_stack([ox.ravel(), oy.ravel()])
    clouds = []
    for q in [*stages, problem.goal_m]:
        c = q[None, :] + offsets
        clouds.append(c[problem.space.is_valid(c)])
    bounds = np.cumsum([0, *(c.shape[0] for c in clouds)])
    return RefineClouds(clouds=clouds, bounds=bounds)


@dataclass(frozen=True, slots=True, kw_only=True)
class CloudDrift:
    """How the candidates drift: the stage clouds' rollouts with the lattice fallback, and the goal cloud's
    short rollout."""

    traj: SampledDrift
    fallback: FloatArray
    goal_traj: SampledDrift


def drift_clouds(
    lattice: ValueLattice,
    problem: DriftProblem,
    clouds: RefineClouds,
    start_traj: SampledDrift,
    opts: LatticeOptions,
    half_extent_m: float,
) -> CloudDrift:
    """Drift every stage candidate over the horizon (with the lattice's value as each one's fallback), and
    the goal cloud for a short time: it only matters through points that drift into the goal disk, which
    they do soon (long enough to cross the cloud a few times at the current near the goal)."""
    if clouds.n_stages > 1:
        traj = sample_drift(problem, np.concatenate(clouds.clouds[:-1], axis=0), opts.stride)
        fallback = lattice.fallback_values(traj)
    else:
        traj = start_traj
        fallback = np.zeros(0)
    gu, gv = problem.propagator.field.velocity_xy(
        float(problem.goal_m[0]), float(problem.goal_m[1]), problem.t0_s
    )
    speed = math.hypot(gu, gv) if math.isfinite(gu + gv) else 0.0
    reach_s = 4.0 * (half_extent_m + problem.goal_tolerance_m) / max(speed, 0.05)
    short = dataclasses.replace(problem, horizon_s=min(problem.horizon_s, reach_s))
    goal_traj = sample_drift(short, clouds.clouds[-1], opts.stride)
    return CloudDrift(traj=traj, fallback=fallback, goal_traj=goal_traj)


@dataclass(frozen=True, slots=True, kw_only=True)
class LinkChoice:
    """Best continuation of each particle: its value, the take-off sample and the target candidate."""

    value: FloatArray
    sample: IntArray
    target: IntArray


def link(
    problem: DriftProblem,
    leg_m: float,
    samples: FloatArray,
    tcost: FloatArray,
    targets: FloatArray,
    target_values: FloatArray,
) -> LinkChoice:
    """Best (value, sample, target) for each particle: ``samples (S+1, P, 2)`` to ``targets (C, 2)``.

    Samples that cannot beat the particle's best bound (distance to the cloud's centre minus its radius)
    are pruned before the exact distances are taken; flights longer than ``leg_m`` (and, with no-fly
    obstacles, flights crossing one) are not allowed.
    """
    n_p = samples.shape[1]
    out_v = np.full(n_p, np.inf)
    out_s = np.zeros(n_p, dtype=np.intp)
    out_c = np.zeros(n_p, dtype=np.intp)
    finite = np.isfinite(target_values)
    if not finite.any():
        return LinkChoice(value=out_v, sample=out_s, target=out_c)
    centre = targets[finite].mean(axis=0)
    radius = float(np.max(np.linalg.norm(targets[finite] - centre, axis=1)))
    u_lo, u_hi = float(target_values[finite].min()), float(target_values[finite].max())
    ex = samples[..., 0] - centre[0]
    ey = samples[..., 1] - centre[1]
    dc = np.sqrt(ex * ex + ey * ey)
    dc[~np.isfinite(dc)] = np.inf
    bound = (dc + radius + tcost).min(axis=0) + u_hi
    keep = (dc - radius + u_lo + tcost <= bound[None, :]) & np.isfinite(dc)
    p_idx, s_idx = np.nonzero(keep.T)
    if p_idx.size == 0:
        return LinkChoice(value=out_v, sample=out_s, target=out_c)
    z = samples[s_idx, p_idx]
    dist = np.sqrt((z[:, None, 0] - targets[None, :, 0]) ** 2 + (z[:, None, 1] - targets[None, :, 1]) ** 2)
    dist[dist > leg_m] = np.inf
    if problem.space.flights_avoid_obstacles:
        shape = (z.shape[0], targets.shape[0], 2)
        ok = problem.space.flight_valid(
            np.broadcast_to(z[:, None, :], shape), np.broadcast_to(targets[None], shape)
        )
        dist[~ok] = np.inf
    total = dist + target_values[None, :] + tcost[s_idx, p_idx][:, None]
    c_best = np.argmin(total, axis=1)
    v_best = total[np.arange(total.shape[0]), c_best]
    order = np.lexsort((v_best, p_idx))
    first = order[np.flatnonzero(np.diff(np.concatenate([[-1], p_idx[order]])) != 0)]
    out_v[p_idx[first]] = v_best[first]
    out_s[p_idx[first]] = s_idx[first]
    out_c[p_idx[first]] = c_best[first]
    return LinkChoice(value=out_v, sample=out_s, target=out_c)


@dataclass(frozen=True, slots=True, kw_only=True)
class BackwardPass:
    """Value of every candidate of every stage, and for each stage its link choice and where the lattice
    fallback was better (``use_fallback``)."""

    values: list[FloatArray]
    choices: list[LinkChoice]
    use_fallback: list[BoolArray]


def backward_pass(
    problem: DriftProblem, leg_m: float, clouds: RefineClouds, drift: CloudDrift
) -> BackwardPass:
    """The dynamic programme from the goal cloud back to the first landing cloud."""
    n = clouds.n_stages
    empty = LinkChoice(value=np.empty(0), sample=np.empty(0, int), target=np.empty(0, int))
    values: list[FloatArray] = [np.empty(0)] * n
    choices: list[LinkChoice] = [empty] * n
    use_fb: list[BoolArray] = [np.empty(0, bool)] * n
    values[n - 1] = drift.goal_traj.finish
    for i in range(n - 2, -1, -1):
        sl = slice(clouds.bounds[i], clouds.bounds[i + 1])
        choice = link(
            problem,
            leg_m,
            drift.traj.samples[:, sl],
            drift.traj.time_cost[:, sl],
            clouds.clouds[i + 1],
            values[i + 1],
        )
        fb = drift.fallback[sl]
        use_fb[i] = fb <= choice.value
        values[i] = np.where(use_fb[i], fb, choice.value)
        choices[i] = choice
    return BackwardPass(values=values, choices=choices, use_fallback=use_fb)


def forward_pass(
    lattice: ValueLattice,
    problem: DriftProblem,
    start_traj: SampledDrift,
    node_traj: SampledDrift,
    clouds: RefineClouds,
    drift: CloudDrift,
    back: BackwardPass,
    opts: LatticeOptions,
) -> list[Leg] | None:
    """The legs of the best plan: from the start into the first cloud, from cloud to cloud (or into the
    lattice's plan where its fallback was better), then drifting from the goal cloud into the disk."""
    first = link(
        problem,
        lattice.leg,
        start_traj.samples[:, -1:],
        start_traj.time_cost[:, -1:],
        clouds.clouds[0],
        back.values[0],
    )
    if not math.isfinite(first.value[0]):
        return None
    s0, c0 = first.sample[0], first.target[0]
    out: list[Leg] = [
        Leg(
            drift_steps=int(start_traj.steps[s0, -1]),
            takeoff=start_traj.samples[s0, -1].copy(),
            landing=clouds.clouds[0][c0],
            to_goal=False,
        )
    ]
    cur = int(c0)
    traj = drift.traj
    for i in range(clouds.n_stages - 1):
        choice = back.choices[i]
        p = clouds.bounds[i] + cur
        if back.use_fallback[i][cur]:
            tail = extract_plan(lattice, traj, p, node_traj, opts.max_flights)
            if tail is None:
                return None
            out.extend(tail)
            return out
        out.append(
            Leg(
                drift_steps=int(traj.steps[choice.sample[cur], p]),
                takeoff=traj.samples[choice.sample[cur], p].copy(),
                landing=clouds.clouds[i + 1][choice.target[cur]],
                to_goal=False,
            )
        )
        cur = int(choice.target[cur])
    # In the goal cloud: drift into the disk.
    out.append(
        Leg(drift_steps=int(drift.goal_traj.goal_step[cur]), takeoff=None, landing=None, to_goal=False)
    )
    return out


def refine_plan(
    lattice: ValueLattice,
    problem: DriftProblem,
    start_traj: SampledDrift,
    node_traj: SampledDrift,
    legs: list[Leg],
    opts: LatticeOptions,
    half_extent_m: float,
) -> list[Leg] | None:
    """Backward dynamic programme over clouds of candidate landing points around ``legs``' landings:
    :func:`landing_clouds`, :func:`drift_clouds`, :func:`backward_pass`, :func:`forward_pass`."""
    clouds = landing_clouds(problem, legs, opts.cloud_half_width, half_extent_m)
    drift = drift_clouds(lattice, problem, clouds, start_traj, opts, half_extent_m)
    back = backward_pass(problem, lattice.leg, clouds, drift)
    return forward_pass(lattice, problem, start_traj, node_traj, clouds, drift, back, opts)
