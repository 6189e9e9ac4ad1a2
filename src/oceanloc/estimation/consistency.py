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

from oceanloc import _validate
from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.errors import ArgumentError, ConfigError


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
    centre = _validate.float_array(
        "center_m", center_m, last=(2,), allow_empty=True, max_abs=_validate.MAX_LENGTH_M, unit="m"
    )
    cov = _validate.covariances("cov_m2", cov_m2, dim=2, allow_empty=True, unit="m^2")
    if centre.shape[:-1] != cov.shape[:-2]:
        raise ArgumentError(
            f"center_m and cov_m2: {centre.shape[:-1]} centres but {cov.shape[:-2]} covariances"
        )
    _validate.number("confidence", confidence, lo=0.0, hi=1.0 - 1e-12, lo_open=True)
    lam, vec = np.linalg.eigh(0.5 * (cov + np.swapaxes(cov, -1, -2)))
    lam = np.maximum(lam, 0.0)
    major = vec[..., :, 1]
    angle = np.arctan2(major[..., 1], major[..., 0])
    angle = np.where(angle > np.pi / 2, angle - np.pi, np.where(angle <= -np.pi / 2, angle + np.pi, angle))
    c = ellipse_scale(confidence)
    return ConfidenceEllipse(
        center_m=centre,
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
    e = _validate.float_array("errors_m", errors_m, min_ndim=2, max_abs=_validate.MAX_LENGTH_M, unit="m")
    info = _validate.float_array("information", information, min_ndim=3, max_abs=_validate.MAX_INFORMATION)
    if info.shape[-2:] != (e.shape[-1], e.shape[-1]) or info.shape[:-2] != e.shape[:-1]:
        raise ArgumentError(
            f"errors_m and information: shapes {e.shape} and {info.shape} do not match "
            "((..., M, d) and (..., M, d, d))"
        )
    return np.einsum("...mi,...mij,...mj->...", e, info, e)


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
    x = _validate.float_array("samples", samples, allow_empty=True).ravel()
    _validate.integer("dof", dof, lo=1, hi=1_000_000)
    if x.size < 2:
        raise ArgumentError(f"samples: {x.size} given; at least 2 are needed")
    if np.any(x < 0.0):
        raise ArgumentError(f"samples: {x.min():g} is negative; NEES samples lie in [0, inf)")
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


LINEARIZATION_BAND = (0.5, 2.0)
"""Band of the cost-increase ratio inside which a linearized covariance is trusted."""


@dataclass(frozen=True, slots=True, kw_only=True)
class LinearizationCheck:
    """Result of :func:`range_linearization_check` for ``B`` estimates.

    Attributes
    ----------
    ratio : (B, 2 d) float
        Cost increase over its quadratic prediction at the ``2 d`` sigma points on the ellipsoid.
    statistic : (B,) float
        ``max |log ratio|`` (0 for a linear model); trusted when it is at most ``log 2``.
    trusted : (B,) bool
        Every ratio within :data:`LINEARIZATION_BAND`.
    confidence : float
        Probability mass of the ellipsoid the sigma points lie on.
    """

    ratio: FloatArray
    statistic: FloatArray
    trusted: BoolArray
    confidence: float

    def messages(self) -> list[str]:
        """One line per estimate: trusted, or how far the range model bends over the ellipsoid."""
        worst = np.exp(self.statistic)
        return [
            "ellipse trusted: the range model is linear over it"
            if ok
            else f"ellipse not trusted: over the {self.confidence:.0%} ellipsoid the cost rises"
            f" {w:.1f}x {'more' if r > 1 else 'less'} than the linearization predicts; collect more ranges"
            for ok, w, r in zip(
                self.trusted, worst, np.take_along_axis(self.ratio, _worst(self.ratio), 1)[:, 0], strict=True
            )
        ]


def _worst(ratio: FloatArray) -> IntArray:
    return np.argmax(np.abs(np.log(np.maximum(ratio, 1e-300))), axis=1)[:, None]


def range_linearization_check(
    estimate_m: ArrayLike,
    covariance_m2: ArrayLike,
    sensor_m: ArrayLike,
    ranges_m: ArrayLike,
    used: ArrayLike,
    sigma_range_m: float,
    prior_mean_m: ArrayLike,
    prior_cov_m2: ArrayLike,
    *,
    confidence: float = 0.95,
    band: tuple[float, float] = LINEARIZATION_BAND,
) -> LinearizationCheck:
    """Whether the linearized covariance of range estimates can be trusted: a check of the range model's
    linearization over the confidence ellipsoid.

    The MAP cost of ranges ``z_i`` from sensor positions ``s_i`` with prior ``N(p0, P0)`` is
    ``J(p) = 1/2 sum_i (z_i - |p - s_i|)^2 / sigma^2 + 1/2 (p - p0)^T P0^-1 (p - p0)``. The reported
    covariance ``P`` is the inverse of its Gauss-Newton Hessian ``Y = H^T H / sigma^2 + P0^-1`` at the
    estimate, i.e. it assumes ``J`` quadratic over the region the covariance describes. The check
    evaluates ``J`` at the ``2 d`` sigma points ``p +- c sqrt(lambda_j) v_j`` on the ``confidence``
    ellipsoid of ``P`` (``c^2`` the chi-square ``d``-dof quantile, 7.81 for 95 % in 3-D; ``lambda_j, v_j``
    the eigenpairs of ``P``) and compares the cost increase ``J(p + Delta) - J(p)`` with the quadratic
    prediction ``1/2 Delta^T Y Delta``. For a linear model the ratio is 1; where the ranges' geometry is
    still poor (few sites, nearly collinear, a mirror ambiguity) the true cost along the long axes is
    much flatter (ratio << 1: the estimate could be anywhere along a curved valley, a second minimum)
    or steeper than predicted, and the ellipse misstates the error. Trusted when every ratio lies in
    ``band`` (default ``[0.5, 2]``: the ellipse's size is right within a factor of ``sqrt 2``).

    Batched over ``B`` estimates with ``n`` ranges each (pad with ``used = False``).

    Parameters
    ----------
    estimate_m : (B, 3) float
    covariance_m2 : (B, 3, 3) float
        The reported covariances, square metres.
    sensor_m : (B, n, 3) float
    ranges_m, used : (B, n) float, bool
    sigma_range_m : float
        Range noise, metres.
    prior_mean_m : (B, 3) float
    prior_cov_m2 : (B, 3, 3) or (3, 3) float
    """
    if not 0.0 < confidence < 1.0:
        raise ConfigError(f"confidence must be in (0, 1), got {confidence}")
    if not 0.0 < band[0] < 1.0 < band[1]:
        raise ConfigError(f"band must hold 1 inside (0, inf), got {band}")
    p = np.asarray(estimate_m, dtype=float)
    cov = np.asarray(covariance_m2, dtype=float)
    sensors = np.asarray(sensor_m, dtype=float)
    z = np.asarray(ranges_m, dtype=float)
    w = np.asarray(used, dtype=bool) / sigma_range_m
    p0 = np.asarray(prior_mean_m, dtype=float)
    prior_info = np.linalg.inv(np.broadcast_to(np.asarray(prior_cov_m2, dtype=float), cov.shape))
    d = p.shape[-1]
    lam, vec = np.linalg.eigh(0.5 * (cov + np.swapaxes(cov, -1, -2)))
    c = float(np.sqrt(_stats().chi2.ppf(confidence, d)))
    axes = c * np.sqrt(np.maximum(lam, 0.0))[:, None, :] * vec  # (B, d, d): column j = c sqrt(l_j) v_j
    delta = np.concatenate([np.swapaxes(axes, 1, 2), -np.swapaxes(axes, 1, 2)], axis=1)  # (B, 2d, d)
    pts = np.concatenate([p[:, None, :], p[:, None, :] + delta], axis=1)  # (B, 1 + 2d, d)
    # |p + D - s|^2 = |p - s|^2 + 2 D.(p - s) + |D|^2: one (n, d) x (d, 2d) product per batch instead of
    # the (1 + 2d, n, d) differences.
    rel = p[:, None, :] - sensors  # (B, n, d)
    d0_sq = np.einsum("bni,bni->bn", rel, rel)
    cross = delta @ np.swapaxes(rel, 1, 2)  # (B, 2d, n)
    step_sq = np.einsum("bci,bci->bc", delta, delta)[:, :, None]
    d0 = np.sqrt(d0_sq)
    dist = np.concatenate(
        [d0[:, None, :], np.sqrt(np.maximum(d0_sq[:, None, :] + 2.0 * cross + step_sq, 0.0))], axis=1
    )  # (B, 1 + 2d, n)
    resid = (z[:, None, :] - dist) * w[:, None, :]
    dev = pts - p0[:, None, :]
    cost = 0.5 * np.sum(resid**2, axis=-1) + 0.5 * np.einsum("bci,bij,bcj->bc", dev, prior_info, dev)
    los = rel / np.maximum(d0[:, :, None], 1e-12)
    jac = los * w[..., None]
    info = np.swapaxes(jac, 1, 2) @ jac + prior_info
    predicted = 0.5 * np.einsum("bci,bij,bcj->bc", delta, info, delta)
    ratio = (cost[:, 1:] - cost[:, :1]) / np.maximum(predicted, 1e-300)
    statistic = np.max(np.abs(np.log(np.maximum(ratio, 1e-300))), axis=1)
    trusted = np.all((ratio >= band[0]) & (ratio <= band[1]), axis=1)
    return LinearizationCheck(ratio=ratio, statistic=statistic, trusted=trusted, confidence=confidence)
