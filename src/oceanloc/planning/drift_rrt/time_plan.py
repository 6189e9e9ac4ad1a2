"""oceanloc's drift planner in time: the value over (node, time), a read-out in exact time, local refinement.

:class:`~oceanloc.planning.drift_rrt.time_values.TimeLattice` gives the value ``V(p, t)`` of being at ``p``
at time ``t`` (dynamic programming backwards from the goal over lattice nodes and time slices). The plan is
read out forwards in exact time: from the vehicle's state ``(p, t)`` its drift is integrated step by step
with the problem's own propagator from ``t``, and the next move is the cheapest of

- drifting on into the goal disk;
- taking off at a drift step ``s`` and flying to a landing node ``q`` (or the goal): the price of the drift
  to ``s``, the flight, and ``V(q, t_s + flight time)``;

then the vehicle is at ``(q, t_s + flight time)`` and the read-out repeats (:func:`read_out`). Flights go
straight; with limited legs a longer flight is a chain of equal legs landing on free water.

The landing points are then refined (:func:`refine_in_time`): around every landing (and around the goal,
where a landing just upstream of the goal disk can drift in) a fine grid of candidates is drifted from the
time the plan lands there, and a backward dynamic programme over these clouds picks the best take-off step
and candidate at every stage, with ``V`` as the alternative at each one. Each round is flown exactly
(:func:`fly_legs`) and kept only if its objective is lower; the next round searches a quarter of the extent.

Powered legs in the water (a boat carried by the current, :mod:`oceanloc.models.powered`) move between
lattice nodes within the stencil's reach: :func:`read_out_water` steps the vehicle one drift step or one
leg at a time, and :func:`refine_water` moves each waypoint of the track over a local cloud with a forward
dynamic programme in arrival time. Every reported figure is the exact cost of the plan as flown.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.direct import prefer_direct
from oceanloc.planning.drift_rrt.lattice_values import Leg
from oceanloc.planning.drift_rrt.problem import (
    DriftPlanResult,
    DriftProblem,
    PlanBudget,
    PlanStatus,
    arrived_result,
)
from oceanloc.planning.drift_rrt.propagation import Rollout
from oceanloc.planning.drift_rrt.time_values import TimeLattice, TimeLatticeOptions

__all__ = ["DEFAULT_TIME_OPTIONS", "fly_legs", "plan_in_time"]

DEFAULT_TIME_OPTIONS = TimeLatticeOptions()
"""The settings measured in the benchmark."""

MIN_HOP = 0.5
"""The read-out's shortest hop to a lattice node, as a fraction of the spacing: a shorter one only chases
the error of the value between nodes (the refinement still shortens hops)."""

CANDIDATE_BATCH = 64
"""Best candidates checked at once for a feasible flight (no-fly obstacles, chains of legs)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class FlownPlan:
    """A plan's legs, the path they fly and its exact objective (in the problem's unit)."""

    legs: list[Leg]
    path: DriftPath
    objective: float
    reaches: bool


def fly_legs(problem: DriftProblem, legs: list[Leg]) -> DriftPath | None:
    """Fly ``legs`` exactly from the problem's start and start time: each leg drifts its steps from the
    time it begins (stopping early where the drift would leave the valid space), then a powered leg goes
    straight to its landing point. ``None`` if a powered leg is infeasible (in the water: a current that
    does not let the vehicle hold the course)."""
    prop, space = problem.propagator, problem.space
    t = float(problem.t0_s)
    pos = np.asarray(problem.start_m, dtype=float)
    points: list[FloatArray] = [pos[None]]
    times: list[float] = [t]
    flags: list[bool] = []
    for leg in legs:
        if leg.drift_steps:
            poly = prop.drift_polyline(space, pos, leg.drift_steps, t0_s=t)
            m = poly.shape[0] - 1
            if m:
                points.append(poly[1:])
                times.extend((t + prop.dt_s * np.arange(1, m + 1)).tolist())
                flags.extend([False] * m)
                t += prop.dt_s * m
                pos = poly[-1]
        if leg.landing is None:
            break
        landing = np.asarray(leg.landing, dtype=float)
        tau, ok = problem.leg_times_s(pos, landing, t)
        if not bool(ok):
            return None
        t += float(tau)
        pos = landing
        points.append(pos[None])
        times.append(t)
        flags.append(True)
        if leg.to_goal:
            break
    return DriftPath(
        points_m=np.concatenate(points), times_s=np.asarray(times), flight=np.asarray(flags, bool)
    )


