"""Following a drift plan in a current that is not the one planned for (Dillard, Chapter V.D, Fig. 72).

A drifter starts at the plan's start and drifts in the *true* current: the planning current scaled and
rotated, plus a spatially uniform random current that varies in time (a first-order Gauss-Markov process,
one per run). It flies only at hop points: when it is inside the watch circle of the next planned take-off
point it flies to that hop's planned landing point (the flight resets the drift error, as in the lab
test). It replans from where it is when it strays farther than ``stray_m`` from the rest of its planned
drift track, when its next drift step would enter an obstacle or leave the map, and when the plan ends
without it reaching the goal. A run succeeds when the drifter gets within the goal tolerance.

All runs of a batch drift together, vectorized; hops, replans and arrivals are handled per run as events.
The Monte Carlo over many runs (chunks, workers, summaries) is :mod:`oceanloc.evaluation.path_following`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
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
    """``(n_steps, 2)`` stationary first-order Gauss-Markov current (std ``sigma``, time scale ``tau``):
    ``x_k = a x_(k-1) + w_k`` with ``a = exp(-dt / tau)``, ``w_k ~ N(0, sigma^2 (1 - a^2))`` and ``x_0`` drawn
    from the stationary law (a linear recursive filter, not a Python loop)."""
    from scipy.signal import lfilter  # here: the command line starts without scipy

    a = math.exp(-dt_s / tau_s)
    w = rng.standard_normal((n_steps, 2)) * sigma_mps * math.sqrt(1.0 - a * a)
    state = rng.standard_normal(2) * sigma_mps
    if n_steps == 0:
        return w
    out, _ = lfilter([1.0], [1.0, -a], w, axis=0, zi=(a * state)[None, :])
    return np.asarray(out, dtype=float)


@dataclass(slots=True)
class _Run:
    """Mutable state of one drifter while it follows (private to :class:`_Fleet`)."""

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
    """Outcome of each run (arrays along the run axis, so chunks join with ``concat_runs``).

    Attributes
    ----------
    arrived : (R,) bool
    flight_energy_wh : (R,) float
        Energy actually flown, Wh.
    planned_energy_wh : float
        Flight energy of the initial plan, Wh.
    replans : (R,) int
    duration_s : (R,) float
        Time until arrival (or until the run was abandoned), seconds.
    track_xy_m : (P, 2) float
        Positions at every step of the runs whose tracks were kept (for figures), metres, run after run.
    track_run : (P,) int
        Run index of each row of ``track_xy_m``.
    flights_m : (F, 2, 2) float
        Take-off and landing of every flight of the kept runs, metres.
    flight_run : (F,) int
        Run index of each flight.
    """

    arrived: BoolArray
    flight_energy_wh: FloatArray
    planned_energy_wh: float
    replans: IntArray
    duration_s: FloatArray
    track_xy_m: FloatArray
    track_run: IntArray
    flights_m: FloatArray
    flight_run: IntArray

    @property
    def runs(self) -> int:
        return int(self.arrived.size)

    def to_record(self) -> dict[str, Any]:
        """Per-run outcomes as plain lists (energies in Wh, durations in s); tracks are for figures only."""
        return {
            "planned_energy_wh": self.planned_energy_wh,
            "arrived": self.arrived.tolist(),
            "flight_energy_wh": self.flight_energy_wh.tolist(),
            "replans": self.replans.tolist(),
            "duration_s": self.duration_s.tolist(),
        }

    def kept_runs(self) -> IntArray:
        """Run indices whose tracks were kept, in order."""
        return np.unique(np.concatenate([self.track_run, self.flight_run]))

    def tracks(self) -> list[FloatArray]:
        """``(K, 2)`` track of every kept run."""
        return [self.track_xy_m[self.track_run == r] for r in self.kept_runs()]

    def flights(self) -> list[FloatArray]:
        """``(F, 2, 2)`` flights of every kept run."""
        return [self.flights_m[self.flight_run == r] for r in self.kept_runs()]

    def with_run_indices(self, run_indices: IntArray) -> FollowingRuns:
        """The same runs renumbered: local run ``i`` becomes ``run_indices[i]`` (for chunked Monte Carlo)."""
        idx = np.asarray(run_indices, dtype=np.int64)
        return dataclasses.replace(self, track_run=idx[self.track_run], flight_run=idx[self.flight_run])


@dataclass(frozen=True, slots=True, kw_only=True)
class FollowingClock:
    """Time grid of a following simulation: the drift step and how many steps a run may take."""

    dt_s: float
    n_steps: int


def following_clock(problem: DriftProblem, plan: DriftPath, max_duration_s: float | None) -> FollowingClock:
    """Drift steps until ``max_duration_s`` (default: three times the plan's duration plus 12 h)."""
    dt = problem.propagator.dt_s
    limit = max_duration_s if max_duration_s is not None else 3.0 * plan.duration_s + 12 * 3600.0
    return FollowingClock(dt_s=dt, n_steps=math.ceil(limit / dt))


def true_current_noise(
    rngs: list[np.random.Generator], clock: FollowingClock, settings: FollowingSettings
) -> FloatArray:
    """``(R, n_steps + 1, 2)`` random part of every run's true current, m/s (drawn first from each
    run's generator, so a run's replans draw the same numbers however runs are chunked)."""
    if not rngs:
        return np.zeros((0, clock.n_steps + 1, 2))
    fs = settings
    n = clock.n_steps + 1
    return np.stack(
        [gauss_markov_noise(g, n, clock.dt_s, fs.noise_mps, fs.noise_correlation_s) for g in rngs]
    )


@dataclass(slots=True)
class _Fleet:
    """Every drifter of a batch while it follows: positions, clocks and per-run events (private)."""

    problem: DriftProblem
    settings: FollowingSettings
    rngs: list[np.random.Generator]
    replanner: Replanner
    runs: list[_Run]
    pos: FloatArray
    t: FloatArray
    duration: FloatArray

    @classmethod
    def start(
        cls,
        problem: DriftProblem,
        plan: DriftPath,
        settings: FollowingSettings,
        rngs: list[np.random.Generator],
        replanner: Replanner,
    ) -> _Fleet:
        n = len(rngs)
        fleet = cls(
            problem=problem,
            settings=settings,
            rngs=rngs,
            replanner=replanner,
            runs=[_Run(plan=plan, hops=plan.hops_m()) for _ in range(n)],
            pos=np.tile(problem.start_m, (n, 1)),
            t=np.full(n, problem.t0_s),
            duration=np.zeros(n),
        )
        for i in range(n):
            fleet.events(i)
        return fleet

    def replan(self, i: int) -> None:
        """Plan again from where run ``i`` is; give up after ``max_replans`` or when no plan is found."""
        run = self.runs[i]
        run.replans += 1
        if run.replans > self.settings.max_replans:
            run.done = True
            return
        here = dataclasses.replace(self.problem, start_m=self.pos[i].copy(), t0_s=float(self.t[i]))
        res = self.replanner(here, self.rngs[i])
        if res.path is None or not res.success:
            run.done = True
            return
        run.plan = res.path
        run.hops = res.path.hops_m()
        run.next_hop = 0
        run.anchor = 0

    def events(self, i: int) -> None:
        """Arrival and hops of run ``i`` at its current position (loops over chained legs)."""
        run, pos, goal = self.runs[i], self.pos, self.problem.goal_m
        for _ in range(1000):
            if np.linalg.norm(pos[i] - goal) < self.problem.goal_tolerance_m:
                run.done = run.arrived = True
                return
            if run.next_hop >= len(run.hops):
                return
            takeoff, landing = run.hops[run.next_hop]
            if np.linalg.norm(pos[i] - takeoff) > self.settings.watch_circle_m:
                return
            d = float(np.linalg.norm(landing - pos[i]))
            run.flights.append(np.stack([pos[i].copy(), landing]))
            run.flight_m += d
            self.t[i] += d / self.problem.energy.flight_speed_mps
            pos[i] = landing
            run.next_hop += 1
            run.anchor = _landing_vertex(run.plan, run.next_hop)
            if np.allclose(landing, goal):
                run.done = run.arrived = True
                return

    def step(self, k: int, noise: FloatArray, step: Callable[..., tuple[Scalar, Scalar]], keep: int) -> bool:
        """Drift every active run one step in its true current, then handle events; ``False`` when all
        runs are done."""
        active = np.flatnonzero([not r.done for r in self.runs])
        if active.size == 0:
            return False
        fs, pos, t = self.settings, self.pos, self.t
        cos_s = fs.current_scale * math.cos(fs.current_rotation_rad)
        sin_s = fs.current_scale * math.sin(fs.current_rotation_rad)
        current = _TrueCurrent(
            self.problem.propagator.field, cos_s, sin_s, noise[active, k, 0], noise[active, k, 1]
        )
        xn, yn = step(current, pos[active, 0], pos[active, 1], t[active], self.problem.propagator.dt_s)
        ok = np.asarray(self.problem.space.is_valid_xy(xn, yn), dtype=bool)
        moved = active[ok]
        pos[moved, 0] = xn[ok]
        pos[moved, 1] = yn[ok]
        t[active] += self.problem.propagator.dt_s
        for i in active[~ok]:
            self.replan(int(i))  # blocked: hop away from the obstacle or the map edge
        n_steps = noise.shape[1] - 1
        for i in active:
            run = self.runs[i]
            if run.done:
                continue
            if len(run.track) < n_steps and i < keep:
                run.track.append(pos[i].copy())
            self.events(int(i))
            if run.done:
                self.duration[i] = t[i] - self.problem.t0_s
                continue
            if k % 5 == 4 and _strayed(run, pos[i], fs.stray_m):
                self.replan(int(i))
                self.events(int(i))
        for i in active:
            if self.runs[i].done and self.duration[i] == 0.0:
                self.duration[i] = t[i] - self.problem.t0_s
        return True

    def result(self, plan: DriftPath, keep: int) -> FollowingRuns:
        """The frozen outcome (runs still under way count their time so far)."""
        unset = self.duration == 0.0
        self.duration[unset] = self.t[unset] - self.problem.t0_s
        wh_per_m = self.problem.energy.flight_wh_per_m
        kept = self.runs[:keep]
        tracks = [np.asarray(r.track, dtype=float).reshape(-1, 2) for r in kept]
        flights = [np.asarray(r.flights, dtype=float).reshape(-1, 2, 2) for r in kept]
        return FollowingRuns(
            arrived=np.array([r.arrived for r in self.runs], dtype=bool),
            flight_energy_wh=np.array([r.flight_m * wh_per_m for r in self.runs]),
            planned_energy_wh=float(plan.flight_distance_m * wh_per_m),
            replans=np.array([r.replans for r in self.runs], dtype=np.int64),
            duration_s=self.duration,
            track_xy_m=np.concatenate([np.zeros((0, 2)), *tracks]),
            track_run=np.repeat(np.arange(len(kept), dtype=np.int64), [a.shape[0] for a in tracks]),
            flights_m=np.concatenate([np.zeros((0, 2, 2)), *flights]),
            flight_run=np.repeat(np.arange(len(kept), dtype=np.int64), [a.shape[0] for a in flights]),
        )


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
    clock = following_clock(problem, plan, max_duration_s)
    noise = true_current_noise(rngs, clock, settings)
    step = step_function(problem.propagator.method)
    fleet = _Fleet.start(problem, plan, settings, rngs, replanner)
    for k in range(clock.n_steps):
        if not fleet.step(k, noise, step, keep_tracks):
            break
    return fleet.result(plan, keep_tracks)


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
