"""Fisher information of range measurements and the D-optimal information gain, batched.

After ``N`` measurements the information about transponder ``m`` is ``Y_N^m`` (the inverse of the MAP
covariance, eq. 22). Ranges taken at ``k`` further sites add ``sigma^-2 h^T h`` each (journal eqs. 28-29):

    Y_{N+k}^m = Y_N^m + sigma^-2 sum_n h_m(n)^T h_m(n)

and by the matrix determinant lemma (journal Appendix A, eq. 59)

    log det Y_{N+k}^m - log det Y_N^m = log det(I_k + sigma^-2 H_m P_m H_m^T),   P_m = (Y_N^m)^-1,

which for ``k = 1`` is ``log(1 + alpha_m)`` with ``alpha_m = sigma^-2 h P h^T`` (eqs. 36-39, conference
eq. 25). The journal's eq. (37) omits the ``sigma^-2``; for one transponder that does not move the argmax,
for several it does, so the consistent form is used here. The block-diagonal log det over all
transponders (eq. 32) is the sum over ``m`` (eq. 35).

The hot path evaluates thousands of candidate site sequences at once. It works on the Cholesky factor
``L`` of ``P / sigma^2`` (``U = H L``, gain ``log det(I + U U^T)``) component by component, with closed-form
determinants for ``k <= 3`` (products of Cholesky pivots, accurate to ``eps cond``), which is several times
faster than stacks of 3x3 matrix products.
"""

from __future__ import annotations

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError
from oceanloc.models.measurements import range_jacobian


def scaled_cholesky(cov_m2: ArrayLike, sigma_range_m: float) -> FloatArray:
    """Lower Cholesky factor of ``P / sigma^2``.

    Parameters
    ----------
    cov_m2 : (..., 3, 3) float
        Estimation covariances ``P``, square metres.
    sigma_range_m : float
        Range noise standard deviation, metres.

    Returns
    -------
    (..., 3, 3) float
        ``L`` with ``L L^T = P / sigma^2``, dimensionless.
    """
    cov = np.asarray(cov_m2, dtype=float)
    return np.linalg.cholesky(0.5 * (cov + np.swapaxes(cov, -1, -2)) / sigma_range_m**2)


def information_gain(
    sites_m: ArrayLike, estimates_m: ArrayLike, chol: ArrayLike, *, total: bool = True
) -> FloatArray:
    """D-optimal gain of measuring at ``k`` sites, summed over transponders (eqs. 29, 35, 38-39).

    Parameters
    ----------
    sites_m : (..., k, 3) float
        Candidate measurement sites (sequences of ``k``), metres.
    estimates_m : (..., M, 3) float
        Current transponder estimates; the Jacobians are linearized about them (eq. 8). Leading
        dimensions broadcast against those of ``sites_m`` (e.g. ``(B, 1, M, 3)`` against ``(B, C, k, 3)``).
    chol : (..., M, 3, 3) float
        :func:`scaled_cholesky` of the current covariances, broadcast like ``estimates_m``.
    total : bool
        Sum over transponders (default) or return the gain per transponder.

    Returns
    -------
    (...) or (..., M) float
        ``sum_m log det(Y_{N+k}^m) - log det(Y_N^m)``, nats.
    """
    sites = np.asarray(sites_m, dtype=float)
    est = np.asarray(estimates_m, dtype=float)
    L = np.asarray(chol, dtype=float)
    # Component arrays of shape (..., k, M): axis -2 is the step, axis -1 the transponder.
    d = [est[..., None, :, c] - sites[..., :, None, c] for c in range(3)]
    lower = [L[..., None, :, i, j] for i, j in _LOWER]
    per_m = whitened_gain(d[0], d[1], d[2], lower)
    return per_m.sum(axis=-1) if total else per_m


_LOWER = ((0, 0), (1, 0), (2, 0), (1, 1), (2, 1), (2, 2))
"""Index pairs of the lower triangle of a 3x3 Cholesky factor, in the order :func:`whitened_gain` takes."""


