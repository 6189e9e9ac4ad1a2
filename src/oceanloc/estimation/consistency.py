"""Consistency of an estimate with its covariance: NEES (Garcia et al. 2019, eq. 44) and its chi-square
check, and confidence ellipses from 2x2 covariances (Appendix B).

For an estimate ``p`` with covariance ``P``, the ``q`` confidence region of a 2-D Gaussian is the ellipse
with semi-axes ``c sqrt(lambda_max)`` and ``c sqrt(lambda_min)`` along the eigenvectors of ``P``, where
``c = sqrt(chi2_2.ppf(q))`` (2.4477 for 95 %, the value the appendix prints), rotated by
``phi = atan2(y_max, x_max)`` of the major eigenvector (eqs. 60-62).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError


@dataclass(frozen=True, slots=True, kw_only=True)
class ConfidenceEllipse:
    """A batch of confidence ellipses.

    Attributes
    ----------
    center_m : (..., 2) float
        Centres (east, north), metres.
    semi_major_m, semi_minor_m : (...) float
        Semi-axes ``a = c sqrt(lambda_max)`` and ``b = c sqrt(lambda_min)``, metres.
    angle_rad : (...) float
        Direction of the major axis, counter-clockwise from east, in ``(-pi/2, pi/2]``.
    confidence : float
        Probability mass inside the ellipse.
    """

    center_m: FloatArray
    semi_major_m: FloatArray
    semi_minor_m: FloatArray
    angle_rad: FloatArray
    confidence: float

    def points(self, n: int = 100) -> FloatArray:
        """Points along the boundary, eq. (60): ``(..., n, 2)``, closed (first point repeated last)."""
        theta = np.linspace(0.0, 2.0 * np.pi, n)
        a, b = self.semi_major_m[..., None], self.semi_minor_m[..., None]
        c, s = np.cos(self.angle_rad)[..., None], np.sin(self.angle_rad)[..., None]
        x, y = a * np.cos(theta), b * np.sin(theta)
        return np.stack([c * x - s * y, s * x + c * y], axis=-1) + self.center_m[..., None, :]


def ellipse_scale(confidence: float) -> float:
    """``c = sqrt(chi2_2.ppf(confidence))``; 2.4477 for 95 %."""
    if not 0.0 < confidence < 1.0:
        raise ConfigError(f"confidence must be in (0, 1), got {confidence}")
    from scipy import stats

    return float(np.sqrt(stats.chi2.ppf(confidence, 2)))


def confidence_ellipse(center_m: ArrayLike, cov_m2: ArrayLike, confidence: float = 0.95) -> ConfidenceEllipse:
    """Confidence ellipses of Gaussians, Appendix B.

    Parameters
    ----------
    center_m : (..., 2) float
    cov_m2 : (..., 2, 2) float
        Covariances (the upper-left block of eq. 22 for east-north), square metres.
    confidence : float
    """
    cov = np.asarray(cov_m2, dtype=float)
    lam, vec = np.linalg.eigh(0.5 * (cov + np.swapaxes(cov, -1, -2)))
    lam = np.maximum(lam, 0.0)
    major = vec[..., :, 1]
    angle = np.arctan2(major[..., 1], major[..., 0])
    angle = np.where(angle > np.pi / 2, angle - np.pi, np.where(angle <= -np.pi / 2, angle + np.pi, angle))
    c = ellipse_scale(confidence)
    return ConfidenceEllipse(
        center_m=np.asarray(center_m, dtype=float),
        semi_major_m=c * np.sqrt(lam[..., 1]),
        semi_minor_m=c * np.sqrt(lam[..., 0]),
        angle_rad=angle,
        confidence=confidence,
    )


def sample_ellipse(points_m: ArrayLike, confidence: float = 0.95) -> ConfidenceEllipse:
    """The ellipse fitted to samples (their mean and covariance), as the journal's Fig. 1 compares.

    Parameters
    ----------
    points_m : (S, 2) float
    """
    pts = np.asarray(points_m, dtype=float)
    if pts.ndim != 2 or pts.shape[0] < 3 or pts.shape[1] != 2:
        raise ConfigError(f"need at least 3 points of shape (S, 2), got {pts.shape}")
    return confidence_ellipse(pts.mean(axis=0), np.cov(pts.T), confidence)


def nees(errors_m: ArrayLike, information: ArrayLike) -> FloatArray:
    """Normalized estimation error squared, eq. (44), over the block-diagonal ``Y_n``.

    Parameters
    ----------
    errors_m : (..., M, 3) float
        Position errors of all transponders.
    information : (..., M, 3, 3) float
        Their information matrices ``Y_n^m``.

    Returns
    -------
    (...) float
        ``sum_m e_m^T Y_m e_m``; chi-square with ``3M`` degrees of freedom for a consistent estimator.
    """
    e = np.asarray(errors_m, dtype=float)
    return np.einsum("...mi,...mij,...mj->...", e, np.asarray(information, dtype=float), e)


@dataclass(frozen=True, slots=True, kw_only=True)
class ChiSquareCheck:
    """Consistency of NEES samples with ``chi2(dof)``.

    Attributes
    ----------
    mean : float
        Sample mean of the NEES.
    dof : int
        Degrees of freedom (``3M``).
    runs : int
        Number of samples.
    mean_band : tuple[float, float]
        ``dof +- 3 sqrt(2 dof / runs)``: three Monte Carlo standard errors of the mean.
    p_value : float
        Kolmogorov-Smirnov goodness-of-fit p-value against ``chi2(dof)``.
    """

    mean: float
    dof: int
    runs: int
    mean_band: tuple[float, float]
    p_value: float

    @property
    def mean_within_band(self) -> bool:
        return self.mean_band[0] <= self.mean <= self.mean_band[1]


def chi_square_check(samples: ArrayLike, dof: int) -> ChiSquareCheck:
    """Compare NEES samples (one per run) with ``chi2(dof)``: mean within 3 SE, KS p-value."""
    x = np.asarray(samples, dtype=float).ravel()
    if x.size < 2 or dof < 1:
        raise ConfigError(f"need at least 2 samples and dof >= 1, got {x.size} samples, dof {dof}")
    half = 3.0 * np.sqrt(2.0 * dof / x.size)
    return ChiSquareCheck(
        mean=float(x.mean()),
        dof=int(dof),
        runs=int(x.size),
        mean_band=(dof - half, dof + half),
        p_value=float(_stats().kstest(x, _stats().chi2(dof).cdf).pvalue),
    )


def _stats():
    """``scipy.stats``, imported on first use (it adds a second to the command line's start)."""
    from scipy import stats

    return stats
