"""Replay planning on recorded data: Garcia et al. (2019) Section VI (Tables VII, IX) and PLANS 2018 eq. 31.

The journal's experiment: 100 Monte Carlo runs with random initial transponder estimates, 50
measurement locations per run chosen by each planner among the ranges recorded at the SPAWAR pier
(``p_V(1) = [8.62, -6.77, 0]`` m, ``phi(1) = 13 deg``, ``T = 1`` s, 3 m/s, ``w_max = 30 deg/s``,
``sigma_eps = 1.006`` m); Table VII for beacon 1 alone (``M = 1``), Table IX for both beacons (``M = 2``,
RMSEE of ``m = 1``). The thesis (Tables 6.2 and 6.6) adds the greedy planner within ``d_max = 10`` m
against a random point in that disk. :func:`replay_logs` runs that experiment on a GPS + USBL log pair
(for example ``oceanloc simulate logs``); :func:`replay_gnssa` runs it on a GNSS-A survey, with the
reference solution over all pings as the truth. Readings: :mod:`oceanloc.field.replay`,
:mod:`oceanloc.field.replay_records` and :func:`gnssa_replay_settings`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa import GnssaOptions, GnssaResult
from oceanloc.evaluation.replay import ReplayStudy, epochs_to_reach, replay_planners
from oceanloc.field.replay import DEFAULT_PLANNERS, RECORDED, RecordSet, ReplaySettings
from oceanloc.field.replay_records import gnssa_replay_records, log_reference, range_log_records
from oceanloc.io.gnssa import GnssaSurvey
from oceanloc.io.usbl import AlignedRanges
from oceanloc.units import DEG

TABULATED_EPOCHS: tuple[int, ...] = (3, 7, 30)
PAPER_RUNS = 100
LOG_BEACONS_ENU_M = np.array([[9.21, 1.68, -1.15], [2.79, 0.44, -1.15]])
"""Journal Tables VI and VIII: the beacons' GPS-surveyed positions (``oceanloc simulate logs`` uses them)."""
LOG_START_ENU_M = np.array([8.62, -6.77, 0.0])
LOG_START_YAW_DEG = 13.0
TABLE_BEACONS: dict[str, tuple[int, ...]] = {"VII": (1,), "IX": (1, 2)}

PaperValues = Mapping[tuple[int, str], tuple[float, float, float, str]]
"""``(epoch n, planner) -> (RMSEE of m = 1 in m, mean log det Y_n, its std, source)``."""


def _table(source: str, planners: Sequence[str], rows: dict[int, Sequence[float]]) -> PaperValues:
    out = {}
    for epoch, values in rows.items():
        for j, planner in enumerate(planners):
            rm, mean, std = values[3 * j : 3 * j + 3]
            out[(epoch, planner)] = (rm, mean, std, source)
    return out


PAPER_TABLES: dict[str, PaperValues] = {
    "VII": {
        **_table("journal Table VII", ("k0", "k1", "k2", "k3"), {
            3: (38.28, -3.89, 1.05, 28.55, -3.43, 1.24, 35.78, -3.64, 1.33, 27.46, -3.36, 1.33),
            7: (16.32, 0.17, 0.84, 13.44, 0.57, 0.85, 20.29, 0.42, 1.21, 10.44, 0.78, 1.24),
            30: (8.23, 4.08, 1.06, 3.99, 5.87, 0.70, 4.15, 5.91, 0.74, 2.68, 5.73, 0.67),
        }),
        **_table("thesis Table 6.2", ("random-disk", "greedy"), {
            3: (55.11, -3.64, 1.14, 32.83, -2.82, 1.28),
            7: (26.79, 0.21, 0.61, 17.39, 0.89, 1.45),
            30: (16.56, 2.71, 0.38, 3.35, 5.65, 0.99),
        }),
    },
    "IX": {
        **_table("journal Table IX", ("k0", "k1", "k2", "k3"), {
            3: (43.69, -8.36, 1.72, 30.43, -6.90, 2.06, 34.27, -7.16, 2.14, 31.16, -6.58, 2.07),
            7: (16.79, 0.14, 0.99, 14.81, 0.79, 1.28, 13.89, 0.93, 1.31, 14.43, 1.03, 1.58),
            30: (9.29, 7.22, 1.83, 4.65, 10.59, 1.73, 4.42, 10.85, 1.40, 3.93, 10.63, 1.25),
        }),
        **_table("thesis Table 6.6", ("random-disk", "greedy"), {
            3: (53.65, -7.16, 2.34, 37.45, -8.59, 1.45),
            7: (24.59, 0.48, 1.43, 6.65, 3.48, 0.46),
            30: (16.99, 5.74, 1.11, 2.08, 10.48, 0.89),
        }),
    },
}  # fmt: skip


