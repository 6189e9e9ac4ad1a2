"""Replay of closed-loop surveys on recorded measurements, vectorized across Monte Carlo runs.

Garcia et al. (2019), Section VI, and PLANS 2018, Section V-C: instead of simulating a range at the
planned site, the planner chooses which *recorded* measurement to use next. At epoch ``n`` it plans a
point ``x*`` from the current estimate; the measurement used is the recorded one nearest to it,

    x_bar = argmin_{x in P_V} ||x - x*||                                       (PLANS eq. 31)

and its recorded range (or two-way travel time) enters the MAP problem; the vehicle's position becomes
that record's position. The epoch convention, warm-started :func:`solve_map`, planners and per-run
generators are those of :mod:`oceanloc.sim.survey`; the same seed draws the same prior means there and
here (prior first, then the planner's draws per epoch), so a replay and a simulation of the same
scenario share their prior draws.

Readings (the papers do not spell these out):

* **Eq. (31), restricted.** ``P_V`` is the set of records not yet used (a ping is used at most once)
  within the reach ``d_max`` (10 m, PLANS Section V-C) of the vehicle's current position; when every
  record within reach is used, the nearest unused record anywhere. Distances are horizontal: the
  planners plan surface points at the vehicle's current height, and recorded heights vary with waves
  and GNSS error, which is not a decision. Ties go to the earliest record.
* **Heading.** A yaw-rate planner's heading becomes the heading it planned (the snap moves the position,
  not the commanded heading); point planners head along the move, as in simulation.
* **"recorded"** is the log's own order: from the start record, the next records in time (wrapping to
  the first record after the last).
* **Start.** ``p_V(1)`` is the record nearest the requested start (the first record by default);
  ``phi(1)`` is the requested heading (by default the recorded track's heading at the start).
* **Planners' noise.** The planners take one range sigma: the median of the records' sigmas (one-way
  equivalent, i.e. half the path sigma for two-way records, whose Jacobian is about twice a range's).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from oceanloc._random import run_generators, standard_normal
from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.consistency import nees
from oceanloc.estimation.map_gauss_newton import (
    GaussianPrior,
    MapOptions,
    RangeProblem,
    WhitenedModel,
    solve_map,
)
from oceanloc.models.measurements import two_way_range_jacobian, two_way_range_m
from oceanloc.planning.information import log_det_information
from oceanloc.planning.measurement_sites import MeasurementSitePlanner, PlanningState
from oceanloc.planning.site_planners import (
    PlannerSettings,
    make_site_planner,
    parse_site_planner,
    site_planner_label,
    site_planner_name,
)
from oceanloc.units import DEG

RECORDED = "recorded"
"""The planner name of the log's own order."""
DEFAULT_PLANNERS: tuple[str, ...] = (RECORDED, "k0", "k1", "k2", "k3", "greedy", "random-disk")
"""Every planner a replay compares by default: the log's order, the journal's random yaw (k = 0) and
look-ahead (k = 1..3) planners, PLANS' greedy planner within ``d_max`` and the thesis' random disk."""


