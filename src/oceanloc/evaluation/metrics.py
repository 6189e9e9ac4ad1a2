"""Survey metrics of Garcia et al. (2019), Section V: RMSEE, NEES and the D-optimal value.

Shapes follow the Monte Carlo layout ``(runs R, epochs N, transponders M, ...)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError


def rmsee(errors_m: ArrayLike) -> FloatArray:
    """Root-mean-square estimation error over runs, eq. (45).

    Parameters
    ----------
    errors_m : (R, ..., 3) float
        Position errors ``p_T - p_hat`` (eq. 42).

    Returns
    -------
    (...) float
        ``sqrt(mean_c ||e_c||^2)``, metres (e.g. ``(N, M)`` per epoch and transponder).
    """
    err = np.asarray(errors_m, dtype=float)
    return np.sqrt(np.mean(np.sum(err * err, axis=-1), axis=0))


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


@dataclass(frozen=True, slots=True, kw_only=True)
class LogDetStats:
    """Mean and standard deviation over runs of ``log det Y_n`` per epoch.

    Attributes
    ----------
    mean, std : (N,) float
        Nats. ``std`` uses ``ddof=1``.
    runs : int
    """

    mean: FloatArray
    std: FloatArray
    runs: int

    @property
    def standard_error(self) -> FloatArray:
        """Monte Carlo standard error of the mean, ``std / sqrt(runs)``."""
        return self.std / np.sqrt(self.runs)


def log_det_stats(log_det: ArrayLike) -> LogDetStats:
    """Summarize ``log det Y_n`` samples of shape ``(R, N)`` over runs."""
    x = np.asarray(log_det, dtype=float)
    return LogDetStats(
        mean=x.mean(axis=0),
        std=x.std(axis=0, ddof=1) if x.shape[0] > 1 else np.zeros(x.shape[1:]),
        runs=x.shape[0],
    )


def _stats():
    """``scipy.stats``, imported on first use (it adds a second to the command line's start)."""
    from scipy import stats

    return stats