@dataclass(frozen=True, slots=True, kw_only=True)
class ReplayRow:
    """One Table VII / IX row: a planner at an epoch, ours beside the paper's where it has one.

    ``logdet_z`` is the difference of the means over ``sqrt(std^2 / runs + paper_std^2 / 100)``.
    """

    epoch: int
    planner: str
    rmse_m: float
    logdet_mean: float
    logdet_std: float
    paper_rmse_m: float | None = None
    paper_logdet_mean: float | None = None
    paper_logdet_std: float | None = None
    paper_source: str = ""
    logdet_z: float | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class ConvergenceRow:
    """How fast a planner converges against the log's own order (``recorded``).

    Attributes
    ----------
    planner : str
    rmse_final_m, logdet_final : float
        RMSEE (of the table's transponder) and mean log det at the last epoch ``N``.
    epochs_to_recorded_rmse : int or None
        Epoch from which the RMSEE stays at most the recorded order's at ``N`` (None: not at ``N``).
    epochs_to_recorded_logdet : int or None
        Epoch from which the mean log det stays at least the recorded order's at ``N``.
    nees_final : float
        Mean NEES at ``N`` (``3M`` if consistent).
    snap_distance_m, plan_time_s : float
    converged_fraction : float
        Share of MAP solves that met the step-size test within ``J_max``.
    """

    planner: str
    rmse_final_m: float
    logdet_final: float
    epochs_to_recorded_rmse: int | None
    epochs_to_recorded_logdet: int | None
    nees_final: float
    snap_distance_m: float
    plan_time_s: float
    converged_fraction: float


@dataclass(frozen=True, slots=True, kw_only=True)
class ReplayExperiment:
    """One record set replayed under every planner.

    Attributes
    ----------
    label : str
        ``"VII"``, ``"IX"`` or the GNSS-A survey's name.
    records : RecordSet
    settings : ReplaySettings
    studies : dict of str to ReplayStudy
    rows : list of ReplayRow
    convergence : list of ConvergenceRow
        Empty when ``recorded`` was not run.
    """

    label: str
    records: RecordSet
    settings: ReplaySettings
    studies: dict[str, ReplayStudy]
    rows: list[ReplayRow]
    convergence: list[ConvergenceRow]


def replay_rows(
    studies: Mapping[str, ReplayStudy],
    *,
    epochs: Sequence[int] = TABULATED_EPOCHS,
    transponder: int = 0,
    paper: PaperValues | None = None,
    paper_runs: int = PAPER_RUNS,
) -> list[ReplayRow]:
    """Rows for every tabulated epoch within the replay's ``N``, planners in the studies' order."""
    rows = []
    for epoch in epochs:
        for name, study in studies.items():
            if epoch > study.epochs:
                continue
            mean, std = float(study.log_det.mean[epoch - 1]), float(study.log_det.std[epoch - 1])
            row = {
                "epoch": epoch,
                "planner": name,
                "rmse_m": float(study.rmsee_m[epoch - 1, transponder]),
                "logdet_mean": mean,
                "logdet_std": std,
            }
            if paper is not None and (epoch, name) in paper:
                p_rmse, p_mean, p_std, source = paper[(epoch, name)]
                se = np.sqrt(std**2 / study.runs + p_std**2 / paper_runs)
                row.update(
                    paper_rmse_m=p_rmse,
                    paper_logdet_mean=p_mean,
                    paper_logdet_std=p_std,
                    paper_source=source,
                    logdet_z=float((mean - p_mean) / se) if se > 0 else None,
                )
            rows.append(ReplayRow(**row))
    return rows


