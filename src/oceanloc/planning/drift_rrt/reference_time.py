"""A dense brute-force yardstick for drift planning in time: exact drifts from every node at every time.

The planner in time (:mod:`oceanloc.planning.drift_rrt.time_plan`) drifts each node for one time slice and
interpolates its value between nodes. This reference does not interpolate anything the vehicle drifts
through: on a fine lattice of landing points ``q`` (spacing ``h``) and landing times ``t_j`` (every
``slot_s`` seconds), every landing ``(q, t_j)`` is drifted with the problem's own propagator and step, step
by step, to the end of the planning window, and its value is

    W(q, t_j) = min( drift into the goal disk,
                     min over drift steps s, landings q':
                         price * s dt + |z_s - q'| + W(q', t_(j')) )

where ``z_s`` is the drift's position at step ``s`` and ``t_(j')`` the slot nearest to the landing time
``t_j + s dt + |z_s - q'| / F``. The inner minimum over ``q'`` is the flight envelope ``E(n, j)`` on the
lattice's nodes, taken exactly over every pair of nodes closer than ``bound / unit cost`` (a plan with a
longer flight costs more than ``bound``, a known plan's objective, so it cannot be optimal; flights
straight to the goal may be any length), and read at the node nearest to ``z_s`` plus the distance to it
(a real flight: the value is achievable, never optimistic). The plan is read out from the
start in exact time with exact flights to the lattice's landing points, then refined
(:func:`~oceanloc.planning.drift_rrt.time_plan.refine_in_time`), and flown exactly: its cost is what the
model's vehicle pays.

Its cost grows as (nodes) x (slots)^2 x (steps per slot): minutes for a 20 km map at 250 m and 5 min.
Only the air (the AquaQuad) and the energy objective with a price of time are covered; it is the
yardstick of the benchmark and of the tests, not a planner.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError
from oceanloc.planning.drift_rrt.direct import prefer_direct
from oceanloc.planning.drift_rrt.lattice_values import Leg
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem, PlanStatus
from oceanloc.planning.drift_rrt.time_plan import (
    SKIP,
    FlownPlan,
    _choose_flight,
    drift_one,
    evaluate,
    flight_legs,
    refine_in_time,
    steps_left,
)
from oceanloc.planning.drift_rrt.time_values import TimeLattice, TimeLatticeOptions

__all__ = ["BruteForceOptions", "brute_force_in_time"]


@dataclass(frozen=True, slots=True, kw_only=True)
class BruteForceOptions:
    """Resolution of the reference: landing points ``spacing_m`` apart, landing times ``slot_steps`` drift
    steps apart, and rounds of refinement of the plan read out."""

    spacing_m: float = 250.0
    slot_steps: int = 1
    refine_rounds: int = 4
    max_nodes: int = 6000
    bound: float | None = None
    """Objective of a known plan (problem's unit): flights longer than ``bound / unit cost`` are left out
    (they cannot be part of a cheaper plan); the direct flight's objective by default."""


class _BruteForce:
    """The value ``W[j, node]`` of landing at a node at slot ``j`` (see the module docstring)."""

    def __init__(self, problem: DriftProblem, opts: BruteForceOptions) -> None:
        if problem.propulsion != "air":
            raise ConfigError("the brute-force reference covers flights through the air only")
        self.problem = problem
        dt = problem.propagator.dt_s
        self.dt = dt
        self.slot = opts.slot_steps * dt
        # The lattice itself (nodes, goal flights, value reads) comes from the planner's class, without its
        # solve(): the reference fills its values its own way.
        self.tl = TimeLattice(
            problem,
            TimeLatticeOptions(spacing_m=opts.spacing_m, slice_s=self.slot, max_nodes=opts.max_nodes),
            np.zeros(2),
        )
        tl = self.tl
        self.n_slots = max(1, math.floor((problem.end_s - problem.t0_s) / self.slot + 1e-9))
        tl.n_slices = self.n_slots
        tl.delta = self.slot
        tl.times = problem.t0_s + self.slot * np.arange(self.n_slots + 1)
        tl.t_end = float(tl.times[-1])

    def _prepare_offsets(self, bound: float) -> None:
        """Flight moves ``(a, b)`` in lattice cells with their length and landing slot, up to the bound."""
        tl = self.tl
        r = bound / tl.unit
        m = math.floor(r / tl.h)
        self.offsets = []
        nx, ny = tl.xs.size, tl.ys.size
        for a in range(-min(m, nx - 1), min(m, nx - 1) + 1):
            for b in range(-min(m, ny - 1), min(m, ny - 1) + 1):
                d = tl.h * math.hypot(a, b)
                if 0 < d <= r:
                    self.offsets.append((a, b, d, round(d / tl.speed / self.slot)))

    def _flights(self, j: int, w: FloatArray, e: FloatArray) -> FloatArray:
        """``min(w, goal flights, min over moves: length + e[slot, landing])`` at slot ``j`` on the grid."""
        tl = self.tl
        ny, nx = tl.ys.size, tl.xs.size
        best = np.minimum(w, tl.goal_flights(float(tl.times[j]))).reshape(ny, nx)
        land_ok = tl.free.reshape(ny, nx)
        for same_slot in (False, True):
            for a, b, d, lag in self.offsets:
                if (lag == 0) != same_slot:
                    continue
                k = j + lag
                if k > self.n_slots:
                    if tl.deadline is not None:
                        continue
                    k = self.n_slots
                src = best if lag == 0 else e[k].reshape(ny, nx)
                ys, yd = slice(max(0, -b), ny - max(0, b)), slice(max(0, b), ny - max(0, -b))
                xs, xd = slice(max(0, -a), nx - max(0, a)), slice(max(0, a), nx - max(0, -a))
                land = np.where(land_ok[yd, xd], src[yd, xd], np.inf)
                np.minimum(best[ys, xs], land + d, out=best[ys, xs])
        return best.ravel()

    def solve(self, bound: float) -> None:
        tl, p = self.tl, self.problem
        tl._prepare_goal()
        self._prepare_offsets(bound)
        free = tl.free_idx
        n_slots = self.n_slots
        w = np.full((n_slots + 1, tl.n_nodes), np.inf)
        e = np.full((n_slots + 1, tl.n_nodes), np.inf)
        w[n_slots] = tl.terminal()
        e[n_slots] = w[n_slots]
        tl.values = e
        spt = round(self.slot / self.dt)
        for j in range(n_slots - 1, -1, -1):
            steps = (n_slots - j) * spt
            roll = p.propagator.rollout(
                p.space,
                tl.nodes[free],
                steps,
                goal_m=p.goal_m,
                goal_tolerance_m=p.goal_tolerance_m,
                stride=1,
                t0_s=float(tl.times[j]),
            )
            z = roll.samples_m[1:]  # (steps, Nf, 2)
            s_idx = np.arange(1, steps + 1)
            slot_of = j + (s_idx + spt // 2) // spt
            node, snap = self._snap(z)
            vals = tl.price * self.dt * s_idx[:, None] + snap + e[slot_of[:, None], node]
            best = np.min(np.where(np.isfinite(z[..., 0]), vals, np.inf), axis=0)
            reach = np.where(roll.reaches_goal, tl.price * self.dt * roll.goal_step, np.inf)
            wj = np.full(tl.n_nodes, np.inf)
            wj[free] = np.minimum(best, reach)
            w[j] = wj
            e[j] = self._flights(j, wj, e)  # flights from every node at slot j (and landing values)
        self.w = w
        tl.values = e
        tl.powered_values = e

    def _snap(self, z: FloatArray) -> tuple[np.ndarray, FloatArray]:
        tl = self.tl
        h = tl.h
        ok = np.isfinite(z[..., 0])
        zx = np.where(ok, z[..., 0], tl.xs[0])
        zy = np.where(ok, z[..., 1], tl.ys[0])
        i = np.clip(np.rint((zx - tl.xs[0]) / h), 0, tl.xs.size - 1).astype(np.intp)
        k = np.clip(np.rint((zy - tl.ys[0]) / h), 0, tl.ys.size - 1).astype(np.intp)
        node = k * tl.xs.size + i
        snap = np.hypot(zx - tl.xs[i], zy - tl.ys[k])
        return node, np.where(ok, snap, np.inf)

    def read_out(self) -> list[Leg] | None:
        """From the start in exact time: take off at the best drift step, land on the best node."""
        tl, p = self.tl, self.problem
        free = tl.free_idx
        lands = tl.nodes[free]
        pos, t = p.start_m.copy(), p.t0_s
        legs: list[Leg] = []
        for _ in range(64):
            roll = drift_one(tl, pos, t, steps_left(tl, t))
            z = roll.samples_m[:, 0]
            valid = np.isfinite(z[:, 0])
            zs, ss = z[valid], roll.sample_steps[valid]
            ts = t + ss * self.dt
            dist = np.hypot(zs[:, None, 0] - lands[None, :, 0], zs[:, None, 1] - lands[None, :, 1])
            dist[dist < 1e-6] = 1e12
            j = np.rint((ts[:, None] + dist / tl.speed - p.t0_s) / self.slot)
            late = j > self.n_slots
            j = np.minimum(j, self.n_slots).astype(np.intp)
            land_w = np.where(late, np.inf, tl.values[j, free[None, :]])
            total = tl.price * self.dt * ss[:, None] + dist + land_w
            goal_d = np.hypot(zs[:, 0] - tl.goal[0], zs[:, 1] - tl.goal[1])
            goal_total = tl.price * self.dt * ss + goal_d
            if tl.deadline is not None:
                goal_total = np.where(ts + goal_d / tl.speed <= tl.deadline + 1e-9, goal_total, np.inf)
            targets = np.concatenate([lands, tl.goal[None]], axis=0)
            v, s, c = _choose_flight(tl, zs, np.concatenate([total, goal_total[:, None]], axis=1), targets)
            finish = tl.price * self.dt * float(roll.goal_step[0]) if bool(roll.reaches_goal[0]) else math.inf
            if finish <= v:
                if not math.isfinite(finish):
                    return None
                legs.append(
                    Leg(drift_steps=int(roll.goal_step[0]), takeoff=None, landing=None, to_goal=False)
                )
                return legs
            to_goal = c == lands.shape[0]
            legs.extend(flight_legs(tl, int(ss[s]), zs[s], targets[c], to_goal))
            if to_goal:
                return legs
            t = float(ts[s]) + float(np.linalg.norm(targets[c] - zs[s])) / tl.speed
            pos = targets[c].copy()
        return None


def brute_force_in_time(problem: DriftProblem, options: BruteForceOptions | None = None) -> DriftPlanResult:
    """The reference plan of ``problem`` (see the module docstring); its energy is exact for the model."""
    opts = options or BruteForceOptions()
    tic = time.perf_counter()
    bf = _BruteForce(problem, opts)
    bound = opts.bound
    if bound is None:
        # The planner's plan is a known plan: no flight longer than its whole cost is in a better one.
        from oceanloc.planning.drift_rrt.time_plan import plan_in_time

        known = plan_in_time(problem, np.random.default_rng(0))
        bound = problem.objective_of(known.path) if known.path is not None else math.inf
    if not math.isfinite(bound):
        raise ConfigError("the brute-force reference needs a finite bound (a known plan's objective)")
    bf.solve(bound)
    best: FlownPlan | None = evaluate(problem, bf.read_out())
    extent = bf.tl.h
    for _ in range(opts.refine_rounds if best is not None else 0):
        cand = evaluate(problem, refine_in_time(bf.tl, best, extent, skip=SKIP))
        extent /= 4.0
        if cand is not None and cand.objective < best.objective - 1e-12:
            best = cand
    direct = problem.direct_flight_wh
    if best is None:
        failed = DriftPlanResult(
            status=PlanStatus.FAILED,
            path=None,
            flight_energy_wh=math.inf,
            direct_flight_wh=direct,
            compute_s=time.perf_counter() - tic,
            message="the reference found no plan in the window",
        )
        return prefer_direct(problem, failed, lambda pr, path: pr.objective_of(path))
    result = DriftPlanResult(
        status=PlanStatus.EXACT if best.reaches else PlanStatus.APPROXIMATE,
        path=best.path,
        flight_energy_wh=problem.powered_energy_wh(best.path),
        direct_flight_wh=direct,
        compute_s=time.perf_counter() - tic,
        iterations=int(bf.tl.free_idx.size * bf.n_slots),
        solutions=1 if best.reaches else 0,
        cost=best.objective,
        message=f"brute force {bf.tl.h:.0f} m x {bf.slot / 60:g} min ({bf.tl.free_idx.size} free nodes, "
        f"{bf.n_slots} slots), value at the start "
        f"{bf.tl.value_at(problem.start_m[None], problem.t0_s)[0] * bf.tl.unit:.4g} "
        f"{problem.objective_unit}",
    )
    return prefer_direct(problem, result, lambda pr, path: pr.objective_of(path))