def evaluate(problem: DriftProblem, legs: list[Leg] | None) -> FlownPlan | None:
    """Fly ``legs`` and score them (``None`` if they cannot be flown)."""
    if not legs:
        return None
    path = fly_legs(problem, legs)
    if path is None:
        return None
    end = path.end_m
    reaches = bool(
        np.linalg.norm(end - problem.goal_m) < problem.goal_tolerance_m or np.allclose(end, problem.goal_m)
    )
    objective = problem.objective_of(path) if reaches else math.inf
    return FlownPlan(legs=legs, path=path, objective=objective, reaches=reaches)


def drift_from(
    tl: TimeLattice, points: FloatArray, t0_s: FloatArray, n_steps: int, stride: int = 1
) -> Rollout:
    """Drift ``(P, 2)`` points, each from its own time, ``n_steps`` steps with the problem's propagator."""
    p = tl.problem
    return p.propagator.rollout(
        p.space,
        points,
        max(int(n_steps), 0),
        goal_m=p.goal_m,
        goal_tolerance_m=p.goal_tolerance_m,
        stride=stride,
        t0_s=np.asarray(t0_s, dtype=float),
    )


def drift_one(tl: TimeLattice, start_m: FloatArray, t_s: float, n_steps: int, stride: int = 1) -> Rollout:
    """:func:`drift_from` for one point, stepped on Python floats (the fields' scalar paths)."""
    p = tl.problem
    poly = p.propagator.drift_polyline(p.space, start_m, max(int(n_steps), 0), t0_s=t_s)
    n_samples = max(int(n_steps), 0) // stride + 1
    samples = np.full((n_samples, 1, 2), np.nan)
    idx = np.arange(0, poly.shape[0], stride)
    samples[: idx.size, 0] = poly[idx]
    d = np.hypot(poly[:, 0] - p.goal_m[0], poly[:, 1] - p.goal_m[1])
    inside = np.flatnonzero(d < p.goal_tolerance_m)
    k = int(inside[0]) if inside.size else int(np.argmin(d))
    return Rollout(
        samples_m=samples,
        sample_steps=np.arange(n_samples) * stride,
        goal_distance_m=np.array([d[k]]),
        goal_step=np.array([k]),
        reaches_goal=np.array([inside.size > 0]),
        closest_m=poly[k][None].copy(),
        end_step=np.array([poly.shape[0] - 1]),
    )


def steps_left(tl: TimeLattice, t_s: float) -> int:
    """Whole drift steps between ``t_s`` and the end of the planning window."""
    return max(math.floor((tl.t_end - t_s) / tl.problem.propagator.dt_s + 1e-9), 0)


# -- the read-out in the air -----------------------------------------------------------------------------


def flight_legs(
    tl: TimeLattice, drift_steps: int, takeoff: FloatArray, landing: FloatArray, to_goal: bool
) -> list[Leg]:
    """One flight as legs: straight, or equal legs landing on free water when longer than a leg."""
    d = float(np.linalg.norm(landing - takeoff))
    n = 1 if not math.isfinite(tl.leg) else max(1, math.ceil(d / tl.leg - 1e-12))
    stops = [takeoff + (landing - takeoff) * i / n for i in range(1, n)] + [np.asarray(landing, dtype=float)]
    legs = [
        Leg(drift_steps=drift_steps, takeoff=takeoff.copy(), landing=stops[0], to_goal=to_goal and n == 1)
    ]
    for i in range(1, n):
        legs.append(
            Leg(drift_steps=0, takeoff=stops[i - 1], landing=stops[i], to_goal=to_goal and i == n - 1)
        )
    return legs


def _flight_ok(tl: TimeLattice, takeoff: FloatArray, landing: FloatArray) -> np.ndarray:
    """``(...)`` bool: the flights ``takeoff -> landing`` can be flown (no-fly zones, free leg landings)."""
    space = tl.problem.space
    ok = np.ones(np.broadcast_shapes(takeoff.shape, landing.shape)[:-1], dtype=bool)
    if space.flights_avoid_obstacles:
        ok &= space.flight_valid(takeoff, landing)
    if math.isfinite(tl.leg):
        ok &= tl._split_ok(np.broadcast_to(takeoff, (*ok.shape, 2)), np.broadcast_to(landing, (*ok.shape, 2)))
    return ok


