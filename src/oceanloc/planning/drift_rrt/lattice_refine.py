"""Local refinement of a lattice plan: a backward dynamic programme over clouds of landing points.

Around each landing point of the plan (and around the goal, where a landing just upstream of the goal
disk can drift in) a fine grid of candidates is drifted; the cheapest combination of take-off samples and
candidates is found backwards, with the lattice's values as the fallback at every stage. Private to the
lattice planner (:mod:`oceanloc.planning.drift_rrt.lattice`).
"""

from __future__ import annotations

import dataclasses
import math

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


def refine_plan(
    lattice: ValueLattice,
    problem: DriftProblem,
    start_traj: SampledDrift,
    node_traj: SampledDrift,
    legs: list[Leg],
    opts: LatticeOptions,
    half_extent_m: float,
) -> list[Leg] | None:
    """Backward dynamic programme over clouds of candidate landing points around ``legs``' landings."""
    # Landing points of the plan, then the goal itself: a landing just upstream of the goal disk that
    # drifts in can beat flying to the goal (its cloud is the last stage).
    stages = [leg.landing for leg in legs if leg.landing is not None and not leg.to_goal]
    w = opts.cloud_half_width
    ticks = np.linspace(-half_extent_m, half_extent_m, 2 * w + 1)
    ox, oy = np.meshgrid(ticks, ticks)
    offsets = np.column_stack([ox.ravel(), oy.ravel()])
    clouds = []
    for q in [*stages, problem.goal_m]:
        c = q[None, :] + offsets
        c = c[problem.space.is_valid(c)]
        clouds.append(c)
    sizes = [c.shape[0] for c in clouds]
    bounds = np.cumsum([0, *sizes])
    if stages:
        traj = sample_drift(problem, np.concatenate(clouds[:-1], axis=0), opts.stride)
        fallback = lattice.fallback_values(traj)
    else:
        traj = start_traj
        fallback = np.zeros(0)
    # The goal cloud only matters through points that drift into the goal disk, which they do soon:
    # a short rollout (long enough to cross the cloud a few times at the current near the goal).
    gu, gv = problem.propagator.field.velocity_xy(
        float(problem.goal_m[0]), float(problem.goal_m[1]), problem.t0_s
    )
    speed = math.hypot(gu, gv) if math.isfinite(gu + gv) else 0.0
    reach_s = 4.0 * (half_extent_m + problem.goal_tolerance_m) / max(speed, 0.05)
    short = dataclasses.replace(problem, horizon_s=min(problem.horizon_s, reach_s))
    goal_traj = sample_drift(short, clouds[-1], opts.stride)
    leg = lattice.leg
    no_fly = problem.space.flights_avoid_obstacles

    def link(
        samples: FloatArray, tcost: FloatArray, targets: FloatArray, target_values: FloatArray
    ) -> tuple[FloatArray, IntArray, IntArray]:
        """Best (value, sample, target) for each particle: ``samples (S+1, P, 2)`` to ``targets (C, 2)``.

        Samples that cannot beat the particle's best bound (distance to the cloud's centre minus its radius)
        are pruned before the exact distances are taken.
        """
        n_p = samples.shape[1]
        out_v = np.full(n_p, np.inf)
        out_s = np.zeros(n_p, dtype=np.intp)
        out_c = np.zeros(n_p, dtype=np.intp)
        finite = np.isfinite(target_values)
        if not finite.any():
            return out_v, out_s, out_c
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
            return out_v, out_s, out_c
        z = samples[s_idx, p_idx]
        dist = np.sqrt(
            (z[:, None, 0] - targets[None, :, 0]) ** 2 + (z[:, None, 1] - targets[None, :, 1]) ** 2
        )
        dist[dist > leg] = np.inf
        if no_fly:
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
        return out_v, out_s, out_c

    n = len(stages) + 1
    values: list[FloatArray] = [np.empty(0)] * n
    choice: list[tuple[IntArray, IntArray, BoolArray]] = [
        (np.empty(0, int), np.empty(0, int), np.empty(0, bool))
    ] * n
    values[n - 1] = goal_traj.finish
    for i in range(n - 2, -1, -1):
        sl = slice(bounds[i], bounds[i + 1])
        v_link, s_best, c_best = link(
            traj.samples[:, sl], traj.time_cost[:, sl], clouds[i + 1], values[i + 1]
        )
        fb = fallback[sl]
        use_fb = fb <= v_link
        values[i] = np.where(use_fb, fb, v_link)
        choice[i] = (s_best, c_best, use_fb)
    v0, s0, c0 = link(start_traj.samples[:, -1:], start_traj.time_cost[:, -1:], clouds[0], values[0])
    if not math.isfinite(v0[0]):
        return None
    # Forward pass.
    out: list[Leg] = [
        Leg(
            drift_steps=int(start_traj.steps[s0[0], -1]),
            takeoff=start_traj.samples[s0[0], -1].copy(),
            landing=clouds[0][c0[0]],
            to_goal=False,
        )
    ]
    cur = int(c0[0])
    for i in range(n - 1):
        s_best, c_best, use_fb = choice[i]
        p = bounds[i] + cur
        if use_fb[cur]:
            tail = extract_plan(lattice, traj, p, node_traj, opts.max_flights)
            if tail is None:
                return None
            out.extend(tail)
            return out
        out.append(
            Leg(
                drift_steps=int(traj.steps[s_best[cur], p]),
                takeoff=traj.samples[s_best[cur], p].copy(),
                landing=clouds[i + 1][c_best[cur]],
                to_goal=False,
            )
        )
        cur = int(c_best[cur])
    # In the goal cloud: drift into the disk.
    out.append(Leg(drift_steps=int(goal_traj.goal_step[cur]), takeoff=None, landing=None, to_goal=False))
    return out
