"""Survey metrics of Garcia et al. (2019), Section V: RMSEE, the D-optimal value and NEES consistency by
epoch (NEES itself and its chi-square check are in :mod:`oceanloc.estimation.consistency`).

Shapes follow the Monte Carlo layout ``(runs R, epochs N, transponders M, ...)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc import _validate
from oceanloc._typing import ArrayLike, FloatArray


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
    err = _validate.float_array("errors_m", errors_m, min_ndim=2, max_abs=_validate.MAX_LENGTH_M, unit="m")
    return np.sqrt(np.mean(np.sum(err * err, axis=-1), axis=0))


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


@dataclass(frozen=True, slots=True, kw_only=True)
class EpochConsistency:
    """NEES consistency per epoch over the Monte Carlo runs.

    A consistent estimator's NEES (eq. 44) follows ``chi2(dof)``: its mean is ``dof`` and a share
    ``1 - confidence`` of the runs lies above the ``confidence`` quantile.

    Attributes
    ----------
    mean_nees : (N,) float
        Mean NEES over runs at each epoch (dimensionless).
    fraction_above : (N,) float
        Share of runs whose NEES exceeds ``quantile`` at each epoch.
    dof : int
        Degrees of freedom (``3M``).
    confidence : float
        Quantile level (0.95).
    quantile : float
        ``chi2(dof).ppf(confidence)``.
    runs : int
    """

    mean_nees: FloatArray
    fraction_above: FloatArray
    dof: int
    confidence: float
    quantile: float
    runs: int

    @property
    def mean_band(self) -> tuple[float, float]:
        """``dof +- 3 sqrt(2 dof / runs)``: three Monte Carlo standard errors of the mean NEES."""
        half = 3.0 * np.sqrt(2.0 * self.dof / self.runs)
        return self.dof - half, self.dof + half

    def to_record(self) -> dict[str, object]:
        return {
            "dof": self.dof,
            "confidence": self.confidence,
            "chi2_quantile": float(self.quantile),
            "runs": self.runs,
            "mean_nees": [float(v) for v in self.mean_nees],
            "fraction_above_quantile": [float(v) for v in self.fraction_above],
        }


def epoch_consistency(nees_runs: ArrayLike, dof: int, confidence: float = 0.95) -> EpochConsistency:
    """Mean NEES and the share of runs above the ``chi2(dof)`` ``confidence`` quantile, per epoch.

    ``nees_runs`` is ``(R, N)``: runs by epochs.
    """
    from scipy import stats

    x = np.asarray(nees_runs, dtype=float)
    q = float(stats.chi2(dof).ppf(confidence))
    return EpochConsistency(
        mean_nees=x.mean(axis=0),
        fraction_above=(x > q).mean(axis=0),
        dof=int(dof),
        confidence=float(confidence),
        quantile=q,
        runs=int(x.shape[0]),
    )
