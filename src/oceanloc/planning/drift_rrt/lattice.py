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
made of legs of at most that length landing on free lattice nodes. The field is taken as steady: every
trajectory is integrated from the problem's start time.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Literal

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.planning.drift_rrt.path import DriftPath
from oceanloc.planning.drift_rrt.problem import DriftProblem, PlanBudget, PlanResult, PlanStatus

EnvelopeKind = Literal["dense", "stencil"]


@dataclass(frozen=True, slots=True, kw_only=True)
class LatticeOptions:
    """Resolution and effort of the lattice search.

    Attributes
    ----------
    spacing_m : float
        Lattice spacing ``h`` of the landing points.
    stride : int
        Drift steps between take-off candidates along a trajectory.
    max_value_iterations : int
        Value-iteration sweeps (each allows one more flight).
    envelope : {"dense", "stencil"}
        Flight envelope: exact dense distance matrix (coarse lattices) or stencil relaxation (fine ones).
    stencil_radius : int
        Stencil moves ``(a, b)`` with ``a^2 + b^2 <= r^2`` and ``gcd(a, b) = 1``.
    refine_rounds : int
        Rounds of local refinement of the landing points.
    cloud_half_width : int
        A refinement cloud has ``(2 w + 1)^2`` candidates spanning plus or minus one lattice spacing in
        the first round, a quarter of that in the next.
    random_offset : bool
        Shift the lattice by a random fraction of ``h`` drawn from the planner's generator.
    max_flights : int
        Safety cap on the number of flights in a plan.
    """

    spacing_m: float = 300.0
    stride: int = 4
    max_value_iterations: int = 12
    envelope: EnvelopeKind = "dense"
    stencil_radius: int = 6
    refine_rounds: int = 2
    cloud_half_width: int = 4
    random_offset: bool = True
    max_flights: int = 64

    def __post_init__(self) -> None:
        if not self.spacing_m > 0:
            raise ConfigError(f"lattice spacing must be positive, got {self.spacing_m}")
        if self.stride < 1 or self.max_value_iterations < 1 or self.max_flights < 1:
            raise ConfigError("stride, max_value_iterations and max_flights must be at least 1")
        if self.envelope not in ("dense", "stencil"):
            raise ConfigError(f"envelope must be 'dense' or 'stencil', got '{self.envelope}'")
        if self.refine_rounds < 0 or self.cloud_half_width < 1 or self.stencil_radius < 1:
            raise ConfigError(
                "refine_rounds >= 0, cloud_half_width >= 1 and stencil_radius >= 1 are required"
            )


@dataclass(frozen=True, slots=True)
class _Traj:
    """Sampled drift of a set of points: take-off candidates and how each one can finish."""

    points: FloatArray  # (P, 2)
    samples: FloatArray  # (S + 1, P, 2), last row: closest approach to the goal; NaN if invalid
    steps: IntArray  # (S + 1, P) drift steps to each sample
    reaches: BoolArray  # (P,) drift enters the goal disk
    goal_step: IntArray  # (P,)
    time_cost: FloatArray  # (S + 1, P) price of the drift time to each sample, metres of flight
    finish: FloatArray  # (P,) price of drifting into the goal disk (inf if the drift misses it)
    goal_cost: FloatArray  # (S + 1, P) flight from each sample straight to the goal (inf if not allowed)


@dataclass(frozen=True, slots=True)
class _Leg:
    drift_steps: int
    takeoff: FloatArray | None  # where the drift ends (exact, from the rollout); None: drift into the goal
    landing: FloatArray | None  # None: the drift itself ends in the goal disk
    to_goal: bool


