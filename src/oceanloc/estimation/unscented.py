"""Unscented Kalman filter (UKF) with scaled sigma points, as pure batched predict/update steps.

AquaQuad thesis, Chapter III.D (Figure 23, after Wan and van der Merwe 2000), additive-noise form:
``2n + 1`` sigma points ``x``, ``x +- sqrt(n + lambda) L_i`` (``L L^T = P``, ``L_i`` its columns) with
``lambda = alpha^2 (n + kappa) - n`` and weights ``Wm_0 = lambda / (n + lambda)``,
``Wc_0 = Wm_0 + 1 - alpha^2 + beta``, ``Wm_i = Wc_i = 1 / (2 (n + lambda))``; the thesis uses
``alpha = 1e-3``, ``beta = 2``, ``kappa = 0``.

Numerical choices:

- Weighted means are taken about the central sigma point, ``x_0 + sum_i Wm_i (x_i - x_0)``. With
  ``alpha = 1e-3`` the weights are of order ``+-1e6``; summing ``Wm_i x_i`` directly cancels away six
  digits of the state, the centred form keeps them.
- Angle components (``angle_mask``, e.g. bearings) are averaged on the circle: the differences to the
  central point are wrapped to ``(-pi, pi]`` before weighting, and every residual is wrapped, so sigma points
  straddling +-180 degrees give the right mean and spread.
- A covariance that is not symmetric positive definite (the prior, ``S``, the posterior or the
  prediction) is repaired by symmetrizing and eigenvalue clipping
  (:func:`oceanloc.estimation.gaussian.repair_covariance`) and the track is flagged (``repaired``) instead
  of the filter raising mid-track; the repaired prior is the one the sigma points and the posterior
  ``P - K S K^T`` use, so every covariance returned is symmetric positive definite.
- :func:`ukf_predict` returns the propagated sigma points. :func:`ukf_update` draws fresh sigma points
  from the predicted Gaussian by default (so that on a linear problem the UKF equals the Kalman filter
  exactly); passing the propagated points (``sigma_points=``) reproduces the thesis' listing and FilterPy,
  which reuse them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray
from oceanloc.errors import ConfigError
from oceanloc.estimation.gaussian import Gaussian, repair_covariance, robust_cholesky, symmetrize
from oceanloc.estimation.kalman import (
    StateFunction,
    UpdateResult,
    innovation,
    masked_noise,
    measurement_mask,
)
from oceanloc.models.measurements import wrap_angle_rad


@dataclass(frozen=True, slots=True, kw_only=True)
class SigmaPointParams:
    """Scaled unscented transform parameters (van der Merwe); defaults are the thesis' values.

    Attributes
    ----------
    alpha : float
        Spread of the sigma points around the mean, ``0 < alpha <= 1``.
    beta : float
        Prior knowledge of the distribution (2 is optimal for a Gaussian).
    kappa : float
        Secondary scaling (usually 0 or ``3 - n``).
    """

    alpha: float = 1e-3
    beta: float = 2.0
    kappa: float = 0.0

    def __post_init__(self) -> None:
        if not 0.0 < self.alpha <= 1.0:
            raise ConfigError(f"UKF alpha must be in (0, 1], got {self.alpha}")

    def lambda_(self, n: int) -> float:
        """``lambda = alpha^2 (n + kappa) - n``."""
        return self.alpha**2 * (n + self.kappa) - n

    def weights(self, n: int) -> tuple[FloatArray, FloatArray]:
        """Mean and covariance weights ``(Wm, Wc)``, each ``(2n + 1,)``."""
        lam = self.lambda_(n)
        c = n + lam
        if not c > 0:
            raise ConfigError(f"UKF needs n + lambda > 0; alpha={self.alpha}, kappa={self.kappa}, n={n}")
        wm = np.full(2 * n + 1, 0.5 / c)
        wc = wm.copy()
        wm[0] = lam / c
        wc[0] = lam / c + (1.0 - self.alpha**2 + self.beta)
        return wm, wc


@dataclass(frozen=True, slots=True, kw_only=True)
class UkfPrediction:
    """Result of :func:`ukf_predict`.

    Attributes
    ----------
    state : Gaussian
        Predicted density (including ``Q``).
    sigma_points : (B, 2n + 1, n) float
        The sigma points after the motion model (before ``Q``).
    repaired : (B,) bool
        The prior covariance needed an eigenvalue repair to be factored.
    """

    state: Gaussian
    sigma_points: FloatArray
    repaired: BoolArray


def sigma_points(state: Gaussian, params: SigmaPointParams) -> tuple[FloatArray, BoolArray]:
    """Scaled sigma points of ``B`` Gaussians.

    Returns
    -------
    points : (B, 2n + 1, n) float
        ``[x, x + c L_1, ..., x + c L_n, x - c L_1, ..., x - c L_n]``, ``c = sqrt(n + lambda)``.
    repaired : (B,) bool
        Which covariances were repaired before factoring.
    """
    n = state.dim
    chol, repaired = robust_cholesky(state.cov)
    scaled = np.sqrt(n + params.lambda_(n)) * np.swapaxes(chol, -1, -2)  # rows are the columns L_i
    x = state.mean[:, None, :]
    return np.concatenate([x, x + scaled, x - scaled], axis=1), repaired


def weighted_mean(points: FloatArray, wm: FloatArray, angle_mask: ArrayLike | None = None) -> FloatArray:
    """Weighted mean of sigma points ``(B, S, d) -> (B, d)`` about the central point; angles on the circle."""
    ref = points[:, 0, :]
    dev = points - ref[:, None, :]
    if angle_mask is not None:
        return _wrap_where(ref + wm @ _wrap_where(dev, angle_mask), angle_mask)
    return ref + wm @ dev


def deviations(points: FloatArray, mean: FloatArray, angle_mask: ArrayLike | None = None) -> FloatArray:
    """``points - mean`` ``(B, S, d)``, angle components wrapped."""
    dev = points - mean[:, None, :]
    return dev if angle_mask is None else _wrap_where(dev, angle_mask)


def _wrap_where(values: FloatArray, angle_mask: ArrayLike) -> FloatArray:
    am = np.asarray(angle_mask, dtype=bool)
    if am.all():
        return wrap_angle_rad(values)
    return np.where(am, wrap_angle_rad(values), values) if am.any() else values


def weighted_outer(weights: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """``sum_s w_s a_s b_s^T``: ``(S,)``, ``(B, S, i)``, ``(B, S, j)`` -> ``(B, i, j)``."""
    return np.swapaxes(a * weights[:, None], -1, -2) @ b


def ukf_predict(
    state: Gaussian, fx: StateFunction, process_noise: ArrayLike, params: SigmaPointParams
) -> UkfPrediction:
    """UKF time update: propagate sigma points through ``f`` and re-form mean and covariance plus ``Q``.

    Parameters
    ----------
    state : Gaussian
        Posterior at step ``k``, ``B`` tracks.
    fx : callable
        Motion model on sigma points, ``(B, S, n) -> (B, S, n)``.
    process_noise : (n, n) or (B, n, n) float
        Additive ``Q``.
    params : SigmaPointParams
    """
    cov_in, repaired = repair_covariance(state.cov)
    points, chol_repaired = sigma_points(Gaussian(mean=state.mean, cov=cov_in), params)
    wm, wc = params.weights(state.dim)
    moved = fx(points)
    mean = weighted_mean(moved, wm)
    dev = deviations(moved, mean)
    cov, cov_repaired = repair_covariance(
        symmetrize(weighted_outer(wc, dev, dev) + np.asarray(process_noise, dtype=float))
    )
    return UkfPrediction(
        state=Gaussian(mean=mean, cov=cov),
        sigma_points=moved,
        repaired=repaired | chol_repaired | cov_repaired,
    )


def ukf_update(
    state: Gaussian,
    z: ArrayLike,
    hx: StateFunction,
    noise_cov: ArrayLike,
    params: SigmaPointParams,
    *,
    propagated_points: FloatArray | None = None,
    angle_mask: ArrayLike | None = None,
    mask: ArrayLike | None = None,
) -> UpdateResult:
    """UKF measurement update (thesis Figure 23).

    Parameters
    ----------
    state : Gaussian
        Prediction, ``B`` tracks.
    z : (B, m) float
        Measurements; ``NaN`` marks a missing one.
    hx : callable
        Measurement model on sigma points, ``(B, S, n) -> (B, S, m)``.
    noise_cov : (m, m) or (B, m, m) float
        Additive ``R``.
    params : SigmaPointParams
    propagated_points : (B, 2n + 1, n) float, optional
        Sigma points to use (e.g. :attr:`UkfPrediction.sigma_points`); drawn from ``state`` if omitted.
    angle_mask : (m,) bool, optional
        Measurement components that are angles.
    mask : (B, m) bool, optional
        False drops a measurement.
    """
    zz = np.asarray(z, dtype=float)
    avail = measurement_mask(zz, mask)
    cov_in, repaired = repair_covariance(state.cov)
    state = Gaussian(mean=state.mean, cov=cov_in)
    if propagated_points is None:
        points, chol_repaired = sigma_points(state, params)
        repaired = repaired | chol_repaired
    else:
        points = propagated_points
    wm, wc = params.weights(state.dim)
    zs = hx(points)
    z_pred = weighted_mean(zs, wm, angle_mask)
    dz = np.where(avail[:, None, :], deviations(zs, z_pred, angle_mask), 0.0)
    dx = deviations(points, state.mean)
    s, s_repaired = repair_covariance(symmetrize(weighted_outer(wc, dz, dz) + masked_noise(noise_cov, avail)))
    pxz = weighted_outer(wc, dx, dz)
    nu = innovation(zz, z_pred, avail, angle_mask)
    # One solve for the gain and the NIS: S^-1 [Pxz^T | nu].
    sol = np.linalg.solve(s, np.concatenate([np.swapaxes(pxz, -1, -2), nu[..., None]], axis=-1))
    k = np.swapaxes(sol[..., :-1], -1, -2)
    mean = state.mean + (k @ nu[..., None])[..., 0]
    cov, cov_repaired = repair_covariance(symmetrize(state.cov - k @ s @ np.swapaxes(k, -1, -2)))
    return UpdateResult(
        state=Gaussian(mean=mean, cov=cov),
        innovation=nu,
        innovation_cov=s,
        nis=np.maximum(np.sum(nu * sol[..., -1], axis=-1), 0.0),
        dof=avail.sum(axis=-1),
        repaired=repaired | s_repaired | cov_repaired,
    )