def _choose_flight(
    tl: TimeLattice, z: FloatArray, total: FloatArray, targets: FloatArray
) -> tuple[float, int, int]:
    """Cheapest feasible ``(value, sample, target)`` of ``total (S, C)``: flights ``z[s] -> targets[c]``."""
    flat = total.ravel()
    k = int(np.argmin(flat))
    if not math.isfinite(flat[k]):
        return math.inf, -1, -1
    s, c = divmod(k, total.shape[1])
    if bool(_flight_ok(tl, z[s], targets[c])):
        return float(flat[k]), s, c
    finite = np.flatnonzero(np.isfinite(flat))
    order = finite[np.argsort(flat[finite], kind="stable")]
    for lo in range(0, min(order.size, 16 * CANDIDATE_BATCH), CANDIDATE_BATCH):
        idx = order[lo : lo + CANDIDATE_BATCH]
        s, c = np.divmod(idx, total.shape[1])
        ok = _flight_ok(tl, z[s], targets[c])
        if ok.any():
            i = int(np.flatnonzero(ok)[0])
            return float(flat[idx[i]]), int(s[i]), int(c[i])
    return math.inf, -1, -1


def read_out(tl: TimeLattice, start_m: FloatArray, t_s: float) -> list[Leg] | None:
    """Greedy read-out of the plan from ``(start_m, t_s)`` in exact time (see the module docstring)."""
    p = tl.problem
    dt = p.propagator.dt_s
    price = tl.price
    free = tl.free_idx
    lands = tl.nodes[free]
    pos = np.asarray(start_m, dtype=float)
    t = float(t_s)
    legs: list[Leg] = []
    for _ in range(tl.opts.max_flights):
        n = steps_left(tl, t)
        roll = drift_one(tl, pos, t, n, tl.opts.stride)
        z = roll.samples_m[:, 0]
        steps = roll.sample_steps
        finish = price * dt * float(roll.goal_step[0]) if bool(roll.reaches_goal[0]) else math.inf
        valid = np.isfinite(z[:, 0])
        zs, ss = z[valid], steps[valid]
        ts = t + ss * dt
        drift_cost = price * dt * ss
        dist = np.hypot(zs[:, None, 0] - lands[None, :, 0], zs[:, None, 1] - lands[None, :, 1])
        dist[dist < MIN_HOP * tl.h] = np.inf  # hops shorter than this chase the value's noise
        arrive = ts[:, None] + dist / tl.speed
        total = drift_cost[:, None] + dist + tl.node_value(free[None, :], arrive)
        goal_d = np.hypot(zs[:, 0] - tl.goal[0], zs[:, 1] - tl.goal[1])
        goal_total = drift_cost + goal_d
        if tl.deadline is not None:
            goal_total = np.where(ts + goal_d / tl.speed <= tl.deadline + 1e-9, goal_total, np.inf)
        targets = np.concatenate([lands, tl.goal[None]], axis=0)
        v, s, c = _choose_flight(tl, zs, np.concatenate([total, goal_total[:, None]], axis=1), targets)
        if finish <= v:
            if not math.isfinite(finish):
                return None
            legs.append(Leg(drift_steps=int(roll.goal_step[0]), takeoff=None, landing=None, to_goal=False))
            return legs
        to_goal = c == lands.shape[0]
        takeoff, landing = zs[s], targets[c]
        legs.extend(flight_legs(tl, int(ss[s]), takeoff, landing, to_goal))
        if to_goal:
            return legs
        t = float(ts[s]) + float(np.linalg.norm(landing - takeoff)) / tl.speed
        pos = landing.copy()
    # Out of flights: go straight to the goal from where the vehicle is.
    return legs + flight_legs(tl, 0, pos.copy(), tl.goal.copy(), True)


# -- refinement in the air -------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, kw_only=True)
class Stages:
    """Landing points of a plan, when the vehicle lands there, when it takes off from there and when it
    took off to land there; the goal's stage last."""

    points: list[FloatArray]
    times: list[float]
    next_takeoff: list[float]
    takeoff_into: list[float]