@dataclass(frozen=True, slots=True, kw_only=True)
class RecordSet:
    """Recorded measurements a replay chooses from: ``P`` records, each measuring ``M`` transponders.

    A record is one ping (GNSS-A) or one group of near-simultaneous ranges to every beacon (USBL), in
    time order. One-way records measure ``|p_m - a_pm|``; two-way records (``receive_enu_m`` given, one
    transponder) measure the path ``|p - a_p| + |p - b_p|`` (:func:`oceanloc.models.measurements.
    two_way_range_m`), i.e. ``c TWTT``.

    Attributes
    ----------
    name : str
        Label for tables (a file stem, "beacon 1", ...).
    location_enu_m : (P, 3) float
        Where the vehicle was: the points eq. (31) snaps to, metres.
    time_s : (P,) float
        Record times (increasing), seconds.
    transmit_enu_m : (P, M, 3) float
        Sensor position of each measurement (transmit position for two-way records), metres.
    receive_enu_m : (P, 1, 3) float or None
        Receive positions of two-way records; ``None`` for one-way ranges.
    value_m : (P, M) float
        Measured one-way range, or two-way path ``c TWTT``, metres.
    sigma_m : (P, M) float
        Standard deviation of ``value_m``, metres.
    reference_enu_m : (M, 3) float
        The positions errors are measured against (truth, or a reference solution), metres.
    surface_z_m : float
        Height of the sea surface; estimates are kept below it (:class:`MapOptions`).
    """

    name: str
    location_enu_m: FloatArray
    time_s: FloatArray
    transmit_enu_m: FloatArray
    receive_enu_m: FloatArray | None
    value_m: FloatArray
    sigma_m: FloatArray
    reference_enu_m: FloatArray
    surface_z_m: float

    def __post_init__(self) -> None:
        p, m = self.value_m.shape if self.value_m.ndim == 2 else (0, 0)
        if p == 0 or m == 0:
            raise DataError(f"{self.name}: no recorded measurement to replay")
        shapes = {
            "location_enu_m": (self.location_enu_m.shape, (p, 3)),
            "time_s": (self.time_s.shape, (p,)),
            "transmit_enu_m": (self.transmit_enu_m.shape, (p, m, 3)),
            "sigma_m": (self.sigma_m.shape, (p, m)),
            "reference_enu_m": (self.reference_enu_m.shape, (m, 3)),
        }
        if self.receive_enu_m is not None:
            shapes["receive_enu_m"] = (self.receive_enu_m.shape, (p, 1, 3))
            if m != 1:
                raise ConfigError(f"{self.name}: two-way records measure one transponder, got {m}")
        for name, (got, want) in shapes.items():
            if got != want:
                raise ConfigError(f"{self.name}: {name} has shape {got}, expected {want}")
        if not np.all(self.sigma_m > 0.0):
            raise DataError(f"{self.name}: measurement sigmas must be positive")

    @property
    def n_records(self) -> int:
        return int(self.value_m.shape[0])

    @property
    def n_transponders(self) -> int:
        return int(self.value_m.shape[1])

    @property
    def two_way(self) -> bool:
        return self.receive_enu_m is not None

    @property
    def sigma_planning_m(self) -> float:
        """The one range sigma the planners use: the median sigma, halved for two-way paths."""
        return float(np.median(self.sigma_m)) * (0.5 if self.two_way else 1.0)

    def nearest(self, point_enu_m: ArrayLike) -> int:
        """Index of the record horizontally nearest ``point_enu_m`` (eq. 31 over all records)."""
        p = np.asarray(point_enu_m, dtype=float)
        d = np.hypot(self.location_enu_m[:, 0] - p[0], self.location_enu_m[:, 1] - p[1])
        return int(np.argmin(d))

    def map_problem(self, chosen: IntArray) -> WhitenedModel:
        """The MAP problems of ``R`` runs that have used the records ``chosen`` ``(R, n)``.

        Returns ``R * M`` problems (run-major, transponder-minor), as :func:`solve_map` takes them.
        """
        runs, n = chosen.shape
        if self.receive_enu_m is None:
            m = self.n_transponders
            sensors = np.moveaxis(self.transmit_enu_m[chosen], 2, 1).reshape(runs * m, n, 3)
            z = np.moveaxis(self.value_m[chosen], 2, 1).reshape(runs * m, n)
            sigma = np.moveaxis(self.sigma_m[chosen], 2, 1).reshape(runs * m, n)
            return RangeProblem.build(sensors, z, sigma)
        return TwoWayProblem(
            transmit_m=self.transmit_enu_m[chosen, 0],
            receive_m=self.receive_enu_m[chosen, 0],
            path_m=self.value_m[chosen, 0],
            sigma_m=self.sigma_m[chosen, 0],
        )


@dataclass(frozen=True, slots=True)
class TwoWayProblem:
    """Two-way paths ``c TWTT = |p - a| + |p - b|`` to one unknown position per problem (a
    :class:`~oceanloc.estimation.map_gauss_newton.WhitenedModel` for :func:`solve_map`).

    :class:`oceanloc.estimation.gnssa.GnssaProblem` holds one set of pings for the whole batch (and the
    sound speed as unknowns); a replay's runs each use their own pings, so here every problem carries
    its own, as :class:`RangeProblem` does. The model is :func:`two_way_range_m` and its Jacobian.

    Attributes
    ----------
    transmit_m, receive_m : (B, n, 3) float
        Transducer positions at transmit and receive, metres.
    path_m : (B, n) float
        Measured two-way paths, metres.
    sigma_m : (B, n) float
        Their standard deviations, metres.
    """

    transmit_m: FloatArray
    receive_m: FloatArray
    path_m: FloatArray
    sigma_m: FloatArray

    @property
    def batch_size(self) -> int:
        return int(self.path_m.shape[0])

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        target = x[:, None, :]
        tx, rx = self.transmit_m[rows], self.receive_m[rows]
        weight = 1.0 / self.sigma_m[rows]
        resid = (self.path_m[rows] - two_way_range_m(target, tx, rx)) * weight
        return resid, two_way_range_jacobian(target, tx, rx) * weight[..., None]


