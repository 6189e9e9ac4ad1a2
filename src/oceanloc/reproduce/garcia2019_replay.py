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

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa import GnssaOptions, GnssaResult
from oceanloc.evaluation.replay import ReplayStudy, epochs_to_reach, replay_planners
from oceanloc.field.range_logs import LogPair, read_log_pair
from oceanloc.field.replay import DEFAULT_PLANNERS, RECORDED, RecordSet, ReplaySettings, planner_label
from oceanloc.field.replay_records import gnssa_replay_records, log_reference, range_log_records
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic, geodetic_to_enu
from oceanloc.io.gnssa import GnssaSurvey, read_gnssa, survey_sound_speeds_mps
from oceanloc.io.usbl import AlignedRanges
from oceanloc.sim.logs import PIER_ORIGIN, BeaconTruth, read_truth
from oceanloc.units import DEG

if TYPE_CHECKING:
    import xarray as xr

TABULATED_EPOCHS: tuple[int, ...] = (3, 7, 30)
PAPER_RUNS = 100
LOG_BEACONS_ENU_M = np.array([[9.21, 1.68, -1.15], [2.79, 0.44, -1.15]])
"""Journal Tables VI and VIII: the beacons' GPS-surveyed positions (``oceanloc simulate logs`` uses them),
ENU in the journal's frame (:data:`JOURNAL_ORIGIN`)."""
JOURNAL_ORIGIN: EnuOrigin = PIER_ORIGIN
"""Origin of the journal's frame (Section VI-C), in which :data:`LOG_BEACONS_ENU_M` and
:data:`LOG_START_ENU_M` are given."""
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

    def to_record(self) -> dict[str, object]:
        """Plain JSON-ready data: settings, table rows, convergence and every planner's curves."""
        return experiment_record(self)

    def to_dataset(self) -> xr.Dataset:
        """Every run of every planner: dims ``planner``, ``run``, ``epoch``, ``transponder``."""
        return experiment_dataset(self)


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
        ``"given"``, ``"journal"``, ``"file NAME"`` or ``"estimate"`` (the robust estimate over every
        range).
    estimate_enu_m : dict of int to (3,) float
        The robust estimate over every range (its outliers are left out of the records).
    experiments : dict of str to ReplayExperiment
    """

    truth_enu_m: dict[int, FloatArray]
    truth_source: str
    estimate_enu_m: dict[int, FloatArray]
    experiments: dict[str, ReplayExperiment]
    logs: LogPair | None = None
    runs: int = 0
    seed: int = 0
    planners: tuple[str, ...] = ()
    inputs: tuple[str, ...] = ()

    def to_record(self) -> dict[str, object]:
        """Plain JSON-ready data: the origin, the reference used, and every table's record."""
        return {
            "seed": self.seed,
            "runs": self.runs,
            "planners": list(self.planners),
            "origin": None if self.logs is None else self.logs.origin_record(),
            "truth_source": self.truth_source,
            "truth_enu_m": {str(b): [float(x) for x in v] for b, v in self.truth_enu_m.items()},
            "estimate_enu_m": {str(b): [float(x) for x in v] for b, v in self.estimate_enu_m.items()},
            "tables": {name: experiment_record(exp) for name, exp in self.experiments.items()},
        }

    def to_dataset(self) -> xr.Dataset:
        """Tables VII and IX along ``experiment`` (see :func:`replays_dataset`)."""
        return replays_dataset(self.experiments)


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


def experiment_record(exp: ReplayExperiment) -> dict[str, object]:
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
                "label": planner_label(name),
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