def plan_stages(problem: DriftProblem, plan: FlownPlan) -> Stages | None:
    """Every landing of ``plan``: where, when the vehicle lands, when it takes off again and when it took
    off to land there. The last is the landing from which the vehicle drifts into the goal disk, or the
    goal itself. ``None`` for a plan without flights."""
    path = plan.path
    edges = np.flatnonzero(path.flight)
    if edges.size == 0:
        return None
    points = [path.points_m[e + 1].copy() for e in edges]
    times = [float(path.times_s[e + 1]) for e in edges]
    into = [float(path.times_s[e]) for e in edges]
    takeoffs = [float(path.times_s[f]) for f in edges[1:]] + [float(path.times_s[-1])]
    return Stages(points=points, times=times, next_takeoff=takeoffs, takeoff_into=into)


def _cloud(tl: TimeLattice, centre: FloatArray, half_extent_m: float) -> FloatArray:
    w = tl.opts.cloud_half_width
    ticks = np.linspace(-half_extent_m, half_extent_m, 2 * w + 1)
    ox, oy = np.meshgrid(ticks, ticks)
    c = centre[None, :] + np.column_stack([ox.ravel(), oy.ravel()])
    return c[tl.problem.space.is_valid(c)]


SKIP = 2
"""In the first round, a stage links to the next ``SKIP`` stages: skipping a landing removes a hop the
read-out made; later rounds link to the next stage only."""

LAYERS = 1
"""Landing-time layers of a refinement cloud on each side of the plan's landing time, one drift step apart:
a link may take off up to this many steps earlier or later than the plan did."""


@dataclass(frozen=True, slots=True, kw_only=True)
class StageChoice:
    """Best continuation of each particle (layer-major: ``layer * candidates + candidate``) of a stage:
    value, take-off sample, and the stage, layer and candidate landed on (stage ``-1``: none)."""

    value: FloatArray
    sample: np.ndarray
    stage: np.ndarray
    layer: np.ndarray
    target: np.ndarray


def drift_batch(tl: TimeLattice, points: FloatArray, t0_s: FloatArray, n_steps: np.ndarray) -> FloatArray:
    """``(S + 1, P, 2)`` drift samples at every step of ``(P, 2)`` points, each from its own time for its
    own number of steps (NaN after that, or once the drift leaves the valid space)."""
    p = tl.problem
    prop, space = p.propagator, p.space
    from oceanloc.models.drift import step_function

    step = step_function(prop.method)
    n_steps = np.asarray(n_steps, dtype=np.int64)
    total = int(n_steps.max(initial=0))
    out = np.full((total + 1, points.shape[0], 2), np.nan)
    ok0 = space.is_valid(points)
    out[0, ok0] = points[ok0]
    active = np.flatnonzero(ok0 & (n_steps > 0))
    x, y = points[active, 0].copy(), points[active, 1].copy()
    t = np.asarray(t0_s, dtype=float)[active].copy()
    dt = prop.dt_s
    for k in range(1, total + 1):
        if active.size == 0:
            break
        xn, yn = step(prop.field, x, y, t, dt)
        ok = np.isfinite(xn) & np.isfinite(yn)
        ok[ok] = space.is_valid_xy(xn[ok], yn[ok])
        keep = ok & (n_steps[active] > k)
        out[k, active[ok], 0] = xn[ok]
        out[k, active[ok], 1] = yn[ok]
        active, x, y, t = active[keep], xn[keep], yn[keep], t[keep] + dt
    return out


