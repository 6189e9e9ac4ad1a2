"""Monte Carlo of drift-plan following (Dillard, Chapter V.D, Figs. 68-72).

:func:`following_monte_carlo` runs :func:`oceanloc.sim.path_following.follow_plans` over chunks of runs
(run ``r`` draws from generator ``(seed, r)``, so the numbers do not depend on chunks or workers) and joins
them with :func:`~oceanloc.evaluation.montecarlo.concat_runs`. :func:`drift_follow_study` plans a scenario's
route and follows it (``oceanloc simulate drift-follow``); :func:`drift_swap_study` plans two drifters
swapping positions and follows both (``oceanloc simulate drift-swap``).
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from oceanloc._random import run_generators
from oceanloc.config.drift import DriftScenario, FollowingSettings, problem_from_scenario
from oceanloc.errors import ConfigError
from oceanloc.evaluation.montecarlo import concat_runs, run_chunked
from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.planner import DriftPlannerName, make_planner, parse_planner_name
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem
from oceanloc.sim.drifters import SwapResult, swap_positions
from oceanloc.sim.path_following import FollowingRuns, Replanner, follow_plans

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "FollowingStudy",
    "FollowingSummary",
    "FollowingTask",
    "SwapStudy",
    "drift_follow_study",
    "drift_swap_study",
    "following_monte_carlo",
    "summarize_following",
]


@dataclass(frozen=True, slots=True)
class FollowingTask:
    """Picklable Monte Carlo task: runs with generators ``(seed, r)``; the first ``keep_tracks`` runs keep
    their tracks."""

    problem: DriftProblem
    plan: DriftPath
    settings: FollowingSettings
    replanner: Replanner
    seed: int
    keep_tracks: int = 0

    def __call__(self, run_indices: np.ndarray) -> FollowingRuns:
        idx = np.asarray(run_indices, dtype=np.int64)
        keep = int(np.sum(idx < self.keep_tracks))
        runs = follow_plans(
            self.problem,
            self.plan,
            self.settings,
            run_generators(self.seed, idx),
            self.replanner,
            keep_tracks=keep,
        )
        return runs.with_run_indices(idx)


def following_monte_carlo(
    problem: DriftProblem,
    plan: DriftPath,
    settings: FollowingSettings,
    replanner: Replanner,
    runs: int,
    seed: int,
    *,
    keep_tracks: int = 0,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> FollowingRuns:
    """``runs`` drifters following ``plan`` in their own true currents, joined in run order."""
    task = FollowingTask(problem, plan, settings, replanner, seed, keep_tracks)
    parts = run_chunked(task, runs, executor=executor, chunk_size=chunk_size, progress=progress)
    return concat_runs(parts, keep=("planned_energy_wh",))


@dataclass(frozen=True, slots=True, kw_only=True)
class FollowingSummary:
    """Monte Carlo summary of path following (energies in Wh; means over the arriving runs)."""

    runs: int
    arrival_rate: float
    planned_energy_wh: float
    flight_energy_wh_mean: float
    extra_energy_wh_mean: float
    extra_energy_wh_std: float
    replans_mean: float
    duration_h_mean: float

    def to_record(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in self.__slots__}  # type: ignore[attr-defined]


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


def _settings_record(fs: FollowingSettings) -> dict[str, Any]:
    return {
        "watch_circle_m": fs.watch_circle_m,
        "current_scale": fs.current_scale,
        "current_rotation_deg": float(np.degrees(fs.current_rotation_rad)),
        "noise_mps": fs.noise_mps,
        "noise_correlation_s": fs.noise_correlation_s,
        "stray_m": fs.stray_m,
        "max_replans": fs.max_replans,
    }


@dataclass(frozen=True, slots=True, kw_only=True)
class FollowingStudy:
    """A scenario's plan followed by many drifters (``oceanloc simulate drift-follow``).

    Attributes
    ----------
    scenario : str
        Scenario name.
    planner : str
        Planner of the plan and of every replan.
    seed : int
        Master seed of the following runs (the plan uses the scenario's planner seed).
    problem : DriftProblem
    settings : FollowingSettings
    plan : DriftPlanResult
        The plan every run starts with.
    runs : FollowingRuns
    summary : FollowingSummary
    """

    scenario: str
    planner: DriftPlannerName
    seed: int
    problem: DriftProblem
    settings: FollowingSettings
    plan: DriftPlanResult
    runs: FollowingRuns
    summary: FollowingSummary

    def to_record(self) -> dict[str, Any]:
        """Scenario, planner, seed, settings, the summary (flat) and the per-run outcomes."""
        return {
            "scenario": self.scenario,
            "planner": self.planner,
            "seed": self.seed,
            "settings": _settings_record(self.settings),
            **self.summary.to_record(),
            "plan": self.plan.to_record(),
            "per_run": self.runs.to_record(),
        }

    def to_dataset(self) -> xr.Dataset:
        """Per-run outcomes on the ``run`` dimension, with units and long names."""
        import xarray as xr

        r = self.runs
        run = np.arange(r.runs)
        return xr.Dataset(
            {
                "arrived": (
                    "run",
                    r.arrived.astype(np.int8),
                    {"units": "1", "long_name": "reached the goal"},
                ),
                "flight_energy": (
                    "run",
                    r.flight_energy_wh,
                    {"units": "W h", "long_name": "energy flown while following"},
                ),
                "replans": ("run", r.replans, {"units": "1", "long_name": "number of replans"}),
                "duration": ("run", r.duration_s, {"units": "s", "long_name": "time to arrival or abandon"}),
            },
            coords={"run": ("run", run, {"units": "1", "long_name": "Monte Carlo run"})},
            attrs={
                "title": f"drift-plan following, {self.scenario}, planner {self.planner}",
                "planned_flight_energy_wh": self.runs.planned_energy_wh,
                "energy_convention": self.problem.energy.convention,
            },
        )


def drift_follow_study(
    scenario: DriftScenario,
    runs: int | None = None,
    seed: int | None = None,
    *,
    planner: str | None = None,
    keep_tracks: int = 5,
    executor: Executor | None = None,
    progress: Callable[[int], None] | None = None,
) -> FollowingStudy:
    """Plan ``scenario``'s route (its planner seed) and follow it ``runs`` times (defaults: the scenario's
    ``[following]`` runs and seed); a ConfigError when the planner finds no plan to follow."""
    name = scenario.planner if planner is None else parse_planner_name(planner, "--planner")
    plan_fn = make_planner(name)
    problem = problem_from_scenario(scenario)
    fs = scenario.following
    first = plan_fn(problem, np.random.default_rng(scenario.seed))
    if first.path is None or not first.success:
        raise ConfigError(f"{scenario.name}: the {name} planner found no plan to follow ({first.message})")
    s = fs.seed if seed is None else seed
    res = following_monte_carlo(
        problem,
        first.path,
        fs,
        plan_fn,
        runs or fs.runs,
        s,
        keep_tracks=keep_tracks,
        executor=executor,
        progress=progress,
    )
    return FollowingStudy(
        scenario=scenario.name,
        planner=name,
        seed=s,
        problem=problem,
        settings=fs,
        plan=first,
        runs=res,
        summary=summarize_following(res),
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class SwapStudy:
    """Two drifters swapping positions, each plan then followed once in a true current.

    Attributes
    ----------
    scenario : str
    planner : str
    seed : int
        Planner seed (the following runs use the scenario's following seed unless a seed was given).
    swap : SwapResult
        Both problems and plans, and the closest approach of the planned schedules.
    followed : tuple of FollowingRuns or None
        One following run per drifter (``None`` where the plan failed).
    settings : FollowingSettings
    """

    scenario: str
    planner: DriftPlannerName
    seed: int
    swap: SwapResult
    followed: tuple[FollowingRuns | None, FollowingRuns | None]
    settings: FollowingSettings

    def to_record(self) -> dict[str, Any]:
        drifters = []
        for k, (res, f) in enumerate(zip(self.swap.results, self.followed, strict=True)):
            entry: dict[str, Any] = {"drifter": k + 1, "plan": res.to_record()}
            if f is not None:
                entry["followed"] = {
                    "arrived": bool(f.arrived[0]),
                    "flight_energy_wh": float(f.flight_energy_wh[0]),
                    "replans": int(f.replans[0]),
                    "duration_s": float(f.duration_s[0]),
                }
            drifters.append(entry)
        return {
            "scenario": self.scenario,
            "planner": self.planner,
            "seed": self.seed,
            "settings": _settings_record(self.settings),
            "min_separation_m": self.swap.min_separation_m,
            "drifters": drifters,
        }


def drift_swap_study(
    scenario: DriftScenario, seed: int | None = None, *, planner: str | None = None
) -> SwapStudy:
    """Drifter 1 plans start -> goal and drifter 2 goal -> start (generators ``(seed, 0)``, ``(seed, 1)``);
    each successful plan is followed once in the scenario's true current."""
    name = scenario.planner if planner is None else parse_planner_name(planner, "--planner")
    plan_fn = make_planner(name)
    problem = problem_from_scenario(scenario)
    s = scenario.seed if seed is None else seed
    rngs = run_generators(s, [0, 1])
    swap = swap_positions(problem, plan_fn, (rngs[0], rngs[1]))
    follow_rngs = run_generators(scenario.following.seed if seed is None else seed, [0, 1])
    followed: list[FollowingRuns | None] = []
    for k, (prob, res) in enumerate(zip(swap.problems, swap.results, strict=True)):
        if res.path is None:
            followed.append(None)
            continue
        f = follow_plans(prob, res.path, scenario.following, [follow_rngs[k]], plan_fn, keep_tracks=1)
        followed.append(f)
    return SwapStudy(
        scenario=scenario.name,
        planner=name,
        seed=s,
        swap=swap,
        followed=(followed[0], followed[1]),
        settings=scenario.following,
    )
