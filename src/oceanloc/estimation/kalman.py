"""Kalman filter (KF) and extended Kalman filter (EKF) as pure, batched predict/update steps.

AquaQuad thesis, Chapter III.A (eqs. III.2-III.9) and III.C (Figure 21): predict with the motion model
``x' = Phi x``, ``P' = Phi P Phi^T + Q``; update with the gain ``K = P' H^T (H P' H^T + R)^-1`` (III.9),
``x = x' + K (z - h(x'))`` (III.8). For the EKF, ``H`` is the measurement Jacobian at the predicted mean.

Choices a mature filter needs and the thesis leaves implicit:

- The covariance update uses the Joseph form ``(I - K H) P (I - K H)^T + K R K^T``, which stays symmetric and
  positive semi-definite under round-off (the ``P = (I - K H) P`` of Figure 21 does not).
- Residuals of angle measurements are wrapped to ``(-pi, pi]`` (``angle_mask``): a bearing of 179 degrees
  against a prediction of -179 degrees is a 2-degree innovation, not 358.
- Missing measurements (``NaN`` in ``z``, or ``mask = False``) are dropped exactly: their rows of ``H`` and
  the innovation are zeroed and their block of ``S`` is replaced by the identity, which leaves the gain's
  other columns as if the rows had been removed. A track with no measurement at all is left at its
  prediction. The NIS counts only the measurements present (``dof``).
- Every array carries the batch dimension first: ``B`` tracks are stepped in one call.
- Covariances are kept symmetric positive definite: a prediction that is not symmetric or not positive
  definite (a bad model, a hand-made prior, round-off) is repaired before the update
  (:func:`oceanloc.estimation.gaussian.repair_covariance`: symmetrize, clip eigenvalues), and so are
  ``S`` and the posterior; the track is flagged (``repaired``). A valid input is used bit for bit as it
  is. The NIS is therefore never negative.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.estimation.gaussian import Gaussian, repair_covariance, symmetrize
from oceanloc.models.measurements import wrap_angle_rad
from oceanloc.models.motion import LinearMotionModel

StateFunction = Callable[[FloatArray], FloatArray]
"""``f(x)``: ``(B, n) -> (B, n)`` or a measurement function ``(B, n) -> (B, m)`` (also ``(B, S, n)``)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class UpdateResult:
    """Posterior and diagnostics of one measurement update.

    Attributes
    ----------
    state : Gaussian
        Posterior, ``B`` tracks.
    innovation : (B, m) float
        ``z - h(x')`` (wrapped for angles), zero for missing measurements.
    innovation_cov : (B, m, m) float
        ``S``; identity rows and columns for missing measurements.
    nis : (B,) float
        Normalized innovation squared ``nu^T S^-1 nu``, chi-square with ``dof`` degrees of freedom for a
        consistent filter.
    dof : (B,) int
        Number of measurements used.
    repaired : (B,) bool
        A covariance of this step (the prediction, ``S`` or the posterior) was not symmetric positive
        definite and was repaired; the posterior returned is symmetric positive definite either way.
    """

    state: Gaussian
    innovation: FloatArray
    innovation_cov: FloatArray
    nis: FloatArray
    dof: IntArray
    repaired: BoolArray


def predict(state: Gaussian, motion: LinearMotionModel) -> Gaussian:
    """Time update of the KF (and of the EKF with a linear motion model): ``Phi x``, ``Phi P Phi^T + Q``."""
    f = motion.transition
    mean = state.mean @ f.T
    cov = f @ state.cov @ f.T + motion.process_noise
    return Gaussian(mean=mean, cov=symmetrize(cov))


def ekf_predict(
    state: Gaussian, fx: StateFunction, jacobian_fx: StateFunction, process_noise: ArrayLike
) -> Gaussian:
    """EKF time update with a nonlinear motion model: ``f(x)``, ``F P F^T + Q`` with ``F = df/dx(x)``.

    Parameters
    ----------
    fx : callable
        ``(B, n) -> (B, n)``.
    jacobian_fx : callable
        ``(B, n) -> (B, n, n)``.
    process_noise : (n, n) or (B, n, n) float
    """
    f = jacobian_fx(state.mean)
    cov = f @ state.cov @ np.swapaxes(f, -1, -2) + np.asarray(process_noise, dtype=float)
    return Gaussian(mean=fx(state.mean), cov=symmetrize(cov))