def convergence_rows(studies: Mapping[str, ReplayStudy], transponder: int = 0) -> list[ConvergenceRow]:
    """Per planner: last-epoch metrics and the epochs needed to match the recorded order's last epoch."""
    if RECORDED not in studies:
        return []
    base = studies[RECORDED]
    rmse_target = float(base.rmsee_m[-1, transponder])
    logdet_target = float(base.log_det.mean[-1])
    return [
        ConvergenceRow(
            planner=name,
            rmse_final_m=float(s.rmsee_m[-1, transponder]),
            logdet_final=float(s.log_det.mean[-1]),
            epochs_to_recorded_rmse=epochs_to_reach(
                s.rmsee_m[:, transponder], rmse_target, higher_is_better=False
            ),
            epochs_to_recorded_logdet=epochs_to_reach(s.log_det.mean, logdet_target, higher_is_better=True),
            nees_final=float(s.nees_mean[-1]),
            snap_distance_m=s.snap_distance_m,
            plan_time_s=s.plan_time_s,
            converged_fraction=s.converged_fraction,
        )
        for name, s in studies.items()
    ]


def run_experiment(
    label: str,
    records: RecordSet,
    settings: ReplaySettings,
    planners: Sequence[str],
    runs: int,
    seed: int,
    *,
    paper: PaperValues | None = None,
    executor: Executor | None = None,
    progress: Callable[[int], None] | None = None,
) -> ReplayExperiment:
    """Replay ``records`` under every planner and tabulate (RMSEE of the first transponder)."""
    studies = replay_planners(records, settings, planners, runs, seed, executor=executor, progress=progress)
    return ReplayExperiment(
        label=label,
        records=records,
        settings=settings,
        studies=studies,
        rows=replay_rows(studies, paper=paper),
        convergence=convergence_rows(studies),
    )


def median_record_step_m(records: RecordSet) -> float:
    """Median horizontal distance between consecutive records: how far the recording vehicle moved."""
    step = np.hypot(*np.diff(records.location_enu_m[:, :2], axis=0).T)
    return float(np.median(step)) if step.size else 1.0


def gnssa_replay_settings(
    records: RecordSet,
    *,
    epochs: int = 50,
    step_m: float | None = None,
    reach_m: float | None = None,
    max_yaw_rate_deg_s: float = 30.0,
    prior_sigma_enu_m: Sequence[float] = (100.0, 100.0, 2.0),
) -> ReplaySettings:
    """Replay settings for a GNSS-A survey.

    The journal's 3 m per epoch and 10 m reach fit a beacon 1 m deep ranged from 10-40 m; a Wave Glider
    survey pings every 10-15 s, 6-11 m apart, around a transponder about 53 m deep at 100-200 m
    offsets, so 3 m steps barely change the geometry while the recorded order advances a ping spacing
    per epoch. Default reading: one epoch is ``T = 1`` s at the speed that covers the recording's median
    ping spacing (``step_m``), the yaw-rate limit stays 30 deg/s, and ``d_max`` is two ping spacings
    (one spacing would leave only the neighbouring pings in reach). Start: the first ping, heading
    along the track; prior ``diag(100, 100, 2)^2`` m^2, as in the journal's simulations.
    """
    step = median_record_step_m(records) if step_m is None else float(step_m)
    return ReplaySettings(
        epochs=epochs,
        speed_mps=step,
        period_s=1.0,
        max_yaw_rate_rad_s=max_yaw_rate_deg_s * DEG,
        reach_m=2.0 * step if reach_m is None else float(reach_m),
        prior_cov_m2=_prior_cov(prior_sigma_enu_m),
    )


