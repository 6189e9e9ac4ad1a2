"""The planner in time for a vehicle that moves through the water (a boat, a glider): read-out and refinement.

A powered leg in the water is carried by the current (:mod:`oceanloc.models.powered`), so long straight
legs are rarely best in a varying current; the value lattice (:mod:`.time_values`) moves between nodes
over a stencil. :func:`read_out_water` follows the value from the start in exact time, one decision at a
time: drift one step (the value interpolated where the drift ends), or make a straight powered leg to a
lattice node within the stencil's reach (its exact time, then the node's value at the arrival time), or go
straight to the goal. :func:`refine_water` moves every waypoint of the track over a local cloud with a
forward dynamic programme in time: each candidate of a stage is reached by the cheapest predecessor, with
its exact arrival time (exact for the time objective, where earlier is always better), the drifts between
waypoints keeping their number of steps. Private to :mod:`oceanloc.planning.drift_rrt.time_plan`.
"""

from __future__ import annotations

import math

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.planning.drift_rrt.lattice_values import Leg
from oceanloc.planning.drift_rrt.time_plan import FlownPlan, evaluate, plan_stages
from oceanloc.planning.drift_rrt.time_values import TimeLattice

MAX_DECISIONS = 4000
"""Safety cap on the read-out's decisions (drift steps and legs)."""


def _reachable_nodes(tl: TimeLattice, pos: FloatArray) -> np.ndarray:
    """Free nodes within the stencil's reach of ``pos`` whose straight leg stays in the water."""
    r = tl.opts.stencil_radius * tl.h
    i0 = max(0, math.floor((pos[0] - r - tl.xs[0]) / tl.h))
    i1 = min(tl.xs.size - 1, math.ceil((pos[0] + r - tl.xs[0]) / tl.h))
    j0 = max(0, math.floor((pos[1] - r - tl.ys[0]) / tl.h))
    j1 = min(tl.ys.size - 1, math.ceil((pos[1] + r - tl.ys[0]) / tl.h))
    jj, ii = np.meshgrid(np.arange(j0, j1 + 1), np.arange(i0, i1 + 1), indexing="ij")
    idx = (jj * tl.xs.size + ii).ravel()
    idx = idx[tl.free[idx]]
    d = np.hypot(tl.nodes[idx, 0] - pos[0], tl.nodes[idx, 1] - pos[1])
    idx = idx[(d <= r + 1e-9) & (d > 1e-6)]
    if idx.size:
        ok = tl.problem.space.obstacles.segment_free(np.broadcast_to(pos, (idx.size, 2)), tl.nodes[idx])
        idx = idx[ok]
    return idx


def read_out_water(tl: TimeLattice, start_m: FloatArray, t_s: float) -> list[Leg] | None:
    """Greedy read-out in exact time for powered legs through the water (see the module docstring)."""
    p = tl.problem
    prop, space = p.propagator, p.space
    dt = prop.dt_s
    speed = tl.speed
    pos = np.asarray(start_m, dtype=float).copy()
    t = float(t_s)
    legs: list[Leg] = []
    drifted = 0
    for _ in range(MAX_DECISIONS):
        if np.hypot(*(pos - p.goal_m)) < p.goal_tolerance_m:
            legs.append(Leg(drift_steps=drifted, takeoff=None, landing=None, to_goal=False))
            return legs
        # Straight to the goal.
        tau_g, ok_g = p.leg_times_s(pos, p.goal_m, t)
        seg_ok = bool(space.obstacles.segment_free(pos, p.goal_m))
        best = speed * float(tau_g) if bool(ok_g) and seg_ok else math.inf
        if tl.deadline is not None and t + float(tau_g) > tl.deadline + 1e-9:
            best = math.inf
        choice: tuple[str, object] = ("goal", None)
        # A leg to a node.
        nodes = _reachable_nodes(tl, pos)
        if nodes.size:
            tau, ok = p.leg_times_s(np.broadcast_to(pos, (nodes.size, 2)), tl.nodes[nodes], t)
            val = np.where(ok, speed * tau + tl.node_value(nodes, t + tau), np.inf)
            k = int(np.argmin(val))
            if val[k] < best:
                best, choice = float(val[k]), ("node", int(nodes[k]))
        # One drift step.
        if t + dt <= tl.t_end + 1e-9:
            nx, ny = prop.step_xy(float(pos[0]), float(pos[1]), t)
            if math.isfinite(nx) and math.isfinite(ny) and bool(space.is_valid_xy(float(nx), float(ny))):
                nxt = np.array([nx, ny])
                entered = np.hypot(*(nxt - p.goal_m)) < p.goal_tolerance_m
                val = tl.price * dt + (0.0 if entered else float(tl.value_at(nxt[None], t + dt)[0]))
                if val < best:
                    best, choice = val, ("drift", nxt)
        if not math.isfinite(best):
            return None
        kind, what = choice
        if kind == "drift":
            pos, t, drifted = what, t + dt, drifted + 1  # type: ignore[assignment]
            continue
        landing = p.goal_m.copy() if kind == "goal" else tl.nodes[what].copy()  # type: ignore[index]
        tau, _ = p.leg_times_s(pos, landing, t)
        legs.append(Leg(drift_steps=drifted, takeoff=pos.copy(), landing=landing, to_goal=kind == "goal"))
        if kind == "goal":
            return legs
        pos, t, drifted = landing, t + float(tau), 0
    return None