def measurement_mask(z: ArrayLike, mask: ArrayLike | None) -> BoolArray:
    """Available measurements: finite values of ``z``, and ``mask`` if given; ``(B, m)`` bool."""
    zz = np.asarray(z, dtype=float)
    avail = np.isfinite(zz)
    if mask is not None:
        avail = avail & np.broadcast_to(np.asarray(mask, dtype=bool), zz.shape)
    return avail


def innovation(
    z: ArrayLike, predicted: FloatArray, avail: BoolArray, angle_mask: ArrayLike | None
) -> FloatArray:
    """``z - z_pred`` with angle components wrapped to ``(-pi, pi]`` and missing ones zero; ``(B, m)``."""
    nu = np.where(avail, np.asarray(z, dtype=float) - predicted, 0.0)
    if angle_mask is not None:
        am = np.asarray(angle_mask, dtype=bool)
        nu = np.where(am, wrap_angle_rad(nu), nu)
    return nu


def masked_noise(noise_cov: ArrayLike, avail: BoolArray) -> FloatArray:
    """``R`` with the rows and columns of missing measurements replaced by those of the identity."""
    r = np.broadcast_to(np.asarray(noise_cov, dtype=float), (*avail.shape, avail.shape[-1]))
    if avail.all():
        return r
    both = avail[..., :, None] & avail[..., None, :]
    eye = np.eye(avail.shape[-1], dtype=bool)
    return np.where(both, r, np.where(eye, 1.0, 0.0))


def nis_of(nu: FloatArray, s: FloatArray) -> FloatArray:
    """``nu^T S^-1 nu`` over the batch."""
    return np.einsum("bi,bi->b", nu, np.linalg.solve(s, nu[..., None])[..., 0])


def linear_update(
    state: Gaussian,
    nu: FloatArray,
    jacobian: FloatArray,
    noise_cov: ArrayLike,
    avail: BoolArray,
) -> UpdateResult:
    """Kalman update given the innovation ``nu (B, m)`` and ``H (B, m, n)``; Joseph-form covariance.

    The prediction, ``S`` and the posterior are repaired where they are not symmetric positive definite
    (flagged in ``repaired``).
    """
    h = jacobian if avail.all() else np.where(avail[..., None], jacobian, 0.0)
    r = masked_noise(noise_cov, avail)
    p, repaired = repair_covariance(state.cov)
    hp = h @ p
    s, s_repaired = repair_covariance(symmetrize(hp @ np.swapaxes(h, -1, -2) + r))
    # One solve for the gain and the NIS: S^-1 [H P | nu].
    sol = np.linalg.solve(s, np.concatenate([hp, nu[..., None]], axis=-1))
    k = np.swapaxes(sol[..., :-1], -1, -2)
    mean = state.mean + (k @ nu[..., None])[..., 0]
    a = np.eye(state.dim) - k @ h
    cov = a @ p @ np.swapaxes(a, -1, -2) + k @ r @ np.swapaxes(k, -1, -2)
    cov, cov_repaired = repair_covariance(symmetrize(cov))
    return UpdateResult(
        state=Gaussian(mean=mean, cov=cov),
        innovation=nu,
        innovation_cov=s,
        nis=np.maximum(np.sum(nu * sol[..., -1], axis=-1), 0.0),
        dof=avail.sum(axis=-1),
        repaired=repaired | s_repaired | cov_repaired,
    )


