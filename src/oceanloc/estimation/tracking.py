"""Track a target from a flock of sensor nodes: the sensor model and a filter runner over a sequence.

A :class:`FlockSensorModel` bundles what the filters need to know about the measurements (bearing, range or
TDOA, the noise covariance ``R``, the TDOA pairs and sound speed); :func:`run_filter` steps a KF, EKF or
UKF over ``T`` epochs for ``B`` tracks at once and returns a :class:`TrackResult` with the estimates,
covariances, innovations, NIS and HDOP at every epoch.

Epoch convention (thesis Figure 18): the initial Gaussian is at ``t_0``; epoch ``k = 1 .. T`` predicts one
step ``dt`` and then updates with the measurements ``z_k`` taken at ``t_k = t_0 + k dt``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Literal, TypeAlias

import numpy as np

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
        return dataclasses.replace(upd, repaired=upd.repaired | pred.repaired)
    prior = predict(state, motion)
    if kind == "ekf":
        return ekf_update(
            prior,
            z,
            lambda x: sensor_model.measure(x, sensors_m),
            lambda x: sensor_model.jacobian(x, sensors_m),
            sensor_model.noise_cov,
            angle_mask=sensor_model.angle_mask,
        )
    if kind == "kf":
        # A linear measurement model given as the Jacobian at the prediction (exact when h is linear).
        return kf_update(prior, z, sensor_model.jacobian(prior.mean, sensors_m), sensor_model.noise_cov)
    raise ConfigError(f"filter must be one of {', '.join(FILTER_KINDS)}; got {kind!r}")


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
    """
    z = np.asarray(measurements, dtype=float)
    sens = np.asarray(sensors_m, dtype=float)
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
    n, m = initial.dim, sensor_model.dim
    est = np.empty((b, t_count, n))
    covs = np.empty((b, t_count, n, n)) if record_covariances else None
    innov = np.empty((b, t_count, m))
    nis = np.empty((b, t_count))
    dof = np.empty((b, t_count), dtype=np.int64)
    rep = np.empty((b, t_count), dtype=bool)
    state = initial
    for k in range(t_count):
        sk = sens[k] if shared else sens[:, k]
        res = filter_step(kind, state, motion, sensor_model, z[:, k], sk, params)
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
    )
