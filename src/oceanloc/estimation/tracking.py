"""Track a target from a flock of sensor nodes: the sensor model and a filter runner over a sequence.

A :class:`FlockSensorModel` bundles what the filters need to know about the measurements (bearing, range or
TDOA, the noise covariance ``R``, the TDOA pairs and sound speed); :func:`run_filter` steps a KF, EKF or
UKF over ``T`` epochs for ``B`` tracks at once and returns a :class:`TrackResult` with the estimates,
covariances, innovations, NIS and HDOP at every epoch.

Innovation gating and divergence detection (not in the thesis; needed where ``h`` is strongly nonlinear,
e.g. a target passing within a few metres of a TDOA node): an epoch whose NIS exceeds the chi-square
quantile ``chi2_dof^-1(gate_probability)`` is not used (the track keeps its prediction, so its covariance
grows by ``Q`` until the measurements fit again), Bar-Shalom, Li & Kirubarajan (2001), Sec. 5.4.2. A gate
alone can lock a track out for good (a wrong prediction rejects the right measurements and coasts away), so
the epoch that completes ``divergence_epochs`` consecutive epochs outside the gate flags the track as
*diverged* (at the first epoch of that streak) and opens its gate (that epoch's and the following
measurements are used again, re-acquiring the target) until an epoch falls inside the gate. A consistent
filter starts such a streak with probability ``(1 - gate_probability)^divergence_epochs`` per epoch
(``1e-60`` for the defaults), i.e. never.

Epoch convention (thesis Figure 18): the initial Gaussian is at ``t_0``; epoch ``k = 1 .. T`` predicts one
step ``dt`` and then updates with the measurements ``z_k`` taken at ``t_k = t_0 + k dt``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Literal, TypeAlias

import numpy as np

from oceanloc import _validate
from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.estimation.bounds import hdop_from_jacobian
from oceanloc.estimation.gaussian import Gaussian
from oceanloc.estimation.kalman import UpdateResult, ekf_update, kf_update, predict
from oceanloc.estimation.unscented import SigmaPointParams, ukf_predict, ukf_update
from oceanloc.models.measurements import (
    MEASUREMENT_KINDS,
    MeasurementKind,
    bearing_jacobian,
    bearing_rad,
    horizontal_range_jacobian,
    horizontal_range_m,
    sensor_pairs,
    tdoa_jacobian,
    tdoa_s,
)
from oceanloc.models.motion import LinearMotionModel

FilterKind: TypeAlias = Literal["kf", "ekf", "ukf"]
FILTER_KINDS: tuple[str, ...] = ("kf", "ekf", "ukf")
DEFAULT_GATE_PROBABILITY = 0.999
"""Chi-square probability of the NIS gate: a consistent filter loses 0.1 % of its epochs."""
DEFAULT_DIVERGENCE_EPOCHS = 20
"""Consecutive epochs beyond the gate that flag a track as diverged."""


@dataclass(frozen=True, slots=True, kw_only=True)
class FlockSensorModel:
    """Measurements of a target by ``N`` nodes: one bearing or range per node, or TDOA per node pair.

    Attributes
    ----------
    kind : {"bearing", "range", "tdoa"}
        Eqs. (II.3), (II.4), (II.7).
    n_sensors : int
        Number of nodes ``N``.
    noise_cov : (m, m) float
        ``R``: rad^2, m^2 or s^2.
    pairs : (P, 2) int or None
        TDOA pairs ``(i, j)``, ``tau_ij = tau_i - tau_j`` (``None`` for bearing and range).
    sound_speed_mps : float
        ``c`` for TDOA.
    """

    kind: MeasurementKind
    n_sensors: int
    noise_cov: FloatArray
    pairs: IntArray | None = None
    sound_speed_mps: float = 1500.0

    def __post_init__(self) -> None:
        if self.kind not in MEASUREMENT_KINDS:
            raise ConfigError(
                f"measurement kind must be one of {', '.join(MEASUREMENT_KINDS)}; got {self.kind}"
            )
        if self.kind == "tdoa" and self.pairs is None:
            object.__setattr__(self, "pairs", sensor_pairs(self.n_sensors))
        r = np.asarray(self.noise_cov, dtype=float)
        if r.shape != (self.dim, self.dim):
            raise ConfigError(f"{self.kind} noise covariance must be ({self.dim}, {self.dim}), got {r.shape}")
        if not np.all(np.linalg.eigvalsh(0.5 * (r + r.T)) > 0):
            raise ConfigError(f"{self.kind} noise covariance must be positive definite")
        object.__setattr__(self, "noise_cov", r)

    @classmethod
    def build(
        cls,
        kind: MeasurementKind,
        n_sensors: int,
        sigma: float,
        *,
        pairs: ArrayLike | str = "all",
        sound_speed_mps: float = 1500.0,
    ) -> FlockSensorModel:
        """Independent measurements with standard deviation ``sigma`` (rad, m or s)."""
        if not sigma > 0:
            raise ConfigError(f"measurement sigma must be positive, got {sigma}")
        p = None
        if kind == "tdoa":
            p = (
                sensor_pairs(n_sensors, pairs)
                if isinstance(pairs, str)
                else np.asarray(pairs, dtype=np.int64)
            )
        m = n_sensors if p is None else p.shape[0]
        return cls(
            kind=kind,
            n_sensors=n_sensors,
            noise_cov=sigma**2 * np.eye(m),
            pairs=p,
            sound_speed_mps=sound_speed_mps,
        )

    @property
    def dim(self) -> int:
        """Number of measurements ``m`` per epoch."""
        return self.n_sensors if self.pairs is None else int(self.pairs.shape[0])

    @property
    def angle_mask(self) -> BoolArray | None:
        """Which measurement components are angles (all for bearings)."""
        return np.ones(self.dim, dtype=bool) if self.kind == "bearing" else None

    @property
    def sigmas(self) -> FloatArray:
        """Standard deviations ``sqrt(diag R)``, ``(m,)``."""
        return np.sqrt(np.diag(self.noise_cov))

    def measure(self, states: ArrayLike, sensors_m: ArrayLike) -> FloatArray:
        """Noise-free ``h(x)``: ``states (..., n)``, ``sensors_m (..., N, 2)`` -> ``(..., m)``."""
        if self.kind == "bearing":
            return bearing_rad(states, sensors_m)
        if self.kind == "range":
            return horizontal_range_m(states, sensors_m)
        assert self.pairs is not None
        return tdoa_s(states, sensors_m, self.pairs, self.sound_speed_mps)

    def jacobian(self, states: ArrayLike, sensors_m: ArrayLike) -> FloatArray:
        """Analytic ``dh/dx``: ``(..., m, n)``."""
        if self.kind == "bearing":
            return bearing_jacobian(states, sensors_m)
        if self.kind == "range":
            return horizontal_range_jacobian(states, sensors_m)
        assert self.pairs is not None
        return tdoa_jacobian(states, sensors_m, self.pairs, self.sound_speed_mps)

    def hdop(
        self, positions_m: ArrayLike, sensors_m: ArrayLike, avail: ArrayLike | None = None
    ) -> FloatArray:
        """HDOP (eq. IV.9) with this model's sigmas, metres; missing measurements excluded.

        Parameters
        ----------
        positions_m : (..., >=2) float
            Target positions (or states).
        sensors_m : (..., N, 2) float
        avail : (..., m) bool, optional
        """
        jac = self.jacobian(np.asarray(positions_m, dtype=float)[..., :2], sensors_m)
        sig = self.sigmas if avail is None else np.where(avail, self.sigmas, np.inf)
        return hdop_from_jacobian(jac, sig)


@dataclass(frozen=True, slots=True, kw_only=True)
class TrackResult:
    """A filter run over ``T`` epochs for ``B`` tracks.

    Attributes
    ----------
    filter : str
        ``kf``, ``ekf`` or ``ukf``.
    estimates : (B, T, n) float
        Posterior means at epochs ``1 .. T``.
    covariances : (B, T, n, n) float or None
        Posterior covariances (``None`` when not recorded).
    innovations : (B, T, m) float
        Measurement residuals against the prediction (wrapped for bearings; zero where missing).
    nis : (B, T) float
        Normalized innovation squared.
    nis_dof : (B, T) int
        Measurements used at each epoch (the NIS degrees of freedom).
    hdop_m : (B, T) float
        HDOP at the posterior estimate with the model's sigmas, metres.
    repaired : (B, T) bool
        A covariance needed an eigenvalue repair (UKF).
    final : Gaussian
        Posterior after the last epoch, to continue the run.
    gated : (B, T) bool
        The epoch's measurements were rejected by the NIS gate (the estimate is the prediction).
    outside_gate : (B, T) bool
        The NIS exceeded the gate's chi-square quantile (equals ``gated`` when gating is on).
    diverged_epoch : (B,) int
        Index (0-based, into ``1 .. T``) of the first epoch of the first run of ``divergence_epochs``
        consecutive epochs outside the gate; ``-1`` for a track that did not diverge.
    streak : (B,) int
        Consecutive epochs outside the gate at the end of the run (to continue it with ``initial_streak``).
    gate_probability : float or None
        The gate's chi-square probability (``None``: gating off; the 0.999 quantile still flags divergence).
    divergence_epochs : int
    """

    filter: str
    estimates: FloatArray
    covariances: FloatArray | None
    innovations: FloatArray
    nis: FloatArray
    nis_dof: IntArray
    hdop_m: FloatArray
    repaired: BoolArray
    final: Gaussian
    gated: BoolArray
    outside_gate: BoolArray
    diverged_epoch: IntArray
    gate_probability: float | None
    divergence_epochs: int
    streak: IntArray

    @property
    def diverged(self) -> BoolArray:
        """``(B,)`` bool: the track diverged (see ``diverged_epoch``)."""
        return self.diverged_epoch >= 0

    @property
    def gated_count(self) -> IntArray:
        """``(B,)`` int: epochs whose measurements the gate rejected."""
        return self.gated.sum(axis=-1)


def nis_gate(probability: float, max_dof: int) -> FloatArray:
    """Chi-square quantiles ``chi2_d^-1(probability)`` for ``d = 0 .. max_dof`` (``inf`` at ``d = 0``)."""
    if not 0.0 < probability < 1.0:
        raise ConfigError(f"gate probability must be in (0, 1), got {probability}")
    from scipy.stats import chi2

    return np.concatenate([[np.inf], chi2.ppf(probability, np.arange(1, max_dof + 1))])


def filter_step(
    kind: FilterKind,
    state: Gaussian,
    motion: LinearMotionModel,
    sensor_model: FlockSensorModel,
    z: FloatArray,
    sensors_m: FloatArray,
    params: SigmaPointParams,
) -> UpdateResult:
    """One predict + update epoch of the chosen filter for ``B`` tracks.

    Parameters
    ----------
    z : (B, m) float
        Measurements, ``NaN`` where missing.
    sensors_m : (B, N, 2) or (N, 2) float
        Node positions at this epoch.
    """
    return predict_update(kind, state, motion, sensor_model, z, sensors_m, params)[1]


def predict_update(
    kind: FilterKind,
    state: Gaussian,
    motion: LinearMotionModel,
    sensor_model: FlockSensorModel,
    z: FloatArray,
    sensors_m: FloatArray,
    params: SigmaPointParams,
) -> tuple[Gaussian, UpdateResult]:
    """:func:`filter_step` that also returns the prediction (what a gated epoch keeps)."""
    if kind == "ukf":
        pred = ukf_predict(state, lambda x: x @ motion.transition.T, motion.process_noise, params)
        sens = sensors_m[:, None] if sensors_m.ndim == 3 else sensors_m
        upd = ukf_update(
            pred.state,
            z,
            lambda x: sensor_model.measure(x, sens),
            sensor_model.noise_cov,
            params,
            angle_mask=sensor_model.angle_mask,
        )
        return pred.state, dataclasses.replace(upd, repaired=upd.repaired | pred.repaired)
    prior = predict(state, motion)
    if kind == "ekf":
        return prior, ekf_update(
            prior,
            z,
            lambda x: sensor_model.measure(x, sensors_m),
            lambda x: sensor_model.jacobian(x, sensors_m),
            sensor_model.noise_cov,
            angle_mask=sensor_model.angle_mask,
        )
    if kind == "kf":
        # A linear measurement model given as the Jacobian at the prediction (exact when h is linear).
        jac = sensor_model.jacobian(prior.mean, sensors_m)
        return prior, kf_update(prior, z, jac, sensor_model.noise_cov)
    raise ConfigError(f"filter must be one of {', '.join(FILTER_KINDS)}; got {kind!r}")


def _check_initial(initial: Gaussian) -> None:
    """The initial density is finite, within the bounds of :mod:`oceanloc._validate`, and a covariance."""
    _validate.float_array("initial.mean", initial.mean, max_abs=_validate.MAX_LENGTH_M)
    _validate.covariances("initial.cov", initial.cov)


def run_filter(
    kind: FilterKind,
    initial: Gaussian,
    motion: LinearMotionModel,
    sensor_model: FlockSensorModel,
    measurements: ArrayLike,
    sensors_m: ArrayLike,
    *,
    params: SigmaPointParams | None = None,
    record_covariances: bool = True,
    gate_probability: float | None = DEFAULT_GATE_PROBABILITY,
    divergence_epochs: int = DEFAULT_DIVERGENCE_EPOCHS,
    initial_streak: ArrayLike | None = None,
) -> TrackResult:
    """Run a filter over a measurement sequence for ``B`` tracks at once.

    Parameters
    ----------
    kind : {"kf", "ekf", "ukf"}
    initial : Gaussian
        State at ``t_0``, ``B`` tracks.
    motion : LinearMotionModel
    sensor_model : FlockSensorModel
    measurements : (B, T, m) float
        ``z_k``; ``NaN`` marks a missing measurement (a node that dropped out for an epoch).
    sensors_m : (B, T, N, 2) or (T, N, 2) float
        Node positions at each epoch, shared by all tracks when 3-D.
    params : SigmaPointParams, optional
        UKF parameters (the thesis' ``alpha = 1e-3, beta = 2, kappa = 0`` by default).
    record_covariances : bool
        Keep every posterior covariance (``B T n^2`` floats).
    gate_probability : float or None
        NIS gate (module docstring); ``None`` accepts every epoch (the thesis' filters).
    divergence_epochs : int
        Consecutive epochs beyond the gate that flag a track as diverged (and open its gate).
    initial_streak : (B,) int, optional
        Epochs outside the gate carried over from a previous block of the same run (``TrackResult.streak``).
    """
    _check_initial(initial)
    z = _validate.float_array(
        "measurements", measurements, allow_nan=True, allow_empty=True, max_abs=_validate.MAX_LENGTH_M
    )
    sens = _validate.float_array("sensors_m", sensors_m, max_abs=_validate.MAX_LENGTH_M, unit="m")
    if gate_probability is not None:
        _validate.number("gate_probability", gate_probability, lo=0.0, hi=1.0, lo_open=True)
    b, t_count = initial.batch_size, z.shape[1] if z.ndim == 3 else -1
    if z.shape != (b, t_count, sensor_model.dim):
        raise ConfigError(f"measurements must be (B={b}, T, m={sensor_model.dim}); got {z.shape}")
    shared = sens.ndim == 3
    if sens.shape[-3 if shared else -4 :] != (
        *((b,) if not shared else ()),
        t_count,
        sensor_model.n_sensors,
        2,
    ):
        raise ConfigError(
            f"sensor positions must be (T={t_count}, N={sensor_model.n_sensors}, 2) or (B, T, N, 2);"
            f" got {sens.shape}"
        )
    params = params or SigmaPointParams()
    if divergence_epochs < 1:
        raise ConfigError(f"divergence_epochs must be at least 1, got {divergence_epochs}")
    n, m = initial.dim, sensor_model.dim
    gate = nis_gate(DEFAULT_GATE_PROBABILITY if gate_probability is None else gate_probability, m)
    outside = np.empty((b, t_count), dtype=bool)
    gated = np.zeros((b, t_count), dtype=bool)
    streak = np.zeros(b, np.int64) if initial_streak is None else np.array(initial_streak, dtype=np.int64)
    diverged_at = np.full(b, -1, dtype=np.int64)
    est = np.empty((b, t_count, n))
    covs = np.empty((b, t_count, n, n)) if record_covariances else None
    innov = np.empty((b, t_count, m))
    nis = np.empty((b, t_count))
    dof = np.empty((b, t_count), dtype=np.int64)
    rep = np.empty((b, t_count), dtype=bool)
    state = initial
    for k in range(t_count):
        sk = sens[k] if shared else sens[:, k]
        prior, res = predict_update(kind, state, motion, sensor_model, z[:, k], sk, params)
        out_k = res.nis > gate[res.dof]
        outside[:, k] = out_k
        streak = np.where(out_k, streak + 1, 0)
        new = (streak == divergence_epochs) & (diverged_at < 0)
        diverged_at[new] = k - divergence_epochs + 1
        keep = out_k & (streak < divergence_epochs)  # gate open after a streak: re-acquire
        gated[:, k] = keep
        if gate_probability is not None and keep.any():
            state = Gaussian(
                mean=np.where(keep[:, None], prior.mean, res.state.mean),
                cov=np.where(keep[:, None, None], prior.cov, res.state.cov),
            )
        else:
            state = res.state
        est[:, k] = state.mean
        if covs is not None:
            covs[:, k] = state.cov
        innov[:, k] = res.innovation
        nis[:, k] = res.nis
        dof[:, k] = res.dof
        rep[:, k] = res.repaired
    # HDOP at every posterior estimate in one vectorized pass.
    hd = sensor_model.hdop(est, sens, np.isfinite(z))
    return TrackResult(
        filter=kind,
        estimates=est,
        covariances=covs,
        innovations=innov,
        nis=nis,
        nis_dof=dof,
        hdop_m=hd,
        repaired=rep,
        final=state,
        gated=gated if gate_probability is not None else np.zeros_like(gated),
        outside_gate=outside,
        diverged_epoch=diverged_at,
        gate_probability=gate_probability,
        divergence_epochs=divergence_epochs,
        streak=streak,
    )