def _legs_objective(problem: DriftProblem, legs: list[_Leg]) -> float:
    """Flight energy plus the price of time of a plan, from its legs (no re-simulation needed)."""
    flown = sum(
        float(np.linalg.norm(leg.landing - leg.takeoff))
        for leg in legs
        if leg.landing is not None and leg.takeoff is not None
    )
    steps = sum(leg.drift_steps for leg in legs)
    hours = (steps * problem.propagator.dt_s + flown / problem.energy.flight_speed_mps) / 3600.0
    return float(problem.energy.flight_energy_wh(flown)) + problem.time_weight_wh_per_h * hours


def _trajectories(problem: DriftProblem, points: FloatArray, stride: int) -> _Traj:
    roll = problem.propagator.rollout(
        problem.space,
        points,
        problem.horizon_steps,
        goal_m=problem.goal_m,
        goal_tolerance_m=problem.goal_tolerance_m,
        stride=stride,
        t0_s=problem.t0_s,
    )
    samples = np.concatenate([roll.samples_m, roll.closest_m[None]], axis=0)
    n = points.shape[0]
    steps = np.concatenate([np.repeat(roll.sample_steps[:, None], n, axis=1), roll.goal_step[None]], axis=0)
    price = problem.time_weight_m_per_s * problem.propagator.dt_s
    time_cost = steps * price
    finish = np.where(roll.reaches_goal, roll.goal_step * price, np.inf)
    goal_cost = _goal_flight(problem, samples)
    return _Traj(
        goal_cost=goal_cost,
        points=points,
        samples=samples,
        steps=steps,
        reaches=roll.reaches_goal,
        goal_step=roll.goal_step,
        time_cost=time_cost,
        finish=finish,
    )


def _goal_flight(problem: DriftProblem, z: FloatArray) -> FloatArray:
    """Flight distance from ``(..., 2)`` points straight to the goal: ``inf`` for NaN points, beyond one leg,
    or across a no-fly obstacle."""
    goal = problem.goal_m
    ex = z[..., 0] - goal[0]
    ey = z[..., 1] - goal[1]
    d = np.sqrt(ex * ex + ey * ey)
    d[~np.isfinite(d)] = np.inf
    if problem.space.flights_avoid_obstacles:
        ok = problem.space.flight_valid(np.where(np.isfinite(z), z, 0.0), goal)
        d = np.where(ok, d, np.inf)
    if problem.max_leg_m is not None:
        d[d > problem.max_leg_m] = np.inf
    return d


