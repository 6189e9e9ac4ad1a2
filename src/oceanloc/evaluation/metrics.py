"""Survey metrics of Garcia et al. (2019), Section V: RMSEE and the D-optimal value (NEES and its
chi-square check are in :mod:`oceanloc.estimation.consistency`).

Shapes follow the Monte Carlo layout ``(runs R, epochs N, transponders M, ...)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
    err = np.asarray(errors_m, dtype=float)
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
