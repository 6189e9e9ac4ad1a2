"""Closed-loop transponder surveys: measure, estimate, plan, move; vectorized across Monte Carlo runs.

One survey (Garcia et al. 2019, Section V) runs for ``N`` epochs. The epoch convention is the one that
reproduces the journal's random rows (k = 0) of Tables III and V:

* measurement ``n`` is taken at ``p_V(n)``; ``p_V(1)`` and ``phi(1)`` are the scenario's start;
* the statistics of epoch ``n`` use the prior and measurements ``1..n`` (estimation starts at ``n = 1``);
* at epoch ``n < N`` the planner uses the epoch-``n`` estimates and covariances, only its first control is
  applied (receding horizon), giving ``p_V(n+1)`` and ``phi(n+1)`` through eq. (1); no planning after the
  last epoch;
* ``Y_n`` is the inverse of the MAP covariance (22), prior information included.

Each run draws its prior mean from ``N(p_T, P_0)`` (one draw per transponder, as in the paper), its range
noise and its random-planner draws from its own generator seeded by ``(seed, run)``, in a fixed order
(prior, then per epoch: noise, planner). A run's numbers therefore do not depend on the batch it is
simulated in. Gauss-Newton is warm-started from the previous epoch's estimate: restarting from the prior
mean every epoch sends many runs to the depth mirror (``z -> -z``), which the papers' NEES histograms rule
out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc import _validate
from oceanloc._random import run_generators, standard_normal
from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.config.survey import SurveyScenario
from oceanloc.errors import ArgumentError
from oceanloc.estimation.consistency import nees
from oceanloc.estimation.map_gauss_newton import GaussianPrior, MapOptions, RangeProblem, solve_map
from oceanloc.models.measurements import range_m
from oceanloc.planning.information import log_det_information
from oceanloc.planning.measurement_sites import MeasurementSitePlanner, PlanningState
from oceanloc.planning.site_planners import make_site_planner


@dataclass(frozen=True, slots=True, kw_only=True)
class SurveyRuns:
    """Per-run histories of simulated surveys (``R`` runs, ``N`` epochs, ``M`` transponders).

    Attributes
    ----------
    run_indices : (R,) int
        Global run indices (their seeds).
    transponders_enu_m : (M, 3) float
        True positions.
    prior_mean_m : (R, M, 3) float
        Each run's prior mean ``0p_T``.
    sites_enu_m : (R, N, 3) float
        Vehicle positions where the ranges were taken.
    yaw_rad : (R, N) float
        Vehicle headings at those epochs.
    ranges_m : (R, N, M) float
        Measured ranges.
    estimates_m : (R, N, M, 3) float
        MAP estimates after each epoch.
    covariances_m2 : (R, N, M, 3, 3) float
        Their covariances (22).
    log_det : (R, N) float
        ``log det Y_n`` of the block-diagonal information over all transponders (eq. 32), nats.
    nees : (R, N) float
        Eq. (44) over all transponders.
    converged : (R, N, M) bool
        Gauss-Newton step-size test met.
    plan_objective : (R, N - 1) float
        Information gain the planner expected from its plan, nats.
    plan_time_s : (R, N - 1) float
        Planning wall time per run: the batched call's time divided by the batch size.
    """

    run_indices: IntArray
    transponders_enu_m: FloatArray
    prior_mean_m: FloatArray
    sites_enu_m: FloatArray
    yaw_rad: FloatArray
    ranges_m: FloatArray
    estimates_m: FloatArray
    covariances_m2: FloatArray
    log_det: FloatArray
    nees: FloatArray
    converged: BoolArray
    plan_objective: FloatArray
    plan_time_s: FloatArray

    @property
    def errors_m(self) -> FloatArray:
        """Position errors ``p_T - p_hat`` (eq. 42), ``(R, N, M, 3)``."""
        return self.transponders_enu_m - self.estimates_m

    @property
    def runs(self) -> int:
        return int(self.run_indices.size)


def scenario_planner(scenario: SurveyScenario) -> MeasurementSitePlanner:
    """The scenario's own planner."""
    return make_site_planner(
        scenario.planner,
        max_yaw_rate_rad_s=scenario.max_yaw_rate_rad_s,
        speed_mps=scenario.speed_mps,
        period_s=scenario.period_s,
        sigma_range_m=scenario.sigma_range_m,
    )


