"""A batch of Gaussian states and the linear-algebra helpers that keep covariances valid.

Filters in :mod:`oceanloc.estimation.kalman` and :mod:`oceanloc.estimation.unscented` are pure functions
``Gaussian -> Gaussian``; a :class:`Gaussian` holds ``B`` independent tracks (Monte Carlo runs, targets)
so one call steps them all.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray
from oceanloc.errors import ArgumentError


@dataclass(frozen=True, slots=True, kw_only=True)
class Gaussian:
    """``B`` Gaussian densities ``N(mean_b, cov_b)``.

    Attributes
    ----------
    mean : (B, n) float
    cov : (B, n, n) float
        Symmetric positive (semi-)definite.
    """

    mean: FloatArray
    cov: FloatArray

    def __post_init__(self) -> None:
        mean = np.asarray(self.mean, dtype=float)
        cov = np.asarray(self.cov, dtype=float)
        if mean.ndim != 2 or cov.shape != (*mean.shape, mean.shape[1]):
            raise ArgumentError(
                f"Gaussian needs mean (B, n) and cov (B, n, n); got {mean.shape}, {cov.shape}"
            )
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)

    @classmethod
    def from_single(cls, mean: ArrayLike, cov: ArrayLike, batch: int = 1) -> Gaussian:
        """``batch`` copies of one density ``mean (n,)``, ``cov (n, n)``."""
        m = np.asarray(mean, dtype=float)
        c = np.asarray(cov, dtype=float)
        return cls(mean=np.tile(m, (batch, 1)), cov=np.tile(c, (batch, 1, 1)))

    @property
    def batch_size(self) -> int:
        return int(self.mean.shape[0])

    @property
    def dim(self) -> int:
        return int(self.mean.shape[1])

    def __getitem__(self, index: int | slice | np.ndarray) -> Gaussian:
        """The tracks ``index`` (a batch is kept a batch: an integer index gives ``B = 1``)."""
        if isinstance(index, int | np.integer):
            index = slice(int(index), int(index) + 1)
        return Gaussian(mean=self.mean[index], cov=self.cov[index])


def symmetrize(cov: FloatArray) -> FloatArray:
    """``(P + P^T) / 2`` over the last two axes."""
    return 0.5 * (cov + np.swapaxes(cov, -1, -2))


def robust_cholesky(cov: ArrayLike, rel_floor: float = 1e-12) -> tuple[FloatArray, BoolArray]:
    """Lower Cholesky factors of a batch of covariances, repairing the ones that are not positive definite.

    A covariance that lost definiteness to round-off (or a bad model) would make ``np.linalg.cholesky``
    raise mid-track. Instead, the failing matrices are symmetrized and their eigenvalues clipped from below
    at ``rel_floor`` times their largest eigenvalue (the nearest positive definite matrix in the Frobenius
    norm, up to the floor) before factorization; the others are factored as they are.

    Parameters
    ----------
    cov : (..., n, n) float
    rel_floor : float
        Smallest eigenvalue kept, relative to the largest.

    Returns
    -------
    chol : (..., n, n) float
        Lower-triangular ``L`` with ``L L^T`` = the (repaired) covariance.
    repaired : (...) bool
        Which matrices were repaired.
    """
    p = np.asarray(cov, dtype=float)
    try:
        return np.linalg.cholesky(p), np.zeros(p.shape[:-2], dtype=bool)
    except np.linalg.LinAlgError:
        pass
    # Rare path: find the matrices whose spectrum is (numerically) not positive, repair those, retry.
    w = np.linalg.eigvalsh(symmetrize(p))
    repaired = w[..., 0] <= rel_floor * np.max(np.abs(w), axis=-1)
    fixed = np.where(repaired[..., None, None], clip_eigenvalues(p, rel_floor), symmetrize(p))
    try:
        return np.linalg.cholesky(fixed), repaired
    except np.linalg.LinAlgError:
        repaired = np.ones(p.shape[:-2], dtype=bool)
        return np.linalg.cholesky(clip_eigenvalues(p, max(rel_floor, 1e-9))), repaired


def clip_eigenvalues(cov: ArrayLike, rel_floor: float = 1e-12) -> FloatArray:
    """Symmetrize and clip eigenvalues below ``rel_floor * max(|eig|)`` (and below a tiny absolute floor)."""
    p = symmetrize(np.asarray(cov, dtype=float))
    w, v = np.linalg.eigh(p)
    scale = np.max(np.abs(w), axis=-1, keepdims=True)
    floor = np.maximum(rel_floor * scale, np.finfo(float).tiny ** 0.5)
    w = np.maximum(w, floor)
    return symmetrize(np.einsum("...ij,...j,...kj->...ik", v, w, v))


def repair_covariance(
    cov: ArrayLike, rel_floor: float = 1e-12, sym_tol: float = 1e-9
) -> tuple[FloatArray, BoolArray]:
    """Symmetric positive-definite covariances, and which of them needed a repair.

    A matrix is left exactly as it is (bit for bit) when it is symmetric to ``sym_tol`` relative to its
    largest entry and its Cholesky factorization succeeds. Otherwise it is symmetrized and, if still not
    positive definite, its eigenvalues are clipped from below at ``rel_floor`` times the largest
    (:func:`clip_eigenvalues`: the nearest such matrix in the Frobenius norm), and it is flagged.
    Matrices with non-finite entries cannot be repaired: they are returned unchanged and flagged.

    Parameters
    ----------
    cov : (..., n, n) float

    Returns
    -------
    cov : (..., n, n) float
        Symmetric positive definite (where finite).
    repaired : (...) bool
    """
    p = np.asarray(cov, dtype=float)
    finite = np.all(np.isfinite(p), axis=(-1, -2))
    scale = np.max(np.abs(np.where(finite[..., None, None], p, 0.0)), axis=(-1, -2))
    asym = np.max(np.abs(p - np.swapaxes(p, -1, -2)), axis=(-1, -2)) > sym_tol * scale
    asym &= finite
    if not (asym.any() or not finite.all()):
        try:
            np.linalg.cholesky(p)
            return p, np.zeros(p.shape[:-2], dtype=bool)
        except np.linalg.LinAlgError:
            pass
    sym = np.where(asym[..., None, None], symmetrize(p), p)
    safe = np.where(finite[..., None, None], sym, np.eye(p.shape[-1]))
    w = np.linalg.eigvalsh(symmetrize(safe))
    indefinite = finite & (w[..., 0] <= rel_floor * np.max(np.abs(w), axis=-1))
    out = np.where(indefinite[..., None, None], clip_eigenvalues(safe, rel_floor), sym)
    return out, asym | indefinite | ~finite
