"""The drift/hop lattice's value function: trajectories, flight envelope, value iteration, extraction.

The pieces of :mod:`oceanloc.planning.drift_rrt.lattice` (see its docstring for the method): the lattice
and its rollouts (:class:`ValueLattice`, :func:`sample_drift`), and the exact greedy read-out of a plan
from the values (:func:`extract_plan`). Private to the lattice planner.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.planning.drift_rrt.problem import DriftProblem

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
    max_memory_gib : float
        Largest estimated working memory of a search (GiB); a larger problem is a ConfigError saying what
        to change, raised before anything is allocated.
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
    max_memory_gib: float = 4.0

    def __post_init__(self) -> None:
        if not self.spacing_m > 0:
            raise ConfigError(f"lattice spacing must be positive, got {self.spacing_m}")
        if self.stride < 1 or self.max_value_iterations < 1 or self.max_flights < 1:
            raise ConfigError("stride, max_value_iterations and max_flights must be at least 1")
        if not self.max_memory_gib > 0:
            raise ConfigError(f"max_memory_gib must be positive, got {self.max_memory_gib}")
        if self.envelope not in ("dense", "stencil"):
            raise ConfigError(f"envelope must be 'dense' or 'stencil', got '{self.envelope}'")
        if self.refine_rounds < 0 or self.cloud_half_width < 1 or self.stencil_radius < 1:
            raise ConfigError(
                "refine_rounds >= 0, cloud_half_width >= 1 and stencil_radius >= 1 are required"
            )


@dataclass(frozen=True, slots=True)
class SampledDrift:
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
class Leg:
    drift_steps: int
    takeoff: FloatArray | None  # where the drift ends (exact, from the rollout); None: drift into the goal
    landing: FloatArray | None  # None: the drift itself ends in the goal disk
    to_goal: bool


def legs_objective(problem: DriftProblem, legs: list[Leg]) -> float:
    """Flight energy plus the price of time of a plan, from its legs (no re-simulation needed)."""
    flown = sum(
        float(np.linalg.norm(leg.landing - leg.takeoff))
        for leg in legs
        if leg.landing is not None and leg.takeoff is not None
    )
    steps = sum(leg.drift_steps for leg in legs)
    hours = (steps * problem.propagator.dt_s + flown / problem.energy.flight_speed_mps) / 3600.0
    return float(problem.energy.flight_energy_wh(flown)) + problem.time_weight_wh_per_h * hours


def sample_drift(
    problem: DriftProblem, points: FloatArray, stride: int, t0_s: float | None = None
) -> SampledDrift:
    """Drift ``(P, 2)`` points from ``t0_s`` (the problem's start time by default) over the horizon."""
    roll = problem.propagator.rollout(
        problem.space,
        points,
        problem.horizon_steps,
        goal_m=problem.goal_m,
        goal_tolerance_m=problem.goal_tolerance_m,
        stride=stride,
        t0_s=problem.t0_s if t0_s is None else t0_s,
    )
    samples = np.concatenate([roll.samples_m, roll.closest_m[None]], axis=0)
    n = points.shape[0]
    steps = np.concatenate([np.repeat(roll.sample_steps[:, None], n, axis=1), roll.goal_step[None]], axis=0)
    price = problem.time_weight_m_per_s * problem.propagator.dt_s
    time_cost = steps * price
    finish = np.where(roll.reaches_goal, roll.goal_step * price, np.inf)
    goal_cost = goal_flight_m(problem, samples)
    return SampledDrift(
        goal_cost=goal_cost,
        points=points,
        samples=samples,
        steps=steps,
        reaches=roll.reaches_goal,
        goal_step=roll.goal_step,
        time_cost=time_cost,
        finish=finish,
    )


def goal_flight_m(problem: DriftProblem, z: FloatArray) -> FloatArray:
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


class ValueLattice:
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
        return goal_flight_m(self.problem, z)

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
    def solve(self, traj: SampledDrift) -> None:
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

    def fallback_values(self, traj: SampledDrift) -> FloatArray:
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


def extract_plan(
    lattice: ValueLattice,
    traj: SampledDrift,
    particle: int,
    node_traj: SampledDrift,
    max_flights: int,
) -> list[Leg] | None:
    """Greedy exact extraction from ``traj``'s ``particle``; landings continue in ``node_traj``."""
    legs: list[Leg] = []
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
            legs.append(Leg(drift_steps=goal_step, takeoff=None, landing=None, to_goal=False))
            return legs
        if not math.isfinite(v):
            return None
        if v > promised + lattice.opts.spacing_m and legs:
            # The lattice values misled the greedy step; finish with straight legs to the goal.
            return finish_direct(lattice, legs, samples, steps)
        promised = v
        landing = lattice.landings[j]
        is_goal = j == lattice.n_free
        legs.append(
            Leg(drift_steps=int(steps[s]), takeoff=samples[s].copy(), landing=landing, to_goal=is_goal)
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
    return finish_direct(lattice, legs, samples, steps)


def extract_in_time(lattice: ValueLattice, max_flights: int) -> list[Leg] | None:
    """Greedy extraction for a time-varying field: every leg drifts from its own start time.

    The lattice values (computed from the start time) only rank the landing points; the drift from each
    landing is integrated afresh from the time the vehicle lands there (start time plus the drift and
    flight time so far), so the take-off points are those of the flown path. Because the values are only
    an estimate in a time-varying field, every step also keeps the exact plan "what is flown so far, then
    drift into the goal or fly straight to it", and the cheapest of these (by :func:`legs_objective`) is
    returned if it beats the greedy plan.
    """
    problem = lattice.problem
    dt, speed = problem.propagator.dt_s, problem.energy.flight_speed_mps
    pos = problem.start_m
    t = problem.t0_s
    legs: list[Leg] = []
    promised = math.inf
    best: list[Leg] | None = None
    best_cost = math.inf

    def consider(plan: list[Leg] | None) -> None:
        nonlocal best, best_cost
        if plan is None:
            return
        cost = legs_objective(problem, plan)
        if cost < best_cost - 1e-9:
            best, best_cost = plan, cost

    for _ in range(max_flights):
        traj = sample_drift(problem, pos[None], lattice.opts.stride, t0_s=t)
        samples = traj.samples[:, 0].copy()
        steps = traj.steps[:, 0]
        into_goal = Leg(drift_steps=int(traj.goal_step[0]), takeoff=None, landing=None, to_goal=False)
        if bool(traj.reaches[0]):
            consider([*legs, into_goal])
        consider(finish_direct(lattice, list(legs), samples, steps))
        if legs and not math.isfinite(lattice.leg):
            samples[0] = np.nan
        v, s, j = lattice.best_takeoff(samples, traj.time_cost[:, 0], traj.goal_cost[:, 0])
        if float(traj.finish[0]) <= v or not math.isfinite(v):
            break
        if v > promised + lattice.opts.spacing_m and legs:
            break
        promised = v
        landing = lattice.landings[j]
        is_goal = j == lattice.n_free
        takeoff = samples[s].copy()
        legs.append(Leg(drift_steps=int(steps[s]), takeoff=takeoff, landing=landing, to_goal=is_goal))
        if is_goal:
            consider(list(legs))
            break
        if legs_objective(problem, legs) >= best_cost:
            break  # what is flown already costs more than a complete plan found before
        t += int(steps[s]) * dt + float(np.linalg.norm(landing - takeoff)) / speed
        pos = np.asarray(landing, dtype=float)
    else:
        traj = sample_drift(problem, pos[None], lattice.opts.stride, t0_s=t)
        consider(finish_direct(lattice, list(legs), traj.samples[:, 0], traj.steps[:, 0]))
    return best


def finish_direct(
    lattice: ValueLattice, legs: list[Leg], samples: FloatArray, steps: IntArray
) -> list[Leg] | None:
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
        Leg(drift_steps=int(steps[s]), takeoff=start.copy(), landing=points[1], to_goal=len(points) == 2)
    )
    for i in range(1, len(points) - 1):
        legs.append(
            Leg(drift_steps=0, takeoff=points[i], landing=points[i + 1], to_goal=i == len(points) - 2)
        )
    return legs