def _link_layers(
    tl: TimeLattice,
    samples: FloatArray,
    sample_t: FloatArray,
    tcost: FloatArray,
    targets: FloatArray,
    target_values: FloatArray,
    land_t0: float,
    takeoff_t: float,
) -> tuple[FloatArray, np.ndarray, np.ndarray, np.ndarray]:
    """Best ``(value, sample, layer, target)`` of each particle: take off at a sample ``(S, P, 2)``
    near ``takeoff_t`` and land on a candidate of ``targets (M, 2)``, whose value at the landing time is
    interpolated between its layers ``target_values (2 L + 1, M)`` (layer ``L`` lands at ``land_t0``)."""
    p = tl.problem
    dt = p.propagator.dt_s
    n_p = samples.shape[1]
    out_v = np.full(n_p, np.inf)
    out_s = np.zeros(n_p, dtype=np.intp)
    out_l = np.zeros(n_p, dtype=np.intp)
    out_c = np.zeros(n_p, dtype=np.intp)
    window = (LAYERS + 1.5) * dt
    near = (np.abs(sample_t - takeoff_t) <= window) & np.isfinite(samples[..., 0])
    s_idx, p_idx = np.nonzero(near)
    finite = np.isfinite(target_values)
    if s_idx.size == 0 or not finite.any():
        return out_v, out_s, out_l, out_c
    # Prune take-offs that cannot beat their particle's best bound (distance to the cloud's centre).
    z = samples[s_idx, p_idx]
    centre = targets[finite.any(axis=0)].mean(axis=0)
    radius = float(np.max(np.hypot(*(targets[finite.any(axis=0)] - centre).T)))
    dc = np.hypot(z[:, 0] - centre[0], z[:, 1] - centre[1])
    tc = tcost[s_idx, p_idx]
    upper = np.full(n_p, np.inf)
    np.minimum.at(upper, p_idx, tc + dc + radius + float(target_values[finite].max()))
    keep = tc + np.maximum(dc - radius, 0.0) + float(target_values[finite].min()) <= upper[p_idx] + 1e-9
    s_idx, p_idx, z = s_idx[keep], p_idx[keep], z[keep]
    dist = np.hypot(z[:, None, 0] - targets[None, :, 0], z[:, None, 1] - targets[None, :, 1])
    dist[dist < 1e-6] = np.inf  # landing where the vehicle is is drifting on
    # The landing layer of a take-off, from the flight to the cloud's centre (flight times across a cloud
    # differ by seconds); the value is interpolated between the two layers around it.
    f = (sample_t[s_idx, p_idx] + dc[keep] / tl.speed - land_t0) / dt + LAYERS
    inside = (f >= -1e-9) & (f <= 2 * LAYERS + 1e-9)
    f = np.clip(f, 0.0, 2 * LAYERS)
    lo = np.minimum(f.astype(np.intp), max(2 * LAYERS - 1, 0))
    w = (f - lo)[:, None]
    v_lo = target_values[lo]
    v_hi = target_values[np.minimum(lo + 1, 2 * LAYERS)]
    with np.errstate(invalid="ignore"):
        val = v_lo + (v_hi - v_lo) * w
    val = np.where(np.isnan(val), np.where(w > 0.5, v_hi, v_lo), val)
    val[~inside] = np.inf
    if math.isfinite(tl.leg):
        dist = np.where(dist <= tl.leg, dist, np.inf)
    if p.space.flights_avoid_obstacles:
        shape = (z.shape[0], targets.shape[0], 2)
        ok = p.space.flight_valid(
            np.broadcast_to(z[:, None, :], shape), np.broadcast_to(targets[None], shape)
        )
        dist = np.where(ok, dist, np.inf)
    total = tcost[s_idx, p_idx][:, None] + dist + val
    c_best = np.argmin(total, axis=1)
    rows = np.arange(total.shape[0])
    v_best = total[rows, c_best]
    order = np.lexsort((v_best, p_idx))
    first = order[np.flatnonzero(np.diff(np.concatenate([[-1], p_idx[order]])) != 0)]
    pp = p_idx[first]
    out_v[pp] = v_best[first]
    out_s[pp] = s_idx[first]
    out_l[pp] = np.rint(f[first]).astype(np.intp)
    out_c[pp] = c_best[first]
    return out_v, out_s, out_l, out_c


def _best_link(tl, samples, sample_t, tcost, clouds, values, stages_to, stages) -> StageChoice:
    n_p = samples.shape[1]
    best = StageChoice(
        value=np.full(n_p, np.inf),
        sample=np.zeros(n_p, dtype=np.intp),
        stage=np.full(n_p, -1, dtype=np.intp),
        layer=np.zeros(n_p, dtype=np.intp),
        target=np.zeros(n_p, dtype=np.intp),
    )
    for j in stages_to:
        v, s, lay, c = _link_layers(
            tl, samples, sample_t, tcost, clouds[j], values[j], stages.times[j], stages.takeoff_into[j]
        )
        better = v < best.value
        best = StageChoice(
            value=np.where(better, v, best.value),
            sample=np.where(better, s, best.sample),
            stage=np.where(better, j, best.stage),
            layer=np.where(better, lay, best.layer),
            target=np.where(better, c, best.target),
        )
    return best