def refine_water(tl: TimeLattice, plan: FlownPlan, half_extent_m: float) -> FlownPlan | None:
    """One round of waypoint refinement (see the module docstring); ``None`` if nothing is found."""
    p = tl.problem
    stages = plan_stages(p, plan)
    if stages is None:
        return None
    legs = plan.legs
    waypoints = [leg for leg in legs if leg.landing is not None]
    n = len(waypoints)
    drift_after = [
        legs[i + 1].drift_steps if i + 1 < len(legs) else 0
        for i, leg in enumerate(legs)
        if leg.landing is not None
    ]
    first_drift = legs[0].drift_steps
    w = tl.opts.cloud_half_width
    ticks = np.linspace(-half_extent_m, half_extent_m, 2 * w + 1)
    ox, oy = np.meshgrid(ticks, ticks)
    offsets = np.column_stack([ox.ravel(), oy.ravel()])
    clouds = []
    for leg in waypoints:
        if leg.to_goal:
            clouds.append(p.goal_m[None].copy())
            continue
        c = np.asarray(leg.landing)[None] + offsets
        clouds.append(c[p.space.is_valid(c)])
    # Forward: the drift from the start, then legs from stage to stage.
    prop = p.propagator
    poly = prop.drift_polyline(p.space, p.start_m, first_drift, t0_s=p.t0_s)
    pos = poly[-1][None]
    times = np.array([p.t0_s + prop.dt_s * (poly.shape[0] - 1)])
    costs = np.array([tl.price * prop.dt_s * (poly.shape[0] - 1)])
    parents: list[np.ndarray] = []
    takeoffs: list[FloatArray] = []
    for i in range(n):
        targets = clouds[i]
        a_idx, b_idx = np.meshgrid(np.arange(pos.shape[0]), np.arange(targets.shape[0]), indexing="ij")
        a_idx, b_idx = a_idx.ravel(), b_idx.ravel()
        tau, ok = p.leg_times_s(pos[a_idx], targets[b_idx], times[a_idx])
        ok &= p.space.obstacles.segment_free(pos[a_idx], targets[b_idx])
        total = np.where(ok, costs[a_idx] + tl.speed * tau, np.inf).reshape(pos.shape[0], targets.shape[0])
        par = np.argmin(total, axis=0)
        cost_b = total[par, np.arange(targets.shape[0])]
        tau_b = tau.reshape(pos.shape[0], targets.shape[0])[par, np.arange(targets.shape[0])]
        t_b = times[par] + tau_b
        parents.append(par)
        takeoffs.append(pos)
        # Drift after landing (its number of steps kept), then the next leg takes off there.
        k = drift_after[i]
        if k and i + 1 < n:
            roll = prop.rollout(
                p.space, targets, k, goal_m=p.goal_m, goal_tolerance_m=p.goal_tolerance_m, t0_s=t_b
            )
            end = roll.samples_m[-1]
            cost_b = np.where(np.isfinite(end[:, 0]), cost_b + tl.price * prop.dt_s * k, np.inf)
            pos, times, costs = np.where(np.isfinite(end), end, targets), t_b + prop.dt_s * k, cost_b
        else:
            pos, times, costs = targets, t_b, cost_b
    best = int(np.argmin(costs))
    if not math.isfinite(costs[best]):
        return None
    chosen = [best]
    for i in range(n - 1, 0, -1):
        chosen.append(int(parents[i][chosen[-1]]))
    chosen.reverse()
    new_legs: list[Leg] = []
    wi = 0
    for leg in legs:
        if leg.landing is None:
            new_legs.append(leg)
            continue
        new_legs.append(
            Leg(
                drift_steps=leg.drift_steps,
                takeoff=None,
                landing=clouds[wi][chosen[wi]].copy(),
                to_goal=leg.to_goal,
            )
        )
        wi += 1
    cand = evaluate(p, new_legs)
    return cand