def whitened_gain(dx: FloatArray, dy: FloatArray, dz: FloatArray, lower: list[FloatArray]) -> FloatArray:
    """Per-transponder gain ``log det(I_k + U U^T)`` from line-of-sight components.

    Parameters
    ----------
    dx, dy, dz : (..., k, M) float
        Components of ``p_hat_m - site`` for each step and transponder (broadcastable).
    lower : list of six (..., 1 or k, M) float
        ``L00, L10, L20, L11, L21, L22`` of :func:`scaled_cholesky` per transponder.

    Returns
    -------
    (..., M) float
    """
    u = whitened_line_of_sight(dx, dy, dz, lower)
    k = dx.shape[-2]
    if k > 3:
        U = np.moveaxis(np.stack(np.broadcast_arrays(*u), axis=-1), -2, -3)  # (..., M, k, 3)
        return np.linalg.slogdet(np.eye(k) + U @ np.swapaxes(U, -1, -2))[1]
    return log_det_identity_plus_gram([tuple(c[..., i, :] for c in u) for i in range(k)])


def whitened_line_of_sight(
    dx: FloatArray, dy: FloatArray, dz: FloatArray, lower: list[FloatArray]
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``L^T (p_hat - site) / r``, the unit line of sight whitened by :func:`scaled_cholesky`'s ``L``.

    Parameters
    ----------
    dx, dy, dz : (...) float
        Components of ``p_hat_m - site`` (broadcastable).
    lower : list of six (...) float
        ``L00, L10, L20, L11, L21, L22``.

    Returns
    -------
    tuple of three (...) float
    """
    l00, l10, l20, l11, l21, l22 = lower
    inv_r = 1.0 / np.sqrt(dx * dx + dy * dy + dz * dz)
    return (dx * l00 + dy * l10 + dz * l20) * inv_r, (dy * l11 + dz * l21) * inv_r, dz * (l22 * inv_r)


def log_det_identity_plus_gram(rows: list[tuple[FloatArray, FloatArray, FloatArray]]) -> FloatArray:
    """``log det(I_k + U U^T)`` for ``k = len(rows) <= 3``, row ``i`` of ``U`` given as its three
    components (broadcastable arrays; rows of different shapes broadcast together).

    Closed forms, each row touched once: the planners' hot path is bound by the number of array
    operations, not by arithmetic. The determinant is the product of the Cholesky pivots of
    ``G = I + U U^T`` (``G_00``, then the Schur complements), not its cofactor expansion: lines of sight
    from nearby sites are nearly parallel, so ``G`` is nearly rank one with entries of 1e4 and more,
    and the expansion cancels products of 1e12 to a determinant of 1e5 (relative errors of 1e-7 in the
    planners' objective, as large as the optimality they must reach). Each pivot loses only
    ``eps cond(G)``, about 1e-12.
    """

    def s(a: int, b: int) -> FloatArray:
        (xa, ya, za), (xb, yb, zb) = rows[a], rows[b]
        return xa * xb + ya * yb + za * zb

    k = len(rows)
    if k == 1:
        return np.log1p(s(0, 0))
    if not 2 <= k <= 3:
        raise ConfigError(f"closed forms exist for 1 to 3 rows, got {k}")
    g00 = 1.0 + s(0, 0)
    g01 = s(0, 1)
    r01 = g01 / g00
    p1 = 1.0 + s(1, 1) - g01 * r01  # second pivot: G_11 - G_10 G_00^-1 G_01
    if k == 2:
        return np.log(g00 * p1)
    g02 = s(0, 2)
    q = s(1, 2) - g02 * r01  # G_21 - G_20 G_00^-1 G_01
    p2 = 1.0 + s(2, 2) - g02 * (g02 / g00) - q * (q / p1)
    return np.log(g00 * p1 * p2)


def information_gain_reference(
    sites_m: ArrayLike, estimates_m: ArrayLike, cov_m2: ArrayLike, sigma_range_m: float
) -> FloatArray:
    """The same gain as :func:`information_gain`, straight from eq. (29): slow, for tests.

    Shapes: ``sites_m (k, 3)``, ``estimates_m (M, 3)``, ``cov_m2 (M, 3, 3)``; returns a float.
    """
    sites = np.asarray(sites_m, dtype=float)
    total = 0.0
    for est, cov in zip(np.asarray(estimates_m, float), np.asarray(cov_m2, float), strict=True):
        info = np.linalg.inv(cov)
        h = range_jacobian(est, sites)
        updated = info + h.T @ h / sigma_range_m**2
        total += np.linalg.slogdet(updated)[1] - np.linalg.slogdet(info)[1]
    return float(total)


def log_det_information(information: ArrayLike) -> FloatArray:
    """``log det Y`` of a stack of information matrices; ``(..., d, d) -> (...)``.

    The block-diagonal log det over transponders (eq. 32) is the sum of these over the transponder axis.
    """
    sign, logdet = np.linalg.slogdet(np.asarray(information, dtype=float))
    return np.where(sign > 0, logdet, -np.inf)
