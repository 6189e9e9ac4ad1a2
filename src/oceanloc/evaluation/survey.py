"""Monte Carlo of closed-loop transponder surveys and their summary metrics (Garcia et al. 2019, Section V).

:func:`survey_monte_carlo` runs :func:`oceanloc.sim.survey.simulate_surveys` over chunks of runs (in this
process, in local worker processes or on a Dask cluster; see :mod:`oceanloc.evaluation.montecarlo`) and
reduces the histories to the paper's metrics: RMSEE per transponder per epoch (eq. 45), mean and standard
deviation of ``log det Y_n`` (block-diagonal over all transponders), NEES (eq. 44) with its chi-square
``3M`` check, and planning time. The same seed gives the same numbers whatever the executor or chunking.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.config.survey import SurveyScenario
from oceanloc.estimation.consistency import ChiSquareCheck, chi_square_check
from oceanloc.evaluation.metrics import LogDetStats, log_det_stats, rmsee
from oceanloc.evaluation.montecarlo import concat_runs, run_chunked
from oceanloc.sim.survey import SurveyRuns, simulate_surveys


@dataclass(frozen=True, slots=True, kw_only=True)
class SurveyRunMetrics:
    """What a chunk of runs sends back: per-run histories without the covariances.

    Attributes
    ----------
    errors_m : (R, N, M, 3) float
    log_det : (R, N) float
    nees : (R, N) float
    sites_enu_m : (R, N, 3) float
    plan_time_s : (R, N - 1) float
    converged : (R, N, M) bool
    """

    errors_m: FloatArray
    log_det: FloatArray
    nees: FloatArray
    sites_enu_m: FloatArray
    plan_time_s: FloatArray
    converged: np.ndarray


@dataclass(frozen=True, slots=True, kw_only=True)
class SurveyMonteCarlo:
    """Summary of a survey Monte Carlo.

    Attributes
    ----------
    scenario : SurveyScenario
    seed : int
    runs : int
    rmsee_m : (N, M) float
        Eq. (45) per epoch and transponder.
    log_det : LogDetStats
        ``log det Y_n`` over runs, per epoch.
    nees : (R, N) float
        Eq. (44) per run and epoch.
    nees_final : ChiSquareCheck
        NEES at the last epoch against ``chi2(3M)``.
    plan_time_s : float
        Mean planning time per run and epoch (batched wall time divided by the batch), seconds.
    converged_fraction : float
        Share of MAP solves that met the step-size test.
    sites_enu_m : (R, N, 3) float
        Every run's measurement sites.
    """

    scenario: SurveyScenario
    seed: int
    runs: int
    rmsee_m: FloatArray
    log_det: LogDetStats
    nees: FloatArray
    nees_final: ChiSquareCheck
    plan_time_s: float
    converged_fraction: float
    sites_enu_m: FloatArray

    def sample_run(self, run: int = 0) -> SurveyRuns:
        """The full history of one run (re-simulated from its seed: identical to the Monte Carlo's)."""
        return simulate_surveys(self.scenario, [run], self.seed)


def survey_monte_carlo(
    scenario: SurveyScenario,
    runs: int,
    seed: int,
    *,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> SurveyMonteCarlo:
    """Run ``runs`` independent surveys of ``scenario`` and summarize them."""
    task = functools.partial(_chunk_metrics, scenario=scenario, seed=seed)
    parts = run_chunked(task, runs, executor=executor, chunk_size=chunk_size, progress=progress)
    joined = concat_runs(parts)
    errors, log_det, nees = joined.errors_m, joined.log_det, joined.nees
    plan_time, converged = joined.plan_time_s, joined.converged
    return SurveyMonteCarlo(
        scenario=scenario,
        seed=seed,
        runs=runs,
        rmsee_m=rmsee(errors),
        log_det=log_det_stats(log_det),
        nees=nees,
        nees_final=chi_square_check(nees[:, -1], 3 * scenario.n_transponders),
        plan_time_s=float(plan_time.mean()) if plan_time.size else 0.0,
        converged_fraction=float(converged.mean()),
        sites_enu_m=joined.sites_enu_m,
    )


def _chunk_metrics(run_indices: np.ndarray, *, scenario: SurveyScenario, seed: int) -> SurveyRunMetrics:
    runs = simulate_surveys(scenario, run_indices, seed)
    return SurveyRunMetrics(
        errors_m=runs.errors_m,
        log_det=runs.log_det,
        nees=runs.nees,
        sites_enu_m=runs.sites_enu_m,
        plan_time_s=runs.plan_time_s,
        converged=runs.converged,
    )