@dataclass(frozen=True, slots=True, kw_only=True)
class ReplaySettings:
    """Vehicle, reach, prior and estimator settings of a replay (defaults: journal Tables VI and VIII).

    Attributes
    ----------
    epochs : int
        Measurement epochs ``N`` (50); at most the number of records.
    start_enu_m : (3,) float or None
        Requested ``p_V(1)``; the nearest record is used. ``None``: the first record.
    start_yaw_rad : float or None
        ``phi(1)``; ``None``: the heading from the start record to the next one.
    speed_mps, period_s, max_yaw_rate_rad_s : float
        Unicycle of the yaw-rate planners (3 m/s, 1 s, 30 deg/s).
    reach_m : float
        ``d_max`` (10 m): the greedy and random-disk planners' reach and the reach of eq. (31).
    prior_cov_m2 : (3, 3) float
        ``0P_T``; each run draws its prior mean from ``N(reference, 0P_T)`` per transponder. The
        experiment's tables do not list it; the default is the simulations' ``diag(1e4, 1e4, 4)``.
    estimator : MapOptions or None
        Stopping rules; ``None``: ``delta_min`` 1e-6 m, ``J_max`` 200 and the records' surface.
    """

    epochs: int = 50
    start_enu_m: FloatArray | None = None
    start_yaw_rad: float | None = None
    speed_mps: float = 3.0
    period_s: float = 1.0
    max_yaw_rate_rad_s: float = 30.0 * DEG
    reach_m: float = 10.0
    prior_cov_m2: FloatArray = field(default_factory=lambda: np.diag([1e4, 1e4, 4.0]))
    estimator: MapOptions | None = None

    def __post_init__(self) -> None:
        if self.epochs < 1:
            raise ConfigError(f"epochs must be at least 1, got {self.epochs}")
        for name in ("speed_mps", "period_s", "max_yaw_rate_rad_s", "reach_m"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"{name} must be positive, got {getattr(self, name)}")
        cov = np.asarray(self.prior_cov_m2, dtype=float)
        if cov.shape != (3, 3) or not np.all(np.linalg.eigvalsh(0.5 * (cov + cov.T)) > 0):
            raise ConfigError("prior_cov_m2 must be a 3x3 positive-definite matrix")


def planner_settings(name: str, reach_m: float) -> PlannerSettings | None:
    """The :class:`PlannerSettings` a replay planner name stands for (``None`` for ``recorded``, the log's
    own order, which is not a planner).

    Every other name goes through :func:`oceanloc.planning.site_planners.parse_site_planner` (``k0``,
    ``k1`` .. ``k10``, ``greedy``, ``random-disk``, ...), with ``d_max = reach_m`` for the point planners.
    """
    if name.strip().lower() == RECORDED:
        return None
    return parse_site_planner(name, max_distance_m=reach_m)


def planner_name(text: str) -> str:
    """The canonical name of a replay planner: ``recorded`` or :func:`site_planner_name` (``k0``, ``k2``,
    ``greedy``, ``random-disk``); raises a ConfigError naming the accepted names."""
    settings = planner_settings(text, 1.0)
    return RECORDED if settings is None else site_planner_name(settings)


def planner_label(name: str) -> str:
    """Label of a replay planner in tables and figures (:func:`site_planner_label`, or ``recorded
    order``)."""
    settings = planner_settings(name, 1.0)
    return "recorded order" if settings is None else site_planner_label(settings)


