"""Cramer-Rao bounds: the snapshot position bound behind HDOP, and the posterior CRLB of a track.

- :func:`hdop_from_jacobian`: ``sqrt(trace((H^T R^-1 H)^-1))``, the square root of the trace of the
  Cramer-Rao bound of a 2-D position from one set of measurements (AquaQuad thesis eqs. IV.6, IV.9).
- :func:`pcrlb`: the posterior Cramer-Rao lower bound of a filtering problem with linear-Gaussian motion
  and additive Gaussian measurement noise, by the recursion of Tichavsky, Muravchik and Nehorai (1998):
  ``J_{k+1} = (F J_k^-1 F^T + Q)^-1 + E[H_{k+1}^T R^-1 H_{k+1}]``, ``J_0 = P_0^-1``; the expectation is over
  the true states, estimated by averaging the measurement information over Monte Carlo truth trajectories
  (:func:`expected_measurement_information`). No unbiased (or Bayesian) estimator's mean square error can be
  below ``J_k^-1``, so ``RMSE / sqrt(bound)`` measures how much a filter leaves on the table.
"""

from __future__ import annotations

import numpy as np

from oceanloc import _validate
from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ArgumentError
from oceanloc.estimation.gaussian import symmetrize

_SINGULAR_RTOL = 1e-12


def hdop_from_jacobian(jacobian: ArrayLike, sigma: ArrayLike = 1.0) -> FloatArray:
    """``sqrt(trace((H^T R^-1 H)^-1))`` for ``R = diag(sigma^2)``, eq. (IV.9), in closed form for 2-D.

    Parameters
    ----------
    jacobian : (..., m, 2) float
        Rows ``h_i``.
    sigma : float or (..., m) float
        Measurement standard deviations; a row with ``sigma = inf`` contributes nothing (a missing node).

    Returns
    -------
    (...) float
        HDOP; ``inf`` where the information matrix is singular.
    """
    h = np.asarray(jacobian, dtype=float)
    w = 1.0 / np.square(np.asarray(sigma, dtype=float))
    w = np.broadcast_to(w, h.shape[:-1])
    g00 = np.sum(w * h[..., 0] ** 2, axis=-1)
    g11 = np.sum(w * h[..., 1] ** 2, axis=-1)
    g01 = np.sum(w * h[..., 0] * h[..., 1], axis=-1)
    tr = g00 + g11
    det = g00 * g11 - g01 * g01
    ok = det > _SINGULAR_RTOL * tr * tr
    out = np.full(tr.shape, np.inf)
    np.divide(tr, det, out=out, where=ok)
    return np.sqrt(out)


def measurement_information(
    jacobian: ArrayLike, noise_cov: ArrayLike, avail: ArrayLike | None = None
) -> FloatArray:
    """Fisher information ``H^T R^-1 H`` of one set of measurements.

    Parameters
    ----------
    jacobian : (..., m, n) float
    noise_cov : (m, m) float
        ``R``; missing measurements (``avail`` False) are dropped from it exactly.
    avail : (..., m) bool, optional

    Returns
    -------
    (..., n, n) float
    """
    h = np.asarray(jacobian, dtype=float)
    r = np.asarray(noise_cov, dtype=float)
    if avail is None:
        w = np.linalg.inv(r)
        return np.swapaxes(h, -1, -2) @ w @ h
    a = np.asarray(avail, dtype=bool)
    both = a[..., :, None] & a[..., None, :]
    r_masked = np.where(both, r, np.where(np.eye(r.shape[0], dtype=bool), 1.0, 0.0))
    hm = np.where(a[..., None], h, 0.0)
    return np.swapaxes(hm, -1, -2) @ np.linalg.solve(r_masked, hm)


def expected_measurement_information(
    jacobians: ArrayLike, noise_cov: ArrayLike, avail: ArrayLike | None = None
) -> FloatArray:
    """Monte Carlo estimate of ``E[H_k^T R^-1 H_k]`` over true trajectories.

    Parameters
    ----------
    jacobians : (R, T, m, n) float
        Measurement Jacobians at the true states of ``R`` truth runs and ``T`` epochs.
    noise_cov : (m, m) float
    avail : (R, T, m) bool, optional
        Which measurements exist (a detection probability below one lowers the information).

    Returns
    -------
    (T, n, n) float
    """
    return np.mean(measurement_information(jacobians, noise_cov, avail), axis=0)


def pcrlb(
    initial_cov: ArrayLike,
    transition: ArrayLike,
    process_noise: ArrayLike,
    information: ArrayLike,
) -> FloatArray:
    """Posterior Cramer-Rao lower bound by the Tichavsky recursion (linear-Gaussian motion).

    ``P_k^- = F J_{k-1}^-1 F^T + Q`` and ``J_k = (P_k^-)^-1 + I_k``; the recursion is written in covariance
    form for the prediction, so ``Q`` may be singular (a deterministic motion model).

    Parameters
    ----------
    initial_cov : (n, n) float
        Prior covariance ``P_0`` at ``t_0``.
    transition : (n, n) float
        ``F``.
    process_noise : (n, n) float
        ``Q``.
    information : (T, n, n) float
        Expected measurement information at epochs ``1 .. T``.

    Returns
    -------
    (T, n, n) float
        Bound covariances ``J_k^-1``.
    """
    cov = _validate.covariances("initial_cov", initial_cov)
    n = cov.shape[-1]
    if cov.ndim != 2:
        raise ArgumentError(f"initial_cov: shape {cov.shape}, expected (n, n)")
    f = _validate.float_array("transition", transition, shape=(n, n), max_abs=_validate.MAX_VARIANCE)
    q = _validate.covariances("process_noise", process_noise, dim=n)
    if q.ndim != 2:
        raise ArgumentError(f"process_noise: shape {q.shape}, expected ({n}, {n})")
    info = _validate.float_array("information", information, shape=(None, n, n), allow_empty=True)
    if info.size:
        _validate.covariances("information", info, dim=n, max_variance=_validate.MAX_INFORMATION)
    if np.linalg.eigvalsh(cov)[0] <= 0.0:
        raise ArgumentError("initial_cov: not positive definite (the bound starts from its inverse)")
    bound = np.empty_like(info)
    for k in range(info.shape[0]):
        prior_cov = symmetrize(f @ cov @ f.T + q)
        j = symmetrize(np.linalg.inv(prior_cov) + info[k])
        cov = symmetrize(np.linalg.inv(j))
        bound[k] = cov
    return bound