def log_replay_settings(
    *,
    epochs: int = 50,
    start_enu_m: Sequence[float] = tuple(LOG_START_ENU_M),
    start_yaw_deg: float = LOG_START_YAW_DEG,
    speed_mps: float = 3.0,
    reach_m: float = 10.0,
    max_yaw_rate_deg_s: float = 30.0,
    prior_sigma_enu_m: Sequence[float] = (100.0, 100.0, 2.0),
) -> ReplaySettings:
    """Journal Tables VI and VIII (and ``d_max = 10`` m of PLANS Section V-C / thesis Table 6.1)."""
    return ReplaySettings(
        epochs=epochs,
        start_enu_m=np.asarray(start_enu_m, dtype=float),
        start_yaw_rad=start_yaw_deg * DEG,
        speed_mps=speed_mps,
        period_s=1.0,
        max_yaw_rate_rad_s=max_yaw_rate_deg_s * DEG,
        reach_m=reach_m,
        prior_cov_m2=_prior_cov(prior_sigma_enu_m),
    )


def _prior_cov(sigma: Sequence[float]) -> FloatArray:
    s = np.asarray(sigma, dtype=float)
    if s.shape != (3,) or not np.all(s > 0):
        raise ConfigError(f"prior sigma must be three positive values (E, N, U in m), got {list(sigma)}")
    return np.diag(s**2)


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaReplay:
    """A GNSS-A survey replayed: the reference solution and the experiment."""

    survey: str
    reference: GnssaResult
    experiment: ReplayExperiment


def replay_gnssa(
    survey: GnssaSurvey,
    options: GnssaOptions,
    *,
    runs: int = PAPER_RUNS,
    seed: int = 2019,
    planners: Sequence[str] = DEFAULT_PLANNERS,
    settings: Callable[[RecordSet], ReplaySettings] = gnssa_replay_settings,
    executor: Executor | None = None,
    progress: Callable[[int], None] | None = None,
) -> GnssaReplay:
    """Localize the survey over all pings (the reference), then replay its pings under every planner.

    ``settings`` builds the :class:`ReplaySettings` from the record set (default
    :func:`gnssa_replay_settings`).
    """
    records, reference = gnssa_replay_records(survey, options)
    experiment = run_experiment(
        survey.name, records, settings(records), planners, runs, seed, executor=executor, progress=progress
    )
    return GnssaReplay(survey=survey.name, reference=reference, experiment=experiment)


@dataclass(frozen=True, slots=True, kw_only=True)
class LogsReplay:
    """Tables VII and IX on a log pair.

    Attributes
    ----------
    truth_enu_m : dict of int to (3,) float
        The positions errors are measured against, per beacon.
    truth_source : str
        ``"given"`` or ``"estimate"`` (the robust estimate over every range).
    estimate_enu_m : dict of int to (3,) float
        The robust estimate over every range (its outliers are left out of the records).
    experiments : dict of str to ReplayExperiment
    """

    truth_enu_m: dict[int, FloatArray]
    truth_source: str
    estimate_enu_m: dict[int, FloatArray]
    experiments: dict[str, ReplayExperiment]