def refine_in_time(
    tl: TimeLattice,
    plan: FlownPlan,
    half_extent_m: float,
    *,
    skip: int = SKIP,
    start: Rollout | None = None,
) -> list[Leg] | None:
    """One round of local refinement of ``plan``'s landing points and times (see the module docstring): a
    backward dynamic programme over clouds of candidates around the landings, each drifted from a few
    landing times around the plan's, linking to the next ``skip`` stages (so a landing can be dropped).
    ``start``: the drift from the start, if already computed."""
    p = tl.problem
    dt = p.propagator.dt_s
    stages = plan_stages(p, plan)
    if stages is None:
        return None
    n = len(stages.points)
    clouds = [_cloud(tl, c, half_extent_m) for c in stages.points]
    # Flying straight to the goal stays a candidate of the last stage.
    clouds[-1] = np.vstack([clouds[-1], p.goal_m[None]])
    if any(c.shape[0] == 0 for c in clouds):
        return None
    offsets = dt * np.arange(-LAYERS, LAYERS + 1)
    nl = offsets.size
    pts, t0s, steps, sizes = [], [], [], []
    for i in range(n - 1):
        until = stages.takeoff_into[min(i + skip, n - 1)] + (LAYERS + 2) * dt
        k = max(1, math.ceil((until - stages.times[i] + LAYERS * dt) / dt))
        k = min(k, steps_left(tl, stages.times[i] - LAYERS * dt))
        pts.append(np.tile(clouds[i], (nl, 1)))
        t0s.append(np.repeat(stages.times[i] + offsets, clouds[i].shape[0]))
        steps.append(np.full(nl * clouds[i].shape[0], k))
        sizes.append(nl * clouds[i].shape[0])
    # The last stage drifts into the goal disk: a little longer than the plan's own drift in.
    g = clouds[-1]
    speed = _goal_speed(p, stages.times[-1])
    reach = 2.0 * (half_extent_m + p.goal_tolerance_m) / max(speed, 0.05)
    span = 1.25 * (stages.next_takeoff[-1] - stages.times[-1]) + reach + LAYERS * dt
    pts.append(np.tile(g, (nl, 1)))
    t0s.append(np.repeat(stages.times[-1] + offsets, g.shape[0]))
    steps.append(
        np.full(nl * g.shape[0], min(math.ceil(span / dt), steps_left(tl, stages.times[-1] - LAYERS * dt)))
    )
    sizes.append(nl * g.shape[0])
    if half_extent_m <= LINEAR_EXTENT * tl.h:
        trajs = _linear_trajectories(tl, stages, clouds, offsets, [int(k[0]) for k in steps], half_extent_m)
    else:
        all_samples = drift_batch(tl, np.concatenate(pts), np.concatenate(t0s), np.concatenate(steps))
        bounds = np.cumsum([0, *sizes])
        trajs = [all_samples[:, bounds[i] : bounds[i + 1]] for i in range(n)]
    goal_traj = trajs.pop()
    d2 = (goal_traj[..., 0] - p.goal_m[0]) ** 2 + (goal_traj[..., 1] - p.goal_m[1]) ** 2
    inside = d2 < p.goal_tolerance_m**2
    reaches = inside.any(axis=0)
    goal_step = np.argmax(inside, axis=0)
    values: list[FloatArray] = [np.empty((nl, 0))] * n
    values[-1] = np.where(reaches, tl.price * dt * goal_step, np.inf).reshape(nl, -1)
    goal_roll = (reaches, goal_step)
    choices: list[StageChoice | None] = [None] * n
    for i in range(n - 2, -1, -1):
        samples = trajs[i]
        sample_steps = np.arange(samples.shape[0])[:, None]
        t_start = np.repeat(stages.times[i] + offsets, clouds[i].shape[0])[None, :]
        tcost = np.broadcast_to(tl.price * dt * sample_steps, samples.shape[:2]).astype(float)
        to = list(range(i + 1, min(i + skip, n - 1) + 1))
        ch = _best_link(tl, samples, t_start + dt * sample_steps, tcost, clouds, values, to, stages)
        values[i] = ch.value.reshape(nl, -1)
        choices[i] = ch
    return _forward(tl, stages, clouds, trajs, goal_roll, values, choices, skip, start)