def snap_to_records(
    planned_enu_m: ArrayLike,
    locations_enu_m: ArrayLike,
    current_enu_m: ArrayLike,
    used: ArrayLike,
    reach_m: float,
) -> IntArray:
    """Eq. (31): the unused record nearest each planned point, among those within reach.

    Parameters
    ----------
    planned_enu_m : (R, 3) float
        Planned points ``x*``, metres.
    locations_enu_m : (P, 3) float
        Record locations, metres.
    current_enu_m : (R, 3) float
        Vehicle positions; a record is within reach if it lies within ``reach_m`` of it (horizontally).
    used : (R, P) bool
        Records each run has already used.
    reach_m : float
        ``d_max``, metres.

    Returns
    -------
    (R,) int
        ``argmin ||x - x*||`` (horizontal) over the unused records within reach, or over every unused
        record where none is within reach; the earliest record on ties.

    Raises
    ------
    ConfigError
        If some run has used every record.
    """
    x = np.asarray(planned_enu_m, dtype=float)
    loc = np.asarray(locations_enu_m, dtype=float)
    here = np.asarray(current_enu_m, dtype=float)
    free = ~np.asarray(used, dtype=bool)
    if not np.all(free.any(axis=1)):
        raise ConfigError(f"every one of the {loc.shape[0]} records is used: ask for fewer epochs")
    d_plan = np.hypot(loc[None, :, 0] - x[:, None, 0], loc[None, :, 1] - x[:, None, 1])
    d_here = np.hypot(loc[None, :, 0] - here[:, None, 0], loc[None, :, 1] - here[:, None, 1])
    in_reach = free & (d_here <= reach_m)
    allowed = np.where(in_reach.any(axis=1, keepdims=True), in_reach, free)
    return np.argmin(np.where(allowed, d_plan, np.inf), axis=1)


@dataclass(frozen=True, slots=True, kw_only=True)
class ReplayRuns:
    """Per-run histories of one planner's replays (``R`` runs, ``N`` epochs, ``M`` transponders).

    Attributes
    ----------
    planner : str
        Replay planner name (:data:`DEFAULT_PLANNERS`).
    run_indices : (R,) int
        Global run indices (their seeds).
    reference_enu_m : (M, 3) float
        The positions errors are measured against.
    prior_mean_m : (R, M, 3) float
        Each run's prior mean.
    chosen : (R, N) int
        Record used at each epoch.
    sites_enu_m : (R, N, 3) float
        Their locations (the vehicle's positions).
    snap_distance_m : (R, N - 1) float
        Horizontal distance from each planned point ``x*`` to the record used (0 for ``recorded``).
    estimates_m : (R, N, M, 3) float
        MAP estimates after each epoch.
    log_det : (R, N) float
        ``log det Y_n`` over all transponders (block diagonal, eq. 32, prior included), nats.
    nees : (R, N) float
        Eq. (44) against the reference.
    converged : (R, N, M) bool
    plan_time_s : (R, N - 1) float
        Planning wall time per run (batched time over the batch size), seconds.
    """

    planner: str
    run_indices: IntArray
    reference_enu_m: FloatArray
    prior_mean_m: FloatArray
    chosen: IntArray
    sites_enu_m: FloatArray
    snap_distance_m: FloatArray
    estimates_m: FloatArray
    log_det: FloatArray
    nees: FloatArray
    converged: BoolArray
    plan_time_s: FloatArray

    @property
    def errors_m(self) -> FloatArray:
        """``reference - estimate`` (eq. 42), ``(R, N, M, 3)``."""
        return self.reference_enu_m - self.estimates_m

    @property
    def runs(self) -> int:
        return int(self.run_indices.size)