def kf_update(
    state: Gaussian,
    z: ArrayLike,
    measurement_matrix: ArrayLike,
    noise_cov: ArrayLike,
    *,
    mask: ArrayLike | None = None,
) -> UpdateResult:
    """Linear Kalman update ``z = H x + v``, ``v ~ N(0, R)``, eqs. (III.8)-(III.9).

    Parameters
    ----------
    state : Gaussian
        Prediction, ``B`` tracks.
    z : (B, m) float
        Measurements; ``NaN`` marks a missing one.
    measurement_matrix : (m, n) or (B, m, n) float
    noise_cov : (m, m) or (B, m, m) float
    mask : (B, m) bool, optional
        False drops a measurement.
    """
    zz = np.asarray(z, dtype=float)
    avail = measurement_mask(zz, mask)
    h = np.broadcast_to(np.asarray(measurement_matrix, dtype=float), (*zz.shape, state.dim))
    nu = innovation(zz, np.einsum("bmn,bn->bm", h, state.mean), avail, None)
    return linear_update(state, nu, h, noise_cov, avail)


def ekf_update(
    state: Gaussian,
    z: ArrayLike,
    hx: StateFunction,
    jacobian_hx: StateFunction,
    noise_cov: ArrayLike,
    *,
    angle_mask: ArrayLike | None = None,
    mask: ArrayLike | None = None,
) -> UpdateResult:
    """EKF measurement update (thesis Figure 21): linearize ``h`` at the predicted mean.

    Parameters
    ----------
    state : Gaussian
        Prediction, ``B`` tracks.
    z : (B, m) float
        Measurements; ``NaN`` marks a missing one.
    hx : callable
        ``(B, n) -> (B, m)``.
    jacobian_hx : callable
        ``(B, n) -> (B, m, n)``, analytic.
    noise_cov : (m, m) or (B, m, m) float
    angle_mask : (m,) bool, optional
        Components that are angles (residuals wrapped).
    mask : (B, m) bool, optional
    """
    zz = np.asarray(z, dtype=float)
    avail = measurement_mask(zz, mask)
    nu = innovation(zz, hx(state.mean), avail, angle_mask)
    return linear_update(state, nu, jacobian_hx(state.mean), noise_cov, avail)


def ekf_update_sequential(
    state: Gaussian,
    z: ArrayLike,
    hx: StateFunction,
    jacobian_hx: StateFunction,
    noise_var: ArrayLike,
    *,
    angle_mask: ArrayLike | None = None,
    mask: ArrayLike | None = None,
) -> UpdateResult:
    """EKF update one measurement at a time (uncorrelated noise), relinearizing after each.

    For a linear model this equals :func:`kf_update` with ``R = diag(noise_var)``; for a nonlinear one the
    later measurements see the Jacobian at the already-corrected mean. Missing measurements are skipped.
    The loop runs over the ``m`` measurements, each step vectorized over the ``B`` tracks. The returned
    innovations are those of each scalar update (against the then-current mean); ``S`` is diagonal and the
    NIS is the sum of the scalar NIS values.

    Parameters
    ----------
    noise_var : (m,) or (B, m) float
        Measurement variances.
    """
    zz = np.asarray(z, dtype=float)
    avail = measurement_mask(zz, mask)
    var = np.broadcast_to(np.asarray(noise_var, dtype=float), zz.shape)
    am = np.zeros(zz.shape[-1], dtype=bool) if angle_mask is None else np.asarray(angle_mask, dtype=bool)
    nus = np.zeros_like(zz)
    s_diag = np.ones_like(zz)
    current = state
    repaired = np.zeros(state.batch_size, dtype=bool)
    for i in range(zz.shape[-1]):
        hi = hx(current.mean)[..., i : i + 1]
        nu = innovation(zz[..., i : i + 1], hi, avail[..., i : i + 1], am[i : i + 1])
        jac = jacobian_hx(current.mean)[..., i : i + 1, :]
        step = linear_update(current, nu, jac, var[..., i : i + 1, None], avail[..., i : i + 1])
        current = step.state
        repaired |= step.repaired
        nus[..., i] = nu[..., 0]
        s_diag[..., i] = step.innovation_cov[..., 0, 0]
    s = np.einsum("bi,ij->bij", s_diag, np.eye(zz.shape[-1]))
    return UpdateResult(
        state=current,
        innovation=nus,
        innovation_cov=s,
        nis=np.sum(nus**2 / s_diag, axis=-1),
        dof=avail.sum(axis=-1),
        repaired=repaired,
    )