class _ValueLattice:
    """Lattice, flight envelope and value iteration (step 1 and 2 of the module docstring)."""

    def __init__(self, problem: DriftProblem, opts: LatticeOptions, offset: FloatArray) -> None:
        self.problem = problem
        self.opts = opts
        x0, x1, y0, y1 = problem.space.bounds_m
        h = opts.spacing_m
        self.xs = np.arange(x0 + offset[0], x1 + 1e-9, h)
        self.ys = np.arange(y0 + offset[1], y1 + 1e-9, h)
        gx, gy = np.meshgrid(self.xs, self.ys)
        self.nodes = np.column_stack([gx.ravel(), gy.ravel()])
        self.free_idx = np.flatnonzero(problem.space.is_valid(self.nodes))
        self.goal = problem.goal_m
        self.leg = math.inf if problem.max_leg_m is None else float(problem.max_leg_m)
        # Landing points: free nodes, then the goal (value 0).
        self.landings = np.concatenate([self.nodes[self.free_idx], self.goal[None]], axis=0)
        self.n_free = self.free_idx.size

    def snap(self, z: FloatArray) -> tuple[IntArray, FloatArray]:
        """Nearest lattice node of each ``(..., 2)`` point and the distance to it.

        NaN points get the index ``len(nodes)`` (one past the last node, where envelopes hold ``inf``) and an
        infinite distance.
        """
        h = self.opts.spacing_m
        flat = z.reshape(-1, 2)
        valid = np.flatnonzero(np.isfinite(flat[:, 0]))
        zz = flat[valid]
        i = np.minimum(np.maximum(np.rint((zz[:, 0] - self.xs[0]) / h), 0), self.xs.size - 1).astype(np.intp)
        j = np.minimum(np.maximum(np.rint((zz[:, 1] - self.ys[0]) / h), 0), self.ys.size - 1).astype(np.intp)
        idx = np.full(flat.shape[0], self.nodes.shape[0], dtype=np.intp)
        dist = np.full(flat.shape[0], np.inf)
        idx[valid] = j * self.xs.size + i
        ex = zz[:, 0] - self.xs[i]
        ey = zz[:, 1] - self.ys[j]
        dist[valid] = np.sqrt(ex * ex + ey * ey)
        return idx.reshape(z.shape[:-1]), dist.reshape(z.shape[:-1])

    def goal_flight(self, z: FloatArray) -> FloatArray:
        """Flight distance from ``(..., 2)`` points straight to the goal (``inf`` beyond a leg, or NaN)."""
        return _goal_flight(self.problem, z)

    # -- envelope ---------------------------------------------------------------------------------------
    def build_envelope(self) -> None:
        if self.opts.envelope == "dense":
            nodes = self.nodes.astype(np.float32)
            lands = self.landings.astype(np.float32)
            ex = nodes[:, None, 0] - lands[None, :, 0]
            ey = nodes[:, None, 1] - lands[None, :, 1]
            dist = np.sqrt(ex * ex + ey * ey)
            if self.problem.space.flights_avoid_obstacles:
                shape = (nodes.shape[0], lands.shape[0], 2)
                ok = self.problem.space.flight_valid(
                    np.broadcast_to(self.nodes[:, None, :], shape),
                    np.broadcast_to(self.landings[None], shape),
                )
                dist = np.where(ok, dist, np.float32(np.inf))
            dist[dist > self.leg] = np.inf
            self._dense = dist
        else:
            if math.isfinite(self.leg):
                raise ConfigError(
                    "the stencil envelope lets flights be any length; use max_leg_m = None with it"
                )
            r = self.opts.stencil_radius
            h = self.opts.spacing_m
            moves = [
                (a, b, h * math.hypot(a, b))
                for a in range(-r, r + 1)
                for b in range(-r, r + 1)
                if (a, b) != (0, 0) and math.gcd(abs(a), abs(b)) == 1 and a * a + b * b <= r * r
            ]
            self._moves = moves
            self._blocked = ~self.problem.space.is_valid(self.nodes).reshape(self.ys.size, self.xs.size)

    def envelope(self, landing_values: FloatArray) -> FloatArray:
        """``D`` on every lattice node from the values of the landing points (free nodes, goal)."""
        if self.opts.envelope == "dense":
            lv = landing_values.astype(np.float32)
            d = np.min(self._dense + lv[None, :], axis=1).astype(float)
            d = np.append(d, np.inf)
            if math.isfinite(self.leg):
                # Chain legs through free nodes until nothing improves.
                for _ in range(256):
                    lv2 = lv.copy()
                    lv2[: self.n_free] = np.minimum(lv[: self.n_free], d[self.free_idx])
                    d2 = np.append(np.min(self._dense + lv2[None, :], axis=1).astype(float), np.inf)
                    if np.all(d2 >= d - 1e-9):
                        break
                    d = np.minimum(d, d2)
                    lv = lv2
            return d
        ny, nx = self.ys.size, self.xs.size
        w = np.full(ny * nx, np.inf)
        w[self.free_idx] = landing_values[: self.n_free]
        w = np.minimum(w, self.goal_flight(self.nodes)).reshape(ny, nx)
        no_fly = self.problem.space.flights_avoid_obstacles
        for _ in range(4 * (nx + ny)):
            before = w.copy()
            for a, b, c in self._moves:
                dst_y = slice(max(0, -b), ny - max(0, b))
                src_y = slice(max(0, b), ny - max(0, -b))
                dst_x = slice(max(0, -a), nx - max(0, a))
                src_x = slice(max(0, a), nx - max(0, -a))
                np.minimum(w[dst_y, dst_x], w[src_y, src_x] + c, out=w[dst_y, dst_x])
            if no_fly:
                w[self._blocked] = np.inf
            if np.array_equal(w, before):
                break
        return np.append(w.ravel(), np.inf)

    # -- value iteration ----------------------------------------------------------------------------------
    def solve(self, traj: _Traj) -> None:
        """Values of every particle of ``traj`` (the first ``n_free`` are the free nodes)."""
        self.build_envelope()
        n_idx, n_cost = self.snap(traj.samples)
        n_cost = n_cost + traj.time_cost
        g_cost = traj.goal_cost + traj.time_cost
        values = np.minimum(traj.finish, g_cost.min(axis=0))
        landing_values = np.append(values[: self.n_free], 0.0)
        d = self.envelope(landing_values)
        incremental = self.opts.envelope == "dense" and not math.isfinite(self.leg)
        for _ in range(self.opts.max_value_iterations):
            via = np.min(n_cost + d[n_idx], axis=0)
            new = np.minimum(values, via)
            changed = np.flatnonzero(new[: self.n_free] < values[: self.n_free] - 1e-6)
            values = new
            landing_values = np.append(values[: self.n_free], 0.0)
            if changed.size == 0:
                break
            if incremental:
                # Values only decrease, so only the columns of the landings that changed can lower D.
                cols = self._dense[:, changed] + landing_values[changed].astype(np.float32)[None, :]
                d[:-1] = np.minimum(d[:-1], cols.min(axis=1))
            else:
                d = self.envelope(landing_values)
        self.values = values
        self.d_nodes = d if incremental else self.envelope(landing_values)
        # What a landing point is worth on arrival: drift on (V) or fly on (D).
        self.arrival = landing_values.copy()
        self.arrival[: self.n_free] = np.minimum(landing_values[: self.n_free], self.d_nodes[self.free_idx])
        self.arrival[-1] = 0.0

    def fallback_values(self, traj: _Traj) -> FloatArray:
        """Approximate value of arbitrary particles from the solved lattice (snapped samples)."""
        n_idx, n_cost = self.snap(traj.samples)
        via = np.min(n_cost + traj.time_cost + self.d_nodes[n_idx], axis=0)
        direct = np.min(traj.goal_cost + traj.time_cost, axis=0)
        return np.minimum(np.minimum(traj.finish, direct), via)

    def best_takeoff(
        self, samples: FloatArray, time_cost: FloatArray, goal_cost: FloatArray
    ) -> tuple[float, int, int]:
        """Exact best ``(value, sample index, landing index)`` from one particle's ``(S + 1, 2)`` samples.

        ``time_cost (S + 1,)`` is the price of drifting to each sample, ``goal_cost (S + 1,)`` the flight from
        it straight to the goal.
        """
        valid = np.flatnonzero(np.isfinite(samples[:, 0]))
        if valid.size == 0:
            return math.inf, -1, -1
        # Upper bound: straight to the goal from the best sample; landings worth more cannot help.
        g = goal_cost[valid] + time_cost[valid]
        k = int(np.argmin(g))
        best = (float(g[k]), int(valid[k]), self.n_free)
        cand = np.flatnonzero(self.arrival < best[0])
        if cand.size == 0:
            return best
        lands = self.landings[cand]
        arrive = self.arrival[cand]
        chunk = max(1, 4_000_000 // cand.size)
        for lo in range(0, valid.size, chunk):
            rows = valid[lo : lo + chunk]
            z = samples[rows]
            if float(time_cost[rows].min()) >= best[0]:
                continue
            dist = np.hypot(z[:, None, 0] - lands[None, :, 0], z[:, None, 1] - lands[None, :, 1])
            if self.problem.space.flights_avoid_obstacles:
                shape = (z.shape[0], lands.shape[0], 2)
                ok = self.problem.space.flight_valid(
                    np.broadcast_to(z[:, None, :], shape), np.broadcast_to(lands[None], shape)
                )
                dist = np.where(ok, dist, np.inf)
            # Zero-length "flights" (landing where one already is) are not moves.
            dist = np.where((dist <= self.leg) & (dist > 1e-6), dist, np.inf)
            total = dist + arrive[None, :] + time_cost[rows, None]
            k = int(np.argmin(total))
            v = float(total.flat[k])
            if v < best[0]:
                best = (v, int(rows[k // total.shape[1]]), int(cand[k % total.shape[1]]))
        return best


def _extract(
    lattice: _ValueLattice,
    traj: _Traj,
    particle: int,
    node_traj: _Traj,
    max_flights: int,
) -> list[_Leg] | None:
    """Greedy exact extraction from ``traj``'s ``particle``; landings continue in ``node_traj``."""
    legs: list[_Leg] = []
    samples = traj.samples[:, particle]
    steps = traj.steps[:, particle]
    tcost = traj.time_cost[:, particle]
    gcost = traj.goal_cost[:, particle]
    finish = float(traj.finish[particle])
    goal_step = int(traj.goal_step[particle])
    promised = math.inf
    for _ in range(max_flights):
        if legs and not math.isfinite(lattice.leg):
            # Landing and taking off again at once never pays when flights can be any length.
            samples = samples.copy()
            samples[0] = np.nan
        v, s, j = lattice.best_takeoff(samples, tcost, gcost)
        if finish <= v:
            legs.append(_Leg(drift_steps=goal_step, takeoff=None, landing=None, to_goal=False))
            return legs
        if not math.isfinite(v):
            return None
        if v > promised + lattice.opts.spacing_m and legs:
            # The lattice values misled the greedy step; finish with straight legs to the goal.
            return _finish_direct(lattice, legs, samples, steps)
        promised = v
        landing = lattice.landings[j]
        is_goal = j == lattice.n_free
        legs.append(
            _Leg(drift_steps=int(steps[s]), takeoff=samples[s].copy(), landing=landing, to_goal=is_goal)
        )
        if is_goal:
            return legs
        p = j  # free node j is particle j of the lattice trajectories
        samples = node_traj.samples[:, p]
        steps = node_traj.steps[:, p]
        tcost = node_traj.time_cost[:, p]
        gcost = node_traj.goal_cost[:, p]
        finish = float(node_traj.finish[p])
        goal_step = int(node_traj.goal_step[p])
    return _finish_direct(lattice, legs, samples, steps)


def _finish_direct(
    lattice: _ValueLattice, legs: list[_Leg], samples: FloatArray, steps: IntArray
) -> list[_Leg] | None:
    """Fly from the sample closest to the goal straight to it, in legs of at most ``max_leg`` if needed."""
    g = np.hypot(samples[:, 0] - lattice.goal[0], samples[:, 1] - lattice.goal[1])
    g[~np.isfinite(g)] = np.inf
    s = int(np.argmin(g))
    if not math.isfinite(g[s]):
        return None
    start = samples[s]
    n = max(1, math.ceil(g[s] / lattice.leg)) if math.isfinite(lattice.leg) else 1
    space = lattice.problem.space
    for extra in range(8):
        k = n + extra
        frac = np.arange(1, k)[:, None] / k
        stops = start[None, :] + frac * (lattice.goal - start)[None, :]
        points = np.vstack([start, stops, lattice.goal])
        if bool(np.all(space.is_valid(stops))) and bool(np.all(space.flight_valid(points[:-1], points[1:]))):
            break
    else:
        return None
    points = [start, *list(stops), lattice.goal]
    legs.append(
        _Leg(drift_steps=int(steps[s]), takeoff=start.copy(), landing=points[1], to_goal=len(points) == 2)
    )
    for i in range(1, len(points) - 1):
        legs.append(
            _Leg(drift_steps=0, takeoff=points[i], landing=points[i + 1], to_goal=i == len(points) - 2)
        )
    return legs


def _refine(
    lattice: _ValueLattice,
    problem: DriftProblem,
    start_traj: _Traj,
    node_traj: _Traj,
    legs: list[_Leg],
    opts: LatticeOptions,
    half_extent_m: float,
) -> list[_Leg] | None:
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
        traj = _trajectories(problem, np.concatenate(clouds[:-1], axis=0), opts.stride)
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
    goal_traj = _trajectories(short, clouds[-1], opts.stride)
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
    out: list[_Leg] = [
        _Leg(
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
            tail = _extract(lattice, traj, p, node_traj, opts.max_flights)
            if tail is None:
                return None
            out.extend(tail)
            return out
        out.append(
            _Leg(
                drift_steps=int(traj.steps[s_best[cur], p]),
                takeoff=traj.samples[s_best[cur], p].copy(),
                landing=clouds[i + 1][c_best[cur]],
                to_goal=False,
            )
        )
        cur = int(c_best[cur])
    # In the goal cloud: drift into the disk.
    out.append(_Leg(drift_steps=int(goal_traj.goal_step[cur]), takeoff=None, landing=None, to_goal=False))
    return out


def _build_path(problem: DriftProblem, legs: list[_Leg]) -> DriftPath:
    prop, space = problem.propagator, problem.space
    t = problem.t0_s
    pos = problem.start_m
    segments: list[tuple[FloatArray, bool]] = []
    for leg in legs:
        drift = prop.drift_polyline(space, pos, leg.drift_steps, t0_s=problem.t0_s)
        segments.append((drift, False))
        pos = drift[-1]
        t += prop.dt_s * (drift.shape[0] - 1)
        if leg.landing is None:
            break
        segments.append((np.vstack([pos, leg.landing]), True))
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
) -> PlanResult:
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
    PlanResult
    """
    opts = options or LatticeOptions()
    tic = time.perf_counter()
    direct = problem.direct_flight_wh
    invalid = problem.validate_endpoints()
    if invalid is not None:
        return PlanResult(
            status=PlanStatus.FAILED,
            path=None,
            flight_energy_wh=math.inf,
            direct_flight_wh=direct,
            compute_s=0.0,
            message=invalid,
        )
    offset = rng.uniform(0.0, opts.spacing_m, 2) if opts.random_offset else np.zeros(2)
    lattice = _ValueLattice(problem, opts, offset)
    points = np.concatenate([lattice.nodes[lattice.free_idx], problem.start_m[None]], axis=0)
    traj = _trajectories(problem, points, opts.stride)
    lattice.solve(traj)
    start = points.shape[0] - 1
    legs = _extract(lattice, traj, start, traj, opts.max_flights)
    if legs is None:
        return PlanResult(
            status=PlanStatus.FAILED,
            path=None,
            flight_energy_wh=math.inf,
            direct_flight_wh=direct,
            compute_s=time.perf_counter() - tic,
            message="no drift/flight sequence reaches the goal from the start",
        )
    start_traj = _Traj(
        points=points[start:],
        samples=traj.samples[:, start:],
        steps=traj.steps[:, start:],
        reaches=traj.reaches[start:],
        goal_step=traj.goal_step[start:],
        time_cost=traj.time_cost[:, start:],
        finish=traj.finish[start:],
        goal_cost=traj.goal_cost[:, start:],
    )
    best_cost = _legs_objective(problem, legs)
    extent = opts.spacing_m
    for _ in range(opts.refine_rounds):
        refined = _refine(lattice, problem, start_traj, traj, legs, opts, extent)
        extent /= 4.0
        if refined is None:
            continue
        cost = _legs_objective(problem, refined)
        if cost < best_cost - 1e-9:
            legs, best_cost = refined, cost
    best_path = _build_path(problem, legs)
    ok = _reaches(problem, best_path)
    energy = float(problem.energy.flight_energy_wh(best_path.flight_distance_m))
    return PlanResult(
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
