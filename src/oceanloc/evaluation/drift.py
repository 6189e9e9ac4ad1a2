"""Monte Carlo of the drift planners (Dillard, Chapter V.A, Table 4): success, flight energy, compute time.

:func:`drift_monte_carlo` runs every planner of :data:`~oceanloc.planning.drift_rrt.planner.PLANNER_NAMES`
(or a chosen subset) over ``runs`` runs; run ``r`` of every planner plans problem ``r % len(problems)`` with
generator ``(seed, r)``, so the numbers do not depend on chunks, workers or the planner order. Chunks join
with :func:`~oceanloc.evaluation.montecarlo.concat_runs`. :func:`summarize` gives Table 4's statistics of
one planner; :func:`summarize_fields` the same across several obstacle fields. :func:`plan_scenario` is
one planner run on a scenario file (``oceanloc drift-plan``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from oceanloc._random import run_generators
from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.config.drift import DriftScenario, problem_from_scenario
from oceanloc.errors import ConfigError
from oceanloc.evaluation.montecarlo import concat_runs, run_chunked
from oceanloc.models.paths import PathEnergy
from oceanloc.planning.drift_rrt.ensemble import EnsemblePlan, plan_for_ensemble
from oceanloc.planning.drift_rrt.planner import (
    PLANNER_NAMES,
    DriftPlannerName,
    make_planner,
    parse_planner_name,
)
from oceanloc.planning.drift_rrt.problem import DriftPlanResult, DriftProblem, PlanBudget
from oceanloc.planning.drift_rrt.thesis import ThesisMode, ThesisOptions, plan_thesis

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "DriftMonteCarlo",
    "FieldsSummary",
    "PlannerRuns",
    "PlannerSummary",
    "ScenarioPlan",
    "drift_monte_carlo",
    "plan_scenario",
    "run_planner",
    "summarize",
    "summarize_fields",
]


@dataclass(frozen=True, slots=True, kw_only=True)
class PlannerRuns:
    """Per-run outcomes of one planner.

    Attributes
    ----------
    success : (R,) bool
    energy_wh : (R,) float
        Flight energy of the plan, Wh (``NaN`` when it failed).
    compute_s : (R,) float
        Wall-clock planning time, seconds.
    field : (R,) int
        Problem (obstacle field) of each run (0 when there is one).
    """

    success: BoolArray
    energy_wh: FloatArray
    compute_s: FloatArray
    field: IntArray

    def to_record(self) -> dict[str, Any]:
        """Per-run lists (energy ``None`` where a plan failed)."""
        return {
            "success": self.success.tolist(),
            "energy_wh": [float(e) if np.isfinite(e) else None for e in self.energy_wh],
            "compute_s": self.compute_s.tolist(),
            "field": self.field.tolist(),
        }


@dataclass(frozen=True, slots=True)
class _PlanTask:
    """Picklable Monte Carlo task: ``planner`` on the problems, run ``r`` on problem ``r % len(problems)``."""

    planner: DriftPlannerName
    problems: tuple[DriftProblem, ...]
    seed: int
    iterations: int | None

    def __call__(self, run_indices: np.ndarray) -> PlannerRuns:
        plan = make_planner(self.planner, self.iterations)
        rngs = run_generators(self.seed, run_indices)
        fields = np.asarray(run_indices, dtype=np.int64) % len(self.problems)
        results = [plan(self.problems[f], rng) for f, rng in zip(fields, rngs, strict=True)]
        return PlannerRuns(
            success=np.asarray([r.success for r in results], dtype=bool),
            energy_wh=np.asarray([r.flight_energy_wh if r.success else np.nan for r in results]),
            compute_s=np.asarray([r.compute_s for r in results]),
            field=fields,
        )


def run_planner(
    planner: str,
    problems: Sequence[DriftProblem],
    runs: int,
    seed: int,
    *,
    iterations: int | None = None,
    executor: Executor | None = None,
    progress: Callable[[int], None] | None = None,
) -> PlannerRuns:
    """Monte Carlo of one planner; run ``r`` uses problem ``r % len(problems)``, generator ``(seed, r)``."""
    if not problems:
        raise ConfigError("the drift Monte Carlo needs at least one problem")
    task = _PlanTask(parse_planner_name(planner), tuple(problems), seed, iterations)
    return concat_runs(run_chunked(task, runs, executor=executor, progress=progress))


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftMonteCarlo:
    """Every planner's runs on the same problems.

    Attributes
    ----------
    planners : tuple of str
    seed : int
    iterations : int or None
        Iteration budget of the optimality-seeking DR-RRT* (``None``: its default).
    runs : dict of str to PlannerRuns
    direct_flight_wh : (F,) float
        Direct-flight energy of each problem, Wh.
    """

    planners: tuple[DriftPlannerName, ...]
    seed: int
    iterations: int | None
    runs: dict[str, PlannerRuns]
    direct_flight_wh: FloatArray

    @property
    def n_runs(self) -> int:
        return int(next(iter(self.runs.values())).success.size)

    def to_record(self) -> dict[str, Any]:
        """Per-planner per-run outcomes as plain lists (energy ``None`` where a plan failed)."""
        return {
            "seed": self.seed,
            "iterations": self.iterations,
            "direct_flight_wh": self.direct_flight_wh.tolist(),
            "planners": {name: r.to_record() for name, r in self.runs.items()},
        }

    def to_dataset(self, prefix: str = "") -> xr.Dataset:
        """Outcomes on dims ``(planner, run)`` (``prefix`` names the variables and dims of a second study,
        e.g. ``field_`` for the random fields), with units and long names."""
        import xarray as xr

        names = list(self.runs)
        run_dim, planner_dim = f"{prefix}run", "planner"

        def stack(attr: str) -> np.ndarray:
            return np.stack([getattr(self.runs[n], attr) for n in names])

        field = next(iter(self.runs.values())).field
        return xr.Dataset(
            {
                f"{prefix}success": (
                    (planner_dim, run_dim),
                    stack("success").astype(np.int8),
                    {"units": "1", "long_name": "plan reached the goal disk (1) or not (0)"},
                ),
                f"{prefix}flight_energy": (
                    (planner_dim, run_dim),
                    stack("energy_wh"),
                    {"units": "W h", "long_name": "flight energy of the plan (NaN when it failed)"},
                ),
                f"{prefix}compute_time": (
                    (planner_dim, run_dim),
                    stack("compute_s"),
                    {"units": "s", "long_name": "wall-clock planning time"},
                ),
                f"{prefix}problem": (
                    run_dim,
                    field,
                    {"units": "1", "long_name": "obstacle field of the run"},
                ),
                f"{prefix}direct_flight_energy": (
                    (f"{prefix}problem_index",),
                    self.direct_flight_wh,
                    {"units": "W h", "long_name": "energy of flying straight from start to goal"},
                ),
            },
            coords={
                planner_dim: (planner_dim, np.asarray(names, dtype=str), {"long_name": "drift planner"}),
                run_dim: (run_dim, np.arange(field.size), {"units": "1", "long_name": "Monte Carlo run"}),
            },
        )


def drift_monte_carlo(
    problems: Sequence[DriftProblem],
    runs: int,
    seed: int,
    *,
    planners: Sequence[str] = PLANNER_NAMES,
    iterations: int | None = None,
    executor: Executor | None = None,
    progress: Callable[[int], None] | None = None,
) -> DriftMonteCarlo:
    """Run each planner ``runs`` times over ``problems`` (see :func:`run_planner`).

    ``iterations`` is the budget of the optimality-seeking DR-RRT* (25,000 in the thesis); the
    single-solution mode stops at its first solution and the lattice planner has no iteration budget.
    ``progress(n)`` is called with the number of runs just finished (``len(planners) * runs`` in all).
    """
    names = tuple(parse_planner_name(p) for p in planners)
    out: dict[str, PlannerRuns] = {}
    for name in names:
        its = iterations if name == "thesis-optimality-seeking" else None
        out[name] = run_planner(
            name, problems, runs, seed, iterations=its, executor=executor, progress=progress
        )
    return DriftMonteCarlo(
        planners=names,
        seed=seed,
        iterations=iterations,
        runs=out,
        direct_flight_wh=np.asarray([p.direct_flight_wh for p in problems]),
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class PlannerSummary:
    """Table 4 statistics of one planner (energies in Wh, saving as a fraction of direct flight)."""

    success_rate: float
    energy_wh_mean: float
    energy_wh_std: float
    saving_mean: float
    compute_s_median: float
    compute_s_mean: float
    ratio_to_best: float

    def to_record(self) -> dict[str, float]:
        return {
            "success_rate": self.success_rate,
            "energy_wh_mean": self.energy_wh_mean,
            "energy_wh_std": self.energy_wh_std,
            "saving_mean": self.saving_mean,
            "compute_s_median": self.compute_s_median,
        }


def summarize(runs: PlannerRuns, direct_wh: float, best_wh: float) -> PlannerSummary:
    """Success rate, mean and std of energy over successful runs, mean saving, compute time."""
    e = runs.energy_wh[runs.success]
    mean = float(np.mean(e)) if e.size else float("nan")
    return PlannerSummary(
        success_rate=float(np.mean(runs.success)),
        energy_wh_mean=mean,
        energy_wh_std=float(np.std(e, ddof=1)) if e.size > 1 else float("nan"),
        saving_mean=float(np.mean(1.0 - e / direct_wh)) if e.size else float("nan"),
        compute_s_median=float(np.median(runs.compute_s)),
        compute_s_mean=float(np.mean(runs.compute_s)),
        ratio_to_best=mean / best_wh,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class FieldsSummary:
    """One planner across obstacle fields: pooled success rate, and per-field mean savings and ratios."""

    success_rate: float
    saving_mean: float
    saving_min_field: float
    ratio_to_best_mean: float
    compute_s_median: float

    def to_record(self) -> dict[str, float]:
        return {name: getattr(self, name) for name in self.__slots__}  # type: ignore[attr-defined]


def summarize_fields(res: PlannerRuns, direct_wh: FloatArray, best_wh: FloatArray) -> FieldsSummary:
    """Per field: mean saving over direct flight and mean energy over the field's best; then their mean
    (and the worst field's saving) over the fields where the planner succeeded at least once."""
    savings, ratios = [], []
    for f in range(len(direct_wh)):
        m = (res.field == f) & res.success
        if m.any():
            e = res.energy_wh[m]
            savings.append(float(np.mean(1.0 - e / direct_wh[f])))
            ratios.append(float(np.mean(e) / best_wh[f]))
    return FieldsSummary(
        success_rate=float(np.mean(res.success)),
        saving_mean=float(np.mean(savings)) if savings else float("nan"),
        saving_min_field=float(np.min(savings)) if savings else float("nan"),
        ratio_to_best_mean=float(np.mean(ratios)) if ratios else float("nan"),
        compute_s_median=float(np.median(res.compute_s)),
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioPlan:
    """One planner run on a drift scenario (``oceanloc drift-plan``).

    Attributes
    ----------
    scenario : DriftScenario
    planner : str
    seed : int
    problem : DriftProblem
    result : DriftPlanResult
        The plan; DR-RRT* planners keep their search tree (for the figure).
    energy : PathEnergy or None
        Energy account of the plan (IV.14), ``None`` when no path was found.
    ensemble : EnsemblePlan or None
        For an ensemble forecast: every candidate plan flown in every member (the chosen one is
        ``result``).
    """

    scenario: DriftScenario
    planner: DriftPlannerName
    seed: int
    problem: DriftProblem
    result: DriftPlanResult
    energy: PathEnergy | None
    ensemble: EnsemblePlan | None = None

    def summary(self) -> dict[str, Any]:
        """Scenario, planner, status, flight energy (Wh) and unit convention (GeoJSON properties)."""
        return {
            "scenario": self.scenario.name,
            "planner": self.planner,
            "status": self.result.status.value,
            "flight_energy_wh": self.result.flight_energy_wh if self.result.path is not None else None,
            "units": self.problem.energy.convention,
        }

    def to_record(self) -> dict[str, Any]:
        """Scenario, planner, seed, the route, the plan's outcome and its energy account (Wh, s)."""
        return {
            "scenario": self.scenario.name,
            "planner": self.planner,
            "seed": self.seed,
            "currents": self.scenario.currents_description,
            "start_m": self.problem.start_m.tolist(),
            "goal_m": self.problem.goal_m.tolist(),
            "goal_tolerance_m": self.problem.goal_tolerance_m,
            "convention": self.problem.energy.convention,
            "objective": self.problem.objective,
            "objective_unit": self.problem.objective_unit,
            "start_time_s": self.problem.t0_s,
            "time_origin": self.scenario.time_origin,
            "result": self.result.to_record(),
            "energy": None if self.energy is None else self.energy.to_record(),
            "ensemble": None if self.ensemble is None else self.ensemble.to_record(),
        }


def plan_scenario(
    scenario: DriftScenario,
    planner: str | None = None,
    seed: int | None = None,
    *,
    iterations: int | None = None,
) -> ScenarioPlan:
    """Plan ``scenario``'s route with ``planner`` (default: the scenario's) from generator
    ``default_rng(seed)`` (default: the scenario's seed); ``iterations`` bounds the DR-RRT* planners.

    The DR-RRT* planners need the scenario's ``[hdop]`` table (their cost has an HDOP term); without it
    this is a ConfigError.
    """
    name = scenario.planner if planner is None else parse_planner_name(planner, "--planner")
    problem = problem_from_scenario(scenario)
    s = scenario.seed if seed is None else seed
    rng = np.random.default_rng(s)
    ensemble = None
    if scenario.ensemble:
        planner_fn = make_planner(name, iterations)
        ensemble = plan_for_ensemble(problem, scenario.ensemble, planner_fn, rng)
        result = ensemble.result
    elif name == "oceanloc":
        result = make_planner(name)(problem, rng)
    else:
        if problem.hdop is None:
            raise ConfigError(f"{scenario.name}: the DR-RRT* planners need an [hdop] table (flock geometry)")
        mode: ThesisMode = "single" if name == "thesis-single" else "optimality-seeking"
        budget = PlanBudget(max_iterations=iterations) if iterations else None
        result = plan_thesis(problem, rng, budget, ThesisOptions(mode=mode, keep_tree=True))
    energy = (
        None if result.path is None else result.path.energy(problem.energy, through_water=problem.in_water)
    )
    return ScenarioPlan(
        scenario=scenario,
        planner=name,
        seed=s,
        problem=problem,
        result=result,
        energy=energy,
        ensemble=ensemble,
    )