def replay_surveys(
    records: RecordSet, settings: ReplaySettings, planner: str, run_indices: ArrayLike, seed: int
) -> ReplayRuns:
    """Replay the runs ``run_indices`` of one planner on recorded measurements, as one batch.

    Parameters
    ----------
    records : RecordSet
    settings : ReplaySettings
    planner : str
        A name :func:`planner_settings` knows.
    run_indices : (R,) int
        Global run indices; run ``r`` uses the generator seeded by ``(seed, r)``.
    seed : int

    Raises
    ------
    ConfigError
        If more epochs are asked for than there are records, or the planner is unknown.
    """
    runs = np.asarray(run_indices, dtype=np.int64).ravel()
    n_runs, n_epochs, m, n_rec = runs.size, settings.epochs, records.n_transponders, records.n_records
    check_epochs(records, settings)
    site_planner = _build(planner, settings, records)
    rngs = run_generators(seed, runs)
    options = settings.estimator or MapOptions(surface_z_m=records.surface_z_m)
    chol0 = np.linalg.cholesky(settings.prior_cov_m2)
    prior_mean = records.reference_enu_m + standard_normal(rngs, n_runs, (m, 3)) @ chol0.T
    prior = GaussianPrior(mean=prior_mean.reshape(-1, 3), cov=settings.prior_cov_m2)

    start = 0 if settings.start_enu_m is None else records.nearest(settings.start_enu_m)
    chosen = np.empty((n_runs, n_epochs), dtype=np.int64)
    chosen[:, 0] = start
    used = np.zeros((n_runs, n_rec), dtype=bool)
    used[:, start] = True
    estimates = np.empty((n_runs, n_epochs, m, 3))
    log_det = np.empty((n_runs, n_epochs))
    nees_n = np.empty((n_runs, n_epochs))
    converged = np.empty((n_runs, n_epochs, m), dtype=bool)
    snap = np.zeros((n_runs, max(n_epochs - 1, 0)))
    plan_time = np.zeros((n_runs, max(n_epochs - 1, 0)))

    pos = np.broadcast_to(records.location_enu_m[start], (n_runs, 3)).copy()
    yaw = np.full(n_runs, _start_yaw(records, start, settings.start_yaw_rad))
    estimate = prior.mean
    rows = np.arange(n_runs)
    for n in range(n_epochs):
        result = solve_map(records.map_problem(chosen[:, : n + 1]), prior, options, initial=estimate)
        estimate = result.estimate
        estimates[:, n] = estimate.reshape(n_runs, m, 3)
        info = result.information.reshape(n_runs, m, 3, 3)
        log_det[:, n] = log_det_information(info).sum(axis=-1)
        nees_n[:, n] = nees(records.reference_enu_m - estimates[:, n], info)
        converged[:, n] = result.converged.reshape(n_runs, m)
        if n == n_epochs - 1:
            break
        if site_planner is None:
            nxt = (chosen[:, n] + 1) % n_rec
        else:
            state = PlanningState(
                pos_enu_m=pos,
                yaw_rad=yaw,
                estimates_m=estimates[:, n],
                covariances_m2=result.covariance.reshape(n_runs, m, 3, 3),
            )
            tic = time.perf_counter()
            plan = site_planner.plan(state, rngs)
            nxt = snap_to_records(plan.next_pos_enu_m, records.location_enu_m, pos, used, settings.reach_m)
            plan_time[:, n] = (time.perf_counter() - tic) / n_runs
            snap[:, n] = _horizontal(records.location_enu_m[nxt] - plan.next_pos_enu_m)
            yaw = plan.next_yaw_rad if plan.yaw_rates_rad_s is not None else _heading(pos, nxt, records, yaw)
        chosen[:, n + 1] = nxt
        used[rows, nxt] = True
        pos = records.location_enu_m[nxt].copy()

    return ReplayRuns(
        planner=planner,
        run_indices=runs,
        reference_enu_m=records.reference_enu_m,
        prior_mean_m=prior_mean,
        chosen=chosen,
        sites_enu_m=records.location_enu_m[chosen],
        snap_distance_m=snap,
        estimates_m=estimates,
        log_det=log_det,
        nees=nees_n,
        converged=converged,
        plan_time_s=plan_time,
    )


def check_epochs(records: RecordSet, settings: ReplaySettings) -> None:
    """Raise a :class:`ConfigError` naming the records if a replay asks for more epochs than records."""
    if settings.epochs > records.n_records:
        raise ConfigError(
            f"{records.name}: {settings.epochs} epochs asked for, but only {records.n_records} recorded "
            "measurements to use"
        )


def _build(planner: str, settings: ReplaySettings, records: RecordSet) -> MeasurementSitePlanner | None:
    spec = planner_settings(planner, settings.reach_m)
    if spec is None:
        return None
    return make_site_planner(
        spec,
        max_yaw_rate_rad_s=settings.max_yaw_rate_rad_s,
        speed_mps=settings.speed_mps,
        period_s=settings.period_s,
        sigma_range_m=records.sigma_planning_m,
    )


def _start_yaw(records: RecordSet, start: int, requested: float | None) -> float:
    if requested is not None:
        return float(requested)
    if records.n_records < 2:
        return 0.0
    a = records.location_enu_m[start]
    b = records.location_enu_m[(start + 1) % records.n_records]
    return float(np.arctan2(b[1] - a[1], b[0] - a[0]))


def _horizontal(d: FloatArray) -> FloatArray:
    return np.hypot(d[..., 0], d[..., 1])


def _heading(pos: FloatArray, nxt: IntArray, records: RecordSet, yaw: FloatArray) -> FloatArray:
    """Heading of the move to the chosen records; unchanged where the vehicle stays put."""
    step = records.location_enu_m[nxt] - pos
    moved = _horizontal(step) > 1e-9
    return np.where(moved, np.arctan2(step[:, 1], step[:, 0]), yaw)