def simulate_surveys(scenario: SurveyScenario, run_indices: ArrayLike, seed: int) -> SurveyRuns:
    """Simulate the runs ``run_indices`` of a scenario as one vectorized batch.

    Parameters
    ----------
    scenario : SurveyScenario
        World, vehicle, sensor, prior, estimator settings and planner.
    run_indices : (R,) int
        Global run indices; run ``r`` uses the generator seeded by ``(seed, r)``.
    seed : int
        Master seed.
    """
    runs = _validate.float_array("run_indices", run_indices, max_abs=2.0**62).ravel()
    if np.any(runs < 0) or np.any(runs != np.round(runs)):
        raise ArgumentError("run_indices: must be non-negative integers")
    runs = runs.astype(np.int64)
    _validate.integer("seed", seed, lo=0, hi=2**63 - 1)
    scenario.check_runs(runs.size)
    rngs = run_generators(seed, runs)
    n_runs, n_epochs, m = runs.size, scenario.epochs, scenario.n_transponders
    truth = scenario.transponders_enu_m
    sigma = scenario.sigma_range_m
    planner = scenario_planner(scenario)
    options = MapOptions(
        delta_min_m=scenario.estimator.delta_min_m, max_iterations=scenario.estimator.max_iterations
    )

    chol0 = np.linalg.cholesky(scenario.prior_cov_m2)
    prior_mean = truth + standard_normal(rngs, n_runs, (m, 3)) @ chol0.T
    prior = GaussianPrior(mean=prior_mean.reshape(-1, 3), cov=scenario.prior_cov_m2)

    sites = np.empty((n_runs, n_epochs, 3))
    yaws = np.empty((n_runs, n_epochs))
    ranges = np.empty((n_runs, n_epochs, m))
    estimates = np.empty((n_runs, n_epochs, m, 3))
    covariances = np.empty((n_runs, n_epochs, m, 3, 3))
    log_det = np.empty((n_runs, n_epochs))
    nees_n = np.empty((n_runs, n_epochs))
    converged = np.empty((n_runs, n_epochs, m), dtype=bool)
    plan_objective = np.empty((n_runs, max(n_epochs - 1, 0)))
    plan_time = np.empty((n_runs, max(n_epochs - 1, 0)))

    pos = np.broadcast_to(scenario.start_enu_m, (n_runs, 3)).copy()
    yaw = np.full(n_runs, scenario.start_yaw_rad)
    estimate = prior.mean
    for n in range(n_epochs):
        sites[:, n], yaws[:, n] = pos, yaw
        ranges[:, n] = range_m(truth, pos[:, None, :]) + sigma * standard_normal(rngs, n_runs, (m,))
        # One MAP problem per (run, transponder), all epochs so far, warm-started.
        sensor = np.broadcast_to(sites[:, None, : n + 1], (n_runs, m, n + 1, 3)).reshape(-1, n + 1, 3)
        z = np.moveaxis(ranges[:, : n + 1], 1, 2).reshape(-1, n + 1)
        result = solve_map(RangeProblem.build(sensor, z, sigma), prior, options, initial=estimate)
        estimate = result.estimate
        estimates[:, n] = estimate.reshape(n_runs, m, 3)
        covariances[:, n] = result.covariance.reshape(n_runs, m, 3, 3)
        info = result.information.reshape(n_runs, m, 3, 3)
        log_det[:, n] = log_det_information(info).sum(axis=-1)
        nees_n[:, n] = nees(truth - estimates[:, n], info)
        converged[:, n] = result.converged.reshape(n_runs, m)
        if n == n_epochs - 1:
            break
        state = PlanningState(
            pos_enu_m=pos, yaw_rad=yaw, estimates_m=estimates[:, n], covariances_m2=covariances[:, n]
        )
        plan = planner.plan(state, rngs)
        plan_objective[:, n] = plan.objective
        plan_time[:, n] = plan.solve_time_s / n_runs
        pos, yaw = plan.next_pos_enu_m, plan.next_yaw_rad

    return SurveyRuns(
        run_indices=runs,
        transponders_enu_m=truth,
        prior_mean_m=prior_mean,
        sites_enu_m=sites,
        yaw_rad=yaws,
        ranges_m=ranges,
        estimates_m=estimates,
        covariances_m2=covariances,
        log_det=log_det,
        nees=nees_n,
        converged=converged,
        plan_objective=plan_objective,
        plan_time_s=plan_time,
    )
