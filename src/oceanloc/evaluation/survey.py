"""Monte Carlo of closed-loop transponder surveys and their summary metrics (Garcia et al. 2019, Section V).

:func:`survey_monte_carlo` runs :func:`oceanloc.sim.survey.simulate_surveys` over chunks of runs (in this
process, in local worker processes or on a Dask cluster; see :mod:`oceanloc.evaluation.montecarlo`) and
reduces the histories to the paper's metrics: RMSEE per transponder per epoch (eq. 45), mean and standard
deviation of ``log det Y_n`` (block-diagonal over all transponders), NEES (eq. 44) with its chi-square
``3M`` check, and planning time. The same seed gives the same numbers whatever the executor or chunking.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from oceanloc import _validate
from oceanloc._typing import FloatArray
from oceanloc.config.survey import SurveyScenario
from oceanloc.estimation.consistency import (
    ChiSquareCheck,
    ConfidenceEllipse,
    chi_square_check,
    confidence_ellipse,
)
from oceanloc.evaluation.metrics import EpochConsistency, LogDetStats, epoch_consistency, log_det_stats, rmsee
from oceanloc.evaluation.montecarlo import concat_runs, run_chunked
from oceanloc.planning.site_planners import site_planner_label, site_planner_name
from oceanloc.sim.survey import SurveyRuns, simulate_surveys

if TYPE_CHECKING:
    import xarray as xr


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
    log_det_runs : (R, N) float
        ``log det Y_n`` per run and epoch, nats.
    nees : (R, N) float
        Eq. (44) per run and epoch.
    nees_final : ChiSquareCheck
        NEES at the last epoch against ``chi2(3M)``.
    consistency : EpochConsistency
        Mean NEES and the share of runs above the ``chi2(3M)`` 95 % quantile at every epoch.
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
    log_det_runs: FloatArray
    nees: FloatArray
    nees_final: ChiSquareCheck
    consistency: EpochConsistency
    plan_time_s: float
    converged_fraction: float
    sites_enu_m: FloatArray

    def sample_run(self, run: int = 0) -> SurveyRuns:
        """The full history of one run (re-simulated from its seed: identical to the Monte Carlo's)."""
        return simulate_surveys(self.scenario, [run], self.seed)

    def to_record(self) -> dict[str, Any]:
        """Plain JSON-ready summary: per-epoch RMSEE (metres) per transponder, log det mean and std
        (nats), the NEES check at the last epoch and the consistency by epoch."""
        c = self.nees_final
        return {
            "scenario": self.scenario.name,
            "planner": site_planner_name(self.scenario.planner),
            "planner_label": site_planner_label(self.scenario.planner),
            "runs": self.runs,
            "seed": self.seed,
            "epochs": self.scenario.epochs,
            "rmsee_m": self.rmsee_m.tolist(),
            "logdet_mean": self.log_det.mean.tolist(),
            "logdet_std": self.log_det.std.tolist(),
            "nees": {
                "epoch": self.scenario.epochs,
                "mean": float(c.mean),
                "dof": int(c.dof),
                "mean_band": [float(v) for v in c.mean_band],
                "mean_within_band": bool(c.mean_within_band),
                "p_value": float(c.p_value),
            },
            "consistency_by_epoch": self.consistency.to_record(),
            "plan_time_s": float(self.plan_time_s),
            "converged_fraction": float(self.converged_fraction),
        }

    def to_dataset(self) -> xr.Dataset:
        """The Monte Carlo as an xarray Dataset: dims ``run``, ``epoch``, ``transponder``."""
        import xarray as xr

        n_runs, n_epochs = self.nees.shape
        dof = self.consistency.dof
        return xr.Dataset(
            {
                "rmsee": (
                    ("epoch", "transponder"),
                    self.rmsee_m,
                    _attrs("m", "root-mean-square estimation error (eq. 45)"),
                ),
                "log_det_mean": (
                    "epoch",
                    self.log_det.mean,
                    _attrs("1", "mean over runs of log det Y_n (nats)"),
                ),
                "log_det_std": (
                    "epoch",
                    self.log_det.std,
                    _attrs("1", "standard deviation over runs of log det Y_n (nats)"),
                ),
                "log_det": (("run", "epoch"), self.log_det_runs, _attrs("1", "log det Y_n per run (nats)")),
                "nees": (
                    ("run", "epoch"),
                    self.nees,
                    _attrs("1", f"normalized estimation error squared (eq. 44), chi2({dof})"),
                ),
                "mean_nees": ("epoch", self.consistency.mean_nees, _attrs("1", "mean NEES over runs")),
                "fraction_nees_above_q95": (
                    "epoch",
                    self.consistency.fraction_above,
                    _attrs("1", f"share of runs with NEES above the chi2({dof}) 95 % quantile"),
                ),
            },
            coords={
                "run": ("run", np.arange(n_runs), _attrs("1", "Monte Carlo run index (its seed)")),
                "epoch": ("epoch", np.arange(1, n_epochs + 1), _attrs("1", "measurement epoch n")),
                "transponder": (
                    "transponder",
                    np.arange(1, self.scenario.n_transponders + 1),
                    _attrs("1", "transponder m"),
                ),
            },
            attrs={
                "title": f"survey Monte Carlo of {self.scenario.name}",
                "planner": site_planner_name(self.scenario.planner),
                "planner_label": site_planner_label(self.scenario.planner),
                "runs": n_runs,
                "chi2_dof": dof,
                "chi2_q95": self.consistency.quantile,
                "plan_time_s": self.plan_time_s,
                "converged_fraction": self.converged_fraction,
            },
        )


def _attrs(units: str, long_name: str) -> dict[str, str]:
    return {"units": units, "long_name": long_name}


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
    _validate.integer("seed", seed, lo=0, hi=2**63 - 1)
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
        log_det_runs=log_det,
        nees=nees,
        nees_final=chi_square_check(nees[:, -1], 3 * scenario.n_transponders),
        consistency=epoch_consistency(nees, 3 * scenario.n_transponders),
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


@dataclass(frozen=True, slots=True, kw_only=True)
class SingleSurvey:
    """One simulated survey and what ``oceanloc simulate survey --runs 1`` (and ``demo``) reports.

    Attributes
    ----------
    scenario : SurveyScenario
    seed : int
    run : SurveyRuns
        The history (``R = 1``).
    ellipses : ConfidenceEllipse
        95 % horizontal confidence ellipses of the final estimates (Appendix B), one per transponder.
    """

    scenario: SurveyScenario
    seed: int
    run: SurveyRuns
    ellipses: ConfidenceEllipse

    @property
    def final_estimates_m(self) -> FloatArray:
        """``(M, 3)`` estimates after the last epoch, metres."""
        return self.run.estimates_m[0, -1]

    @property
    def error_norm_m(self) -> FloatArray:
        """``(N, M)`` estimation error norms per epoch and transponder, metres."""
        return np.linalg.norm(self.run.errors_m[0], axis=-1)

    @property
    def sigma_up_m(self) -> FloatArray:
        """``(M,)`` one-sigma vertical uncertainty of the final estimates, metres."""
        return np.sqrt(self.run.covariances_m2[0, -1, :, 2, 2])

    def to_record(self) -> dict[str, Any]:
        scen, ell, final = self.scenario, self.ellipses, self.final_estimates_m
        errors = self.error_norm_m[-1]
        return {
            "scenario": scen.name,
            "planner": site_planner_name(scen.planner),
            "planner_label": site_planner_label(scen.planner),
            "seed": self.seed,
            "epochs": scen.epochs,
            "transponders": [
                {
                    "m": m + 1,
                    "truth_enu_m": scen.transponders_enu_m[m].tolist(),
                    "estimate_enu_m": final[m].tolist(),
                    "error_m": float(errors[m]),
                    "ellipse95_semi_axes_m": [float(ell.semi_major_m[m]), float(ell.semi_minor_m[m])],
                    "ellipse95_angle_deg": float(np.degrees(ell.angle_rad[m])),
                    "sigma_u_m": float(self.sigma_up_m[m]),
                }
                for m in range(scen.n_transponders)
            ],
            "log_det": self.run.log_det[0].tolist(),
            "error_norm_m": self.error_norm_m.tolist(),
            "sites_enu_m": self.run.sites_enu_m[0].tolist(),
            "nees_final": float(self.run.nees[0, -1]),
            "nees_dof": 3 * scen.n_transponders,
            "plan_time_s": float(self.run.plan_time_s.mean()) if self.run.plan_time_s.size else 0.0,
        }


def single_survey(scenario: SurveyScenario, seed: int) -> SingleSurvey:
    """Simulate run 0 of ``scenario`` with master seed ``seed`` (the Monte Carlo's run 0)."""
    run = simulate_surveys(scenario, [0], seed)
    final, cov = run.estimates_m[0, -1], run.covariances_m2[0, -1]
    return SingleSurvey(
        scenario=scenario, seed=seed, run=run, ellipses=confidence_ellipse(final[:, :2], cov[:, :2, :2])
    )


def planners_dataset(groups: Mapping[str, Sequence[SurveyMonteCarlo]]) -> xr.Dataset:
    """Several Monte Carlos in one Dataset: each group (e.g. ``"M1"``, ``"M4"``: same runs and epochs,
    one study per planner) is stacked along a ``planner_<group>`` dim, its variables prefixed ``<group>_``
    and its transponder dim named ``transponder_<group>``."""
    import xarray as xr

    parts = []
    for group, studies in groups.items():
        names = [site_planner_name(s.scenario.planner) for s in studies]
        stacked = xr.concat([s.to_dataset() for s in studies], dim="planner", combine_attrs="override")
        stacked = stacked.assign_coords(planner=("planner", names, {"long_name": "measurement-site planner"}))
        stacked = stacked.rename(
            {"planner": f"planner_{group}", "transponder": f"transponder_{group}"}
            | {v: f"{group}_{v}" for v in stacked.data_vars}
        )
        parts.append(stacked)
    merged = xr.merge(parts, combine_attrs="override")
    merged.attrs = {"title": "survey Monte Carlos by planner", "groups": ", ".join(groups)}
    return merged
