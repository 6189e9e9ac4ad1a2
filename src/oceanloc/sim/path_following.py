"""Following a drift plan in a current that is not the one planned for (Dillard, Chapter V.D, Fig. 72).

A drifter starts at the plan's start and drifts in the *true* current: the planning current scaled and
rotated, plus a spatially uniform random current that varies in time (a first-order Gauss-Markov process,
one per run). It flies only at hop points: when it is inside the watch circle of the next planned take-off
point it flies to that hop's planned landing point (the flight resets the drift error, as in the lab
test). It replans from where it is when it strays farther than ``stray_m`` from the rest of its planned
drift track, when its next drift step would enter an obstacle or leave the map, and when the plan ends
without it reaching the goal. A run succeeds when the drifter gets within the goal tolerance.

All runs of a chunk drift together, vectorized; hops, replans and arrivals are handled per run as events.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from oceanloc._random import run_generators
from oceanloc._typing import BoolArray, FloatArray
from oceanloc.config.drift import FollowingSettings
from oceanloc.models.currents import CurrentField, Scalar
from oceanloc.models.drift import step_function
from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem

Replanner = Callable[[DriftProblem, np.random.Generator], DriftPlanResult]


@dataclass(frozen=True, slots=True)
class _TrueCurrent:
    """``scale * R(rotation) * base + noise`` for a batch of drifters (noise: one row per drifter)."""

    base: CurrentField
    cos_s: float
    sin_s: float
    noise_u: FloatArray
    noise_v: FloatArray

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        u, v = self.base.velocity_xy(x_m, y_m, time_s)
        return self.cos_s * u - self.sin_s * v + self.noise_u, self.sin_s * u + self.cos_s * v + self.noise_v


def gauss_markov_noise(
    rng: np.random.Generator, n_steps: int, dt_s: float, sigma_mps: float, tau_s: float
) -> FloatArray:
    """``(n_steps, 2)`` stationary first-order Gauss-Markov current (std ``sigma``, time scale ``tau``)."""
    a = math.exp(-dt_s / tau_s)
    w = rng.standard_normal((n_steps, 2)) * sigma_mps * math.sqrt(1.0 - a * a)
    out = np.empty((n_steps, 2))
    state = rng.standard_normal(2) * sigma_mps
    for k in range(n_steps):
        state = a * state + w[k]
        out[k] = state
    return out


@dataclass(slots=True)
class _Run:
    """Mutable state of one drifter while it follows (private to the simulation loop)."""

    plan: DriftPath
    hops: FloatArray
    next_hop: int = 0
    anchor: int = 0  # plan vertex from which the remaining drift track starts
    flight_m: float = 0.0
    replans: int = 0
    done: bool = False
    arrived: bool = False
    track: list[FloatArray] = field(default_factory=list)
    flights: list[FloatArray] = field(default_factory=list)


@dataclass(frozen=True, slots=True, kw_only=True)
class FollowingRuns:
    """Outcome of each run.

    Attributes
    ----------
    arrived : (R,) bool
    flight_energy_wh : (R,) float
        Energy actually flown.
    planned_energy_wh : float
        Flight energy of the initial plan.
    replans : (R,) int
    duration_s : (R,) float
        Time until arrival (or until the run was abandoned).
    tracks : list of (K, 2) float
        Positions of the first runs at every step (for figures).
    flights : list of (F, 2, 2) float
        Flights of the first runs.
    """

    arrived: BoolArray
    flight_energy_wh: FloatArray
    planned_energy_wh: float
    replans: np.ndarray
    duration_s: FloatArray
    tracks: list[FloatArray]
    flights: list[FloatArray]


def follow_plans(
    problem: DriftProblem,
    plan: DriftPath,
    settings: FollowingSettings,
    rngs: list[np.random.Generator],
    replanner: Replanner,
    *,
    keep_tracks: int = 0,
    max_duration_s: float | None = None,
) -> FollowingRuns:
    """Simulate ``len(rngs)`` drifters following ``plan`` in their own true currents.

    Parameters
    ----------
    problem : DriftProblem
        The planning problem (its current is the planning current).
    plan : DriftPath
        The plan every run starts with.
    settings : FollowingSettings
        True current, watch circle, replanning rules.
    rngs : list of numpy.random.Generator
        One per run: its noise current and its replans.
    replanner : callable
        ``replanner(problem_from_here, rng) -> DriftPlanResult``.
    keep_tracks : int
        Keep the tracks of this many first runs.
    max_duration_s : float, optional
        Abandon a run after this long (default: three times the plan plus 12 h).
    """
    n = len(rngs)
    dt = problem.propagator.dt_s
    limit = max_duration_s if max_duration_s is not None else 3.0 * plan.duration_s + 12 * 3600.0
    n_steps = math.ceil(limit / dt)
    fs = settings
    noise = (
        np.stack([gauss_markov_noise(g, n_steps + 1, dt, fs.noise_mps, fs.noise_correlation_s) for g in rngs])
        if n
        else np.zeros((0, n_steps + 1, 2))
    )
    cos_s = fs.current_scale * math.cos(fs.current_rotation_rad)
    sin_s = fs.current_scale * math.sin(fs.current_rotation_rad)
    step = step_function(problem.propagator.method)
    space = problem.space
    goal = problem.goal_m
    tol = problem.goal_tolerance_m
    wh_per_m = problem.energy.flight_wh_per_m
    runs = [_Run(plan=plan, hops=plan.hops_m()) for _ in range(n)]
    pos = np.tile(problem.start_m, (n, 1))
    t = np.full(n, problem.t0_s)
    duration = np.zeros(n)

    def replan(i: int) -> None:
        run = runs[i]
        run.replans += 1
        if run.replans > fs.max_replans:
            run.done = True
            return
        res = replanner(dataclasses.replace(problem, start_m=pos[i].copy(), t0_s=float(t[i])), rngs[i])
        if res.path is None or not res.success:
            run.done = True
            return
        run.plan = res.path
        run.hops = res.path.hops_m()
        run.next_hop = 0
        run.anchor = 0

    def events(i: int) -> None:
        """Arrival and hops of run ``i`` at its current position (loops over chained legs)."""
        run = runs[i]
        for _ in range(1000):
            if np.linalg.norm(pos[i] - goal) < tol:
                run.done = run.arrived = True
                return
            if run.next_hop >= len(run.hops):
                return
            takeoff, landing = run.hops[run.next_hop]
            if np.linalg.norm(pos[i] - takeoff) > fs.watch_circle_m:
                return
            d = float(np.linalg.norm(landing - pos[i]))
            run.flights.append(np.stack([pos[i].copy(), landing]))
            run.flight_m += d
            t[i] += d / problem.energy.flight_speed_mps
            pos[i] = landing
            run.next_hop += 1
            run.anchor = _landing_vertex(run.plan, run.next_hop)
            if np.allclose(landing, goal):
                run.done = run.arrived = True
                return

    for i in range(n):
        events(i)
    for k in range(n_steps):
        active = np.flatnonzero([not r.done for r in runs])
        if active.size == 0:
            break
        field = _TrueCurrent(problem.propagator.field, cos_s, sin_s, noise[active, k, 0], noise[active, k, 1])
        xn, yn = step(field, pos[active, 0], pos[active, 1], t[active], dt)
        ok = np.asarray(space.is_valid_xy(xn, yn), dtype=bool)
        moved = active[ok]
        pos[moved, 0] = xn[ok]
        pos[moved, 1] = yn[ok]
        t[active] += dt
        for i in active[~ok]:
            replan(int(i))  # blocked: hop away from the obstacle or the map edge
        for i in active:
            run = runs[i]
            if run.done:
                continue
            if len(run.track) < n_steps and i < keep_tracks:
                run.track.append(pos[i].copy())
            events(int(i))
            if run.done:
                duration[i] = t[i] - problem.t0_s
                continue
            if k % 5 == 4 and _strayed(run, pos[i], fs.stray_m):
                replan(int(i))
                events(int(i))
        for i in active:
            if runs[i].done and duration[i] == 0.0:
                duration[i] = t[i] - problem.t0_s
    for i in range(n):
        if duration[i] == 0.0:
            duration[i] = t[i] - problem.t0_s
    return FollowingRuns(
        arrived=np.array([r.arrived for r in runs], dtype=bool),
        flight_energy_wh=np.array([r.flight_m * wh_per_m for r in runs]),
        planned_energy_wh=float(plan.flight_distance_m * wh_per_m),
        replans=np.array([r.replans for r in runs], dtype=np.int64),
        duration_s=duration,
        tracks=[np.asarray(r.track) for r in runs[:keep_tracks]],
        flights=[np.asarray(r.flights).reshape(-1, 2, 2) for r in runs[:keep_tracks]],
    )


def _landing_vertex(plan: DriftPath, hops_done: int) -> int:
    """Index of the plan vertex where the ``hops_done``-th flight lands (0 before any flight)."""
    if hops_done == 0:
        return 0
    idx = np.flatnonzero(plan.flight)
    return int(idx[min(hops_done, idx.size) - 1] + 1)


def _strayed(run: _Run, p: FloatArray, stray_m: float) -> bool:
    """Farther than ``stray_m`` from every remaining drift vertex of the plan (or the plan is used up)."""
    rest = run.plan.points_m[run.anchor :]
    if rest.shape[0] == 0:
        return True
    d2 = np.min(np.sum((rest - p) ** 2, axis=1))
    return bool(d2 > stray_m * stray_m)


@dataclass(frozen=True, slots=True, kw_only=True)
class FollowingSummary:
    """Monte Carlo summary of path following."""

    runs: int
    arrival_rate: float
    planned_energy_wh: float
    flight_energy_wh_mean: float
    extra_energy_wh_mean: float
    extra_energy_wh_std: float
    replans_mean: float
    duration_h_mean: float


def summarize_following(res: FollowingRuns) -> FollowingSummary:
    """Arrival rate; energy, extra energy over the plan, replans and duration of the arriving runs."""
    a = res.arrived
    e = res.flight_energy_wh[a]
    extra = e - res.planned_energy_wh
    return FollowingSummary(
        runs=int(a.size),
        arrival_rate=float(np.mean(a)) if a.size else float("nan"),
        planned_energy_wh=res.planned_energy_wh,
        flight_energy_wh_mean=float(np.mean(e)) if e.size else float("nan"),
        extra_energy_wh_mean=float(np.mean(extra)) if e.size else float("nan"),
        extra_energy_wh_std=float(np.std(extra, ddof=1)) if e.size > 1 else float("nan"),
        replans_mean=float(np.mean(res.replans[a])) if e.size else float("nan"),
        duration_h_mean=float(np.mean(res.duration_s[a])) / 3600.0 if e.size else float("nan"),
    )


@dataclass(frozen=True, slots=True)
class FollowingTask:
    """Picklable Monte Carlo task: runs with generators ``(seed, r)``."""

    problem: DriftProblem
    plan: DriftPath
    settings: FollowingSettings
    replanner: Replanner
    seed: int
    keep_tracks: int = 0

    def __call__(self, run_indices: np.ndarray) -> FollowingRuns:
        keep = int(np.sum(np.asarray(run_indices) < self.keep_tracks))
        return follow_plans(
            self.problem,
            self.plan,
            self.settings,
            run_generators(self.seed, run_indices),
            self.replanner,
            keep_tracks=keep,
        )


def merge_following(chunks: list[FollowingRuns]) -> FollowingRuns:
    """Concatenate chunk results in run order."""
    return FollowingRuns(
        arrived=np.concatenate([c.arrived for c in chunks]),
        flight_energy_wh=np.concatenate([c.flight_energy_wh for c in chunks]),
        planned_energy_wh=chunks[0].planned_energy_wh,
        replans=np.concatenate([c.replans for c in chunks]),
        duration_s=np.concatenate([c.duration_s for c in chunks]),
        tracks=[tr for c in chunks for tr in c.tracks],
        flights=[f for c in chunks for f in c.flights],
    )
