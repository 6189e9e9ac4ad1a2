"""Monte Carlo of replays on recorded measurements (Garcia et al. 2019, Section VI) and their metrics.

:func:`replay_monte_carlo` runs :func:`oceanloc.field.replay.replay_surveys` for one planner over chunks of
runs through :func:`oceanloc.evaluation.montecarlo.run_chunked` (this process, local processes or
Dask) and summarizes them: RMSEE per epoch and transponder (eq. 45, against the record set's
reference), mean and standard deviation of ``log det Y_n``, mean NEES (eq. 44). Every run draws from its
own generator, so the same seed gives the same numbers whatever the chunking or executor; every planner
of one seed shares the prior draws (common random numbers).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.evaluation.metrics import LogDetStats, log_det_stats, rmsee
from oceanloc.evaluation.montecarlo import concat_runs, run_chunked
from oceanloc.field.replay import (
    RecordSet,
    ReplayRuns,
    ReplaySettings,
    check_epochs,
    planner_settings,
    replay_surveys,
)


@dataclass(frozen=True, slots=True, kw_only=True)
class ReplayStudy:
    """One planner's replay Monte Carlo on one record set.

    Attributes
    ----------
    records : str
        Name of the record set.
    planner : str
    seed : int
    histories : ReplayRuns
        Every run's per-epoch errors, log det, NEES and chosen records.
    rmsee_m : (N, M) float
        Eq. (45) per epoch and transponder.
    log_det : LogDetStats
        ``log det Y_n`` over runs, per epoch.
    nees_mean : (N,) float
        Mean NEES (eq. 44, ``3M`` degrees of freedom if consistent) per epoch.
    plan_time_s : float
        Mean planning time per run and epoch (batched), seconds.
    snap_distance_m : float
        Mean horizontal distance from a planned point to the record used (eq. 31), metres.
    converged_fraction : float
        Share of MAP solves that met the step-size test.
    """

    records: str
    planner: str
    seed: int
    histories: ReplayRuns
    rmsee_m: FloatArray
    log_det: LogDetStats
    nees_mean: FloatArray
    plan_time_s: float
    snap_distance_m: float
    converged_fraction: float

    @property
    def runs(self) -> int:
        return self.histories.runs

    @property
    def epochs(self) -> int:
        return int(self.rmsee_m.shape[0])


def replay_monte_carlo(
    records: RecordSet,
    settings: ReplaySettings,
    planner: str,
    runs: int,
    seed: int,
    *,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> ReplayStudy:
    """Run ``runs`` replays of one planner and summarize them (see the module docstring)."""
    check_epochs(records, settings)  # here, not in a worker
    planner_settings(planner, settings.reach_m)
    task = functools.partial(_chunk, records=records, settings=settings, planner=planner, seed=seed)
    parts = run_chunked(task, runs, executor=executor, chunk_size=chunk_size, progress=progress)
    return summarize(concat_runs(parts, keep=("planner", "reference_enu_m")), records.name, seed)


def replay_planners(
    records: RecordSet,
    settings: ReplaySettings,
    planners: Sequence[str],
    runs: int,
    seed: int,
    *,
    executor: Executor | None = None,
    chunk_size: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> dict[str, ReplayStudy]:
    """:func:`replay_monte_carlo` for every planner (same seed: same prior draws), in the given order."""
    return {
        p: replay_monte_carlo(
            records, settings, p, runs, seed, executor=executor, chunk_size=chunk_size, progress=progress
        )
        for p in planners
    }


def summarize(histories: ReplayRuns, records: str, seed: int) -> ReplayStudy:
    """Reduce per-run histories to the paper's metrics."""
    plan = histories.plan_time_s
    snap = histories.snap_distance_m
    return ReplayStudy(
        records=records,
        planner=histories.planner,
        seed=seed,
        histories=histories,
        rmsee_m=rmsee(histories.errors_m),
        log_det=log_det_stats(histories.log_det),
        nees_mean=histories.nees.mean(axis=0),
        plan_time_s=float(plan.mean()) if plan.size else 0.0,
        snap_distance_m=float(snap.mean()) if snap.size else 0.0,
        converged_fraction=float(histories.converged.mean()),
    )


def epochs_to_reach(curve: FloatArray, target: float, *, higher_is_better: bool) -> int | None:
    """First epoch ``n`` (1-based) from which ``curve`` meets ``target`` at every later epoch.

    ``None`` if it does not meet it at the last epoch. Used as the convergence speed against the
    recorded order: the epoch from which a planner's RMSEE stays at or below (its mean log det at or
    above) what the log's own order reaches at its last epoch.
    """
    x = np.asarray(curve, dtype=float)
    hit = x >= target if higher_is_better else x <= target
    if not hit.size or not hit[-1]:
        return None
    misses = np.flatnonzero(~hit)
    return int(misses[-1]) + 2 if misses.size else 1


def _chunk(
    run_indices: np.ndarray, *, records: RecordSet, settings: ReplaySettings, planner: str, seed: int
) -> ReplayRuns:
    return replay_surveys(records, settings, planner, run_indices, seed)