LINEAR_EXTENT = 0.1
"""Clouds at most this fraction of the lattice spacing across drift as the linearization of the flow about
their centre (three drifts per landing time instead of one per candidate); the plan is flown exactly."""


def _linear_trajectories(tl, stages, clouds, offsets, steps, half_extent_m) -> list[FloatArray]:
    """``(S + 1, layers * M, 2)`` drifts of every stage's candidates from the flow's linearization about
    the stage's centre: the centre and two points ``half_extent_m`` east and north are drifted from each
    landing time, and a candidate follows ``z0 + J (c - centre)``."""
    nl = offsets.size
    delta = max(half_extent_m, 1e-3)
    pts, t0s, ks = [], [], []
    for i, centre in enumerate(stages.points):
        trio = np.array([centre, centre + np.array([delta, 0.0]), centre + np.array([0.0, delta])])
        pts.append(np.tile(trio, (nl, 1)))
        t0s.append(np.repeat(stages.times[i] + offsets, 3))
        ks.append(np.full(3 * nl, steps[i]))
    samples = drift_batch(tl, np.concatenate(pts), np.concatenate(t0s), np.concatenate(ks))
    out = []
    for i, centre in enumerate(stages.points):
        block = samples[: steps[i] + 1, 3 * nl * i : 3 * nl * (i + 1)].reshape(-1, nl, 3, 2)
        z0 = block[:, :, 0]
        jx = (block[:, :, 1] - z0) / delta
        jy = (block[:, :, 2] - z0) / delta
        off = clouds[i] - centre  # (M, 2)
        traj = (
            z0[:, :, None]
            + jx[:, :, None] * off[None, None, :, 0:1]
            + jy[:, :, None] * off[None, None, :, 1:2]
        )
        # Candidates start exactly where they are, and stop where their drift would leave the valid space.
        traj[0] = np.broadcast_to(clouds[i][None], (nl, clouds[i].shape[0], 2))
        traj = traj.reshape(traj.shape[0], nl * clouds[i].shape[0], 2)
        bad = ~tl.problem.space.is_valid(traj)
        traj[np.cumsum(bad, axis=0) > 0] = np.nan
        out.append(traj)
    return out


def _goal_speed(problem: DriftProblem, t_s: float) -> float:
    gu, gv = problem.propagator.field.velocity_xy(float(problem.goal_m[0]), float(problem.goal_m[1]), t_s)
    return math.hypot(gu, gv) if math.isfinite(gu + gv) else 0.0


def start_drift(tl: TimeLattice) -> Rollout:
    """The drift from the start over the whole planning window, every step."""
    p = tl.problem
    return drift_one(tl, p.start_m, p.t0_s, steps_left(tl, p.t0_s))


def _forward(tl, stages, clouds, trajs, goal_roll, values, choices, skip, start) -> list[Leg] | None:
    """The legs of the refined plan: from the start into a cloud, from cloud to cloud, then drifting from
    the goal cloud into the disk."""
    p = tl.problem
    dt = p.propagator.dt_s
    n = len(clouds)
    roll = start if start is not None else start_drift(tl)
    samples = roll.samples_m
    tcost = tl.price * dt * roll.sample_steps[:, None].astype(float)
    sample_t = p.t0_s + dt * roll.sample_steps[:, None]
    first = _best_link(tl, samples, sample_t, tcost, clouds, values, list(range(0, min(skip, n))), stages)
    if not math.isfinite(first.value[0]):
        return None
    legs: list[Leg] = []
    cur = 0
    s, j, lay, c = int(first.sample[0]), int(first.stage[0]), int(first.layer[0]), int(first.target[0])
    while True:
        landing = clouds[j][c]
        to_goal = j == n - 1 and bool(np.allclose(landing, p.goal_m))
        legs.extend(flight_legs(tl, s, samples[s, cur].copy(), landing, to_goal))
        if to_goal:
            return legs
        cur = lay * clouds[j].shape[0] + c
        if j == n - 1:
            break
        ch = choices[j]
        if ch.stage[cur] < 0:
            return None
        samples = trajs[j]
        s, j, lay, c = int(ch.sample[cur]), int(ch.stage[cur]), int(ch.layer[cur]), int(ch.target[cur])
    reaches, goal_step = goal_roll
    if not bool(reaches[cur]):
        return None
    legs.append(Leg(drift_steps=int(goal_step[cur]), takeoff=None, landing=None, to_goal=False))
    return legs