def experiment_dataset(exp: ReplayExperiment) -> xr.Dataset:
    """The replay Monte Carlo of one record set as a Dataset (CF units and long names).

    Dims: ``planner`` (names, with their labels), ``run`` (global run index: its seed), ``epoch`` (1..N),
    ``transponder`` (the record set's transponders, 1-based), ``axis`` (E, N, U). Planning quantities
    defined between epochs (snap distance) are NaN at epoch 1.
    """
    import xarray as xr  # imported on use: the command line starts without xarray

    names = list(exp.studies)
    hist = [exp.studies[n].histories for n in names]
    runs = hist[0].run_indices
    n = exp.settings.epochs

    def stack(get: Callable[[object], np.ndarray]) -> np.ndarray:
        return np.stack([get(h) for h in hist])

    snap = stack(lambda h: np.concatenate([np.full((h.runs, 1), np.nan), h.snap_distance_m], axis=1))
    m = exp.records.n_transponders
    dims4 = ("planner", "run", "epoch", "transponder")
    data = {
        "error_m": (
            (*dims4, "axis"),
            stack(lambda h: h.errors_m),
            {"units": "m", "long_name": "reference minus estimate (eq. 42)"},
        ),
        "error_norm_m": (
            dims4,
            np.linalg.norm(stack(lambda h: h.errors_m), axis=-1),
            {"units": "m", "long_name": "distance from the estimate to the reference"},
        ),
        "log_det": (
            ("planner", "run", "epoch"),
            stack(lambda h: h.log_det),
            {"units": "1", "long_name": "log det of the information matrix Y_n (eq. 32), nats"},
        ),
        "nees": (
            ("planner", "run", "epoch"),
            stack(lambda h: h.nees),
            {"units": "1", "long_name": f"normalized estimation error squared (eq. 44), {3 * m} dof"},
        ),
        "snap_distance_m": (
            ("planner", "run", "epoch"),
            snap,
            {"units": "m", "long_name": "distance from the planned point to the record used (eq. 31)"},
        ),
        "record": (
            ("planner", "run", "epoch"),
            stack(lambda h: h.chosen),
            {"units": "1", "long_name": "index of the record used"},
        ),
        "rmsee_m": (
            ("planner", "epoch", "transponder"),
            np.stack([exp.studies[p].rmsee_m for p in names]),
            {"units": "m", "long_name": "root mean square estimation error over runs (eq. 45)"},
        ),
        "reference_enu_m": (
            ("transponder", "axis"),
            exp.records.reference_enu_m,
            {"units": "m", "long_name": "reference transponder position, ENU"},
        ),
    }
    coords = {
        "planner": ("planner", names, {"long_name": "planner"}),
        "planner_label": ("planner", [planner_label(p) for p in names], {"long_name": "planner label"}),
        "run": ("run", runs, {"units": "1", "long_name": "Monte Carlo run (its seed index)"}),
        "epoch": ("epoch", np.arange(1, n + 1), {"units": "1", "long_name": "measurement epoch n"}),
        "transponder": ("transponder", np.arange(1, m + 1), {"units": "1", "long_name": "transponder"}),
        "axis": ("axis", ["E", "N", "U"], {"long_name": "east, north, up"}),
    }
    s = exp.settings
    attrs = {
        "title": f"replay on recorded data: {exp.records.name}",
        "records": exp.records.name,
        "n_records": exp.records.n_records,
        "reach_m": s.reach_m,
        "speed_mps": s.speed_mps,
        "max_yaw_rate_deg_s": s.max_yaw_rate_rad_s / DEG,
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def replays_dataset(experiments: Mapping[str, ReplayExperiment]) -> xr.Dataset:
    """Several replayed record sets in one Dataset, along ``experiment`` (Table VII/IX, or the surveys);
    transponders a record set does not have are NaN."""
    import xarray as xr

    parts = [exp.to_dataset().expand_dims(experiment=[label]) for label, exp in experiments.items()]
    ds = xr.concat(parts, dim="experiment", join="outer", combine_attrs="override")
    ds["experiment"].attrs["long_name"] = "replayed record set"
    ds.attrs = {"title": "replay on recorded data (Garcia et al. 2019, Section VI)"}
    return ds


def journal_frame_to(origin: EnuOrigin, enu_m: Sequence[Sequence[float]] | FloatArray) -> FloatArray:
    """Points given in the journal's frame (:data:`JOURNAL_ORIGIN`) in the ENU frame of ``origin``."""
    geo = enu_to_geodetic(np.asarray(enu_m, dtype=float), JOURNAL_ORIGIN).reshape(-1, 3)
    return geodetic_to_enu(geo[:, 0], geo[:, 1], geo[:, 2], origin).reshape(-1, 3)


@dataclass(frozen=True, slots=True, kw_only=True)
class GnssaReplays:
    """GNSS-A surveys replayed (``replay gnssa``): one :class:`GnssaReplay` per file."""

    replays: tuple[GnssaReplay, ...]
    runs: int
    seed: int
    planners: tuple[str, ...]
    epochs: int
    inputs: tuple[str, ...]

    def to_record(self) -> dict[str, object]:
        return {
            "seed": self.seed,
            "runs": self.runs,
            "epochs": self.epochs,
            "planners": list(self.planners),
            "surveys": [
                {
                    "file": r.survey,
                    "reference": {
                        "enu_m": [float(v) for v in r.reference.position_enu_m],
                        "sigma_enu_m": [float(v) for v in r.reference.sigma_enu_m],
                        "pings_used": r.reference.pings_used,
                    },
                    **experiment_record(r.experiment),
                }
                for r in self.replays
            ],
        }

    def to_dataset(self) -> xr.Dataset:
        return replays_dataset({r.survey: r.experiment for r in self.replays})


def replay_gnssa_files(
    paths: Sequence[str | Path],
    *,
    sound_speeds_mps: Sequence[float] = (),
    runs: int = PAPER_RUNS,
    seed: int = 2019,
    planners: Sequence[str] = DEFAULT_PLANNERS,
    epochs: int = 50,
    step_m: float | None = None,
    reach_m: float | None = None,
    max_yaw_rate_deg_s: float = 30.0,
    prior_sigma_enu_m: Sequence[float] = (100.0, 100.0, 2.0),
    executor: Executor | None = None,
    progress: Callable[[int], None] | None = None,
) -> GnssaReplays:
    """Read each GNSS-A file and replay it (:func:`replay_gnssa`, settings :func:`gnssa_replay_settings`)."""
    speeds = survey_sound_speeds_mps(paths, sound_speeds_mps)
    surveys = [read_gnssa(p) for p in paths]

    def settings(records: RecordSet) -> ReplaySettings:
        return gnssa_replay_settings(
            records, epochs=epochs, step_m=step_m, reach_m=reach_m, max_yaw_rate_deg_s=max_yaw_rate_deg_s,
            prior_sigma_enu_m=prior_sigma_enu_m,
        )  # fmt: skip

    kw = {"runs": runs, "seed": seed, "planners": planners, "executor": executor, "progress": progress}
    replays = tuple(
        replay_gnssa(survey, GnssaOptions(sound_speed_mps=c), settings=settings, **kw)
        for survey, c in zip(surveys, speeds, strict=True)
    )
    return GnssaReplays(
        replays=replays, runs=runs, seed=seed, planners=tuple(planners), epochs=epochs,
        inputs=tuple(str(p) for p in paths),
    )  # fmt: skip


LogTruth = str | Path | BeaconTruth | Mapping[int, Sequence[float]]
"""What ``replay logs`` measures errors against: ``"journal"`` (the journal's beacons, moved from its
frame), ``"estimate"`` (the robust estimate over every range), a ``truth.json`` path of ``simulate
logs``, or ``{beacon: (E, N, U)}`` in the frame of the origin used."""


def _resolve_truth(truth: LogTruth, origin: EnuOrigin) -> tuple[dict[int, list[float]] | None, str]:
    if isinstance(truth, BeaconTruth):
        enu = truth.enu_in(origin)
        return {b: list(map(float, v)) for b, v in enu.items()}, f"file {Path(truth.path or 'truth').name}"
    if isinstance(truth, Mapping):
        return {int(b): list(map(float, v)) for b, v in truth.items()}, "given"
    if str(truth).lower() == "journal":
        moved = journal_frame_to(origin, LOG_BEACONS_ENU_M)
        return {b + 1: list(map(float, v)) for b, v in enumerate(moved)}, "journal"
    if str(truth).lower() == "estimate":
        return None, "estimate"
    raise ConfigError(f"truth {truth!r}: expected journal, estimate, a truth file or positions per beacon")


def replay_log_files(
    gps: str | Path,
    ranges: str | Path,
    *,
    truth: LogTruth = "journal",
    origin: EnuOrigin | None = None,
    tables: Sequence[str] = ("VII", "IX"),
    runs: int = PAPER_RUNS,
    seed: int = 2019,
    planners: Sequence[str] = DEFAULT_PLANNERS,
    epochs: int = 50,
    speed_mps: float = 3.0,
    reach_m: float = 10.0,
    max_yaw_rate_deg_s: float = 30.0,
    prior_sigma_enu_m: Sequence[float] = (100.0, 100.0, 2.0),
    sigma_range_m: float = 1.006,
    sound_speed_mps: float = 1500.0,
    max_gap_s: float = 2.0,
    executor: Executor | None = None,
    progress: Callable[[int], None] | None = None,
) -> LogsReplay:
    """Tables VII and IX on a GPS + USBL log pair (:func:`replay_logs`).

    ENU from ``origin``, else the earliest fix (as every command on logs); the journal's start point
    ``p_V(1)`` and, for ``truth="journal"``, its beacons are moved from the journal's frame to that one.
    """
    if sigma_range_m <= 0 or speed_mps <= 0 or reach_m <= 0:
        raise ConfigError("--sigma-range, --speed and --reach must be positive")
    if isinstance(truth, str | Path) and str(truth).lower() not in ("journal", "estimate"):
        truth = read_truth(truth)  # a bad truth file fails before the work
    logs = read_log_pair(gps, ranges, origin=origin, sound_speed_mps=sound_speed_mps, max_gap_s=max_gap_s)
    truth_enu, source = _resolve_truth(truth, logs.origin)
    settings = log_replay_settings(
        epochs=epochs, start_enu_m=tuple(journal_frame_to(logs.origin, LOG_START_ENU_M)[0]),
        speed_mps=speed_mps, reach_m=reach_m, max_yaw_rate_deg_s=max_yaw_rate_deg_s,
        prior_sigma_enu_m=prior_sigma_enu_m,
    )  # fmt: skip
    result = replay_logs(
        logs.aligned, truth_enu_m=truth_enu, tables=tables, runs=runs, seed=seed, planners=planners,
        settings=settings, sigma_range_m=sigma_range_m, executor=executor, progress=progress,
    )  # fmt: skip
    inputs = (*logs.inputs, *([truth.path] if isinstance(truth, BeaconTruth) and truth.path else []))
    return dataclasses.replace(
        result, truth_source=source, logs=logs, runs=runs, seed=seed, planners=tuple(planners), inputs=inputs
    )