def replay_logs(
    aligned: AlignedRanges,
    *,
    truth_enu_m: Mapping[int, Sequence[float]] | None = None,
    tables: Sequence[str] = ("VII", "IX"),
    runs: int = PAPER_RUNS,
    seed: int = 2019,
    planners: Sequence[str] = DEFAULT_PLANNERS,
    settings: ReplaySettings | None = None,
    sigma_range_m: float = 1.006,
    executor: Executor | None = None,
    progress: Callable[[int], None] | None = None,
) -> LogsReplay:
    """Tables VII (beacon 1) and IX (beacons 1 and 2) on aligned GPS + USBL ranges.

    ``truth_enu_m`` maps beacon ids to their positions in the frame of ``aligned``; ``None`` uses the
    robust estimate over every range as the reference (as for GNSS-A).
    """
    unknown = [t for t in tables if t not in TABLE_BEACONS]
    if unknown or not tables:
        raise ConfigError(f"tables must be among {', '.join(TABLE_BEACONS)}; got {', '.join(tables)}")
    estimate, keep = log_reference(aligned, sigma_range_m)
    truth = {b: np.asarray(v, dtype=float) for b, v in (truth_enu_m or estimate).items()}
    opts = settings or log_replay_settings()
    experiments = {}
    for table in tables:
        beacons = TABLE_BEACONS[table]
        missing = [b for b in beacons if b not in truth]
        if missing:
            raise ConfigError(f"Table {table} needs the position of beacon(s) {missing}: give --truth")
        records = range_log_records(
            aligned,
            beacons,
            np.array([truth[b] for b in beacons]),
            keep=keep,
            sigma_range_m=sigma_range_m,
            name=f"Table {table}: beacon{'s' if len(beacons) > 1 else ''} " + ", ".join(map(str, beacons)),
        )
        experiments[table] = run_experiment(
            table, records, opts, planners, runs, seed, paper=PAPER_TABLES[table], executor=executor,
            progress=progress,
        )  # fmt: skip
    return LogsReplay(
        truth_enu_m=truth,
        truth_source="estimate" if truth_enu_m is None else "given",
        estimate_enu_m=estimate,
        experiments=experiments,
    )


def experiment_json(exp: ReplayExperiment) -> dict[str, object]:
    """The machine-readable record of one replayed record set."""
    s = exp.settings
    return {
        "label": exp.label,
        "records": exp.records.name,
        "n_records": exp.records.n_records,
        "reference_enu_m": exp.records.reference_enu_m,
        "settings": {
            "epochs": s.epochs,
            "speed_mps": s.speed_mps,
            "period_s": s.period_s,
            "max_yaw_rate_deg_s": s.max_yaw_rate_rad_s / DEG,
            "reach_m": s.reach_m,
            "prior_sigma_enu_m": np.sqrt(np.diag(s.prior_cov_m2)),
            "sigma_planning_m": exp.records.sigma_planning_m,
        },
        "rows": [
            {
                "epoch": r.epoch,
                "planner": r.planner,
                "rmse_m": r.rmse_m,
                "logdet_mean": r.logdet_mean,
                "logdet_std": r.logdet_std,
                "paper_rmse_m": r.paper_rmse_m,
                "paper_logdet_mean": r.paper_logdet_mean,
                "paper_logdet_std": r.paper_logdet_std,
                "paper_source": r.paper_source or None,
                "logdet_z": r.logdet_z,
            }
            for r in exp.rows
        ],
        "convergence": [
            {
                "planner": c.planner,
                "rmse_final_m": c.rmse_final_m,
                "logdet_final": c.logdet_final,
                "epochs_to_recorded_rmse": c.epochs_to_recorded_rmse,
                "epochs_to_recorded_logdet": c.epochs_to_recorded_logdet,
                "nees_final": c.nees_final,
                "snap_distance_m": c.snap_distance_m,
                "plan_time_s": c.plan_time_s,
                "converged_fraction": c.converged_fraction,
            }
            for c in exp.convergence
        ],
        "planners": {
            name: {
                "runs": st.runs,
                "rmsee_m": st.rmsee_m[:, 0],
                "logdet_mean": st.log_det.mean,
                "logdet_std": st.log_det.std,
                "nees_mean": st.nees_mean,
                "converged_fraction": st.converged_fraction,
            }
            for name, st in exp.studies.items()
        },
    }