# -- the planner -----------------------------------------------------------------------------------------


def plan_in_time(
    problem: DriftProblem,
    rng: np.random.Generator,
    budget: PlanBudget | None = None,
    options: TimeLatticeOptions | None = None,
) -> DriftPlanResult:
    """Plan with the value over (node, time) (see the module docstring).

    Parameters
    ----------
    problem : DriftProblem
        Any field (steady or not), objective (energy, time, energy with a deadline) and propulsion.
    rng : numpy.random.Generator
        Draws the lattice's offset when ``options.random_offset``.
    budget : PlanBudget, optional
        Unused: the effort is set by ``options``.
    options : TimeLatticeOptions, optional
        :data:`DEFAULT_TIME_OPTIONS` by default.
    """
    opts = options or DEFAULT_TIME_OPTIONS
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
    offset = rng.uniform(0.0, 1.0, 2) if opts.random_offset else np.zeros(2)
    tl = TimeLattice(problem, opts, offset)
    tl.solve()
    if problem.in_water:
        from oceanloc.planning.drift_rrt.time_water import read_out_water, refine_water

        best = evaluate(problem, read_out_water(tl, problem.start_m, problem.t0_s))
        for r in range(opts.refine_rounds if best is not None else 0):
            cand = refine_water(tl, best, tl.h / 2.0 ** (r + 1))
            if cand is not None and cand.objective < best.objective - 1e-12:
                best = cand
    else:
        best = evaluate(problem, read_out(tl, problem.start_m, problem.t0_s))
        extent = tl.h
        start = start_drift(tl)
        for r in range(opts.refine_rounds if best is not None else 0):
            cand = evaluate(
                problem, refine_in_time(tl, best, extent, skip=SKIP if r == 0 else 1, start=start)
            )
            extent /= 4.0
            if cand is not None and cand.objective < best.objective - 1e-12:
                best = cand
    start_value = float(tl.value_at(problem.start_m[None], problem.t0_s)[0]) * tl.unit
    where = (
        f"lattice in time {tl.h:.0f} m x {tl.delta / 60:.0f} min ({tl.free_idx.size} free nodes, "
        f"{tl.n_slices} slices), value at the start {start_value:.4g} {problem.objective_unit}"
    )
    if best is None:
        failed = DriftPlanResult(
            status=PlanStatus.FAILED,
            path=None,
            flight_energy_wh=math.inf,
            direct_flight_wh=direct,
            compute_s=time.perf_counter() - tic,
            message=f"no drift/flight sequence reaches the goal {_window_text(problem)}; {where}",
        )
        return prefer_direct(problem, failed, _measure)
    if not math.isfinite(best.objective):
        late = DriftPlanResult(
            status=PlanStatus.FAILED,
            path=None,
            flight_energy_wh=math.inf,
            direct_flight_wh=direct,
            compute_s=time.perf_counter() - tic,
            message=f"no plan reaches the goal {_window_text(problem)}; {where}",
        )
        return prefer_direct(problem, late, _measure)
    result = DriftPlanResult(
        status=PlanStatus.EXACT if best.reaches else PlanStatus.APPROXIMATE,
        path=best.path,
        flight_energy_wh=problem.powered_energy_wh(best.path),
        direct_flight_wh=direct,
        compute_s=time.perf_counter() - tic,
        iterations=int(tl.free_idx.size * tl.n_slices),
        solutions=1 if best.reaches else 0,
        cost=best.objective,
        message=f"{where}, {best.path.hops_m().shape[0]} powered leg(s)",
    )
    return prefer_direct(problem, result, _measure)


def _window_text(problem: DriftProblem) -> str:
    if problem.max_duration_s is not None:
        return f"by the deadline ({problem.max_duration_s / 3600:g} h after the start)"
    return f"within the planning window ({problem.horizon_s / 3600:g} h)"


def _measure(problem: DriftProblem, path: DriftPath) -> float:
    return problem.objective_of(path)


def start_value(tl: TimeLattice) -> float:
    """The lattice's value of the start, in the problem's objective unit."""
    return float(tl.value_at(tl.problem.start_m[None], tl.problem.t0_s)[0]) * tl.unit
