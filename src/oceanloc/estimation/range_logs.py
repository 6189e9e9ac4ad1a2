"""Beacon localization from aligned GPS + USBL range logs: robust MAP per beacon (eqs. 10-22).

Each beacon is one MAP problem. The range noise is the journal's total ``sigma_eps`` (USBL noise and
GPS error projected on the line of sight, Section VI-B, eqs. 46-52). Multipath returns arrive late
(ranges too long by metres); the authors' rule removes the largest normalized residual above
``outlier_threshold`` one at a time, re-solving after each removal, and every exclusion is listed.

The journal treats the GPS part ``q(n) = h(n) dp_V(n)`` as white. A differential GPS error is not: it
wanders over tens of seconds to minutes, so ranges a few seconds apart share it, and the white model's
covariance is several times too small (NEES in the tens to hundreds on the simulated pier logs, whose
DGPS error is Gauss-Markov with a 60 s time constant). With ``gps_correlation_s`` the GPS error is a
Gauss-Markov process, ``Cov(q_i, q_j) = h_i D h_j^T exp(-|t_i - t_j| / tau)``, and the final estimate
is the generalized least-squares MAP solution with that full covariance (whitened by its Cholesky
factor), its covariance consistent; outliers are still found under the white model first.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.map_gauss_newton import GaussianPrior, MapOptions, RangeProblem, solve_map
from oceanloc.io.usbl import AlignedRanges
from oceanloc.models.measurements import range_jacobian, range_m


@dataclass(frozen=True, slots=True, kw_only=True)
class BeaconEstimate:
    """One beacon's estimate.

    Attributes
    ----------
    beacon : int
    position_enu_m : (3,) float
    covariance_m2 : (3, 3) float
    used : (m,) bool
        Over that beacon's ranges, in log order.
    n_excluded : int
    residual_rms_m : float
    """

    beacon: int
    position_enu_m: FloatArray
    covariance_m2: FloatArray
    used: BoolArray
    n_excluded: int
    residual_rms_m: float


@dataclass(frozen=True, slots=True)
class CorrelatedRangeProblem:
    """Ranges to one position with white sensor noise plus a Gauss-Markov GPS error (module docstring).

    Attributes
    ----------
    sensor_m : (m, 3) float
        Vehicle positions of the ranges used, metres.
    ranges_m : (m,) float
    chol : (m, m) float
        Lower Cholesky factor of their covariance, built at a linearization point by :meth:`at`.
    """

    sensor_m: FloatArray
    ranges_m: FloatArray
    chol: FloatArray

    @classmethod
    def at(
        cls,
        point_m: FloatArray,
        sensor_m: FloatArray,
        ranges_m: FloatArray,
        t_s: FloatArray,
        used: BoolArray,
        *,
        sigma_white_m: float,
        sigma_gps_enu_m: FloatArray,
        correlation_s: float,
    ) -> CorrelatedRangeProblem:
        """The used ranges, with their covariance built at the lines of sight from ``point_m`` (3,).

        ``sensor_m (n, 3)``, ``ranges_m (n,)``, ``t_s (n,)`` (seconds) and ``used (n,)``; white noise
        ``sigma_white_m``, GPS sigma per axis ``sigma_gps_enu_m (3,)`` with time constant ``correlation_s``.
        """
        sensors = sensor_m[used]
        h = range_jacobian(point_m, sensors)
        t = t_s[used]
        cov = (
            (h * np.square(sigma_gps_enu_m)) @ h.T * np.exp(-np.abs(t[:, None] - t[None, :]) / correlation_s)
        )
        cov[np.diag_indices_from(cov)] += sigma_white_m**2
        return cls(sensors, ranges_m[used], np.linalg.cholesky(cov))

    @property
    def batch_size(self) -> int:
        return 1

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        from scipy.linalg import solve_triangular

        resid = self.ranges_m - range_m(x[:, None, :], self.sensor_m)[0]
        jac = range_jacobian(x[:, None, :], self.sensor_m)[0]
        w_resid = solve_triangular(self.chol, resid, lower=True)
        w_jac = solve_triangular(self.chol, jac, lower=True)
        return w_resid[None, :], w_jac[None, :, :]


def prior_mean(
    beacon: int,
    sensors_m: FloatArray,
    ranges_m: FloatArray,
    surface_m: float,
    prior_depth_m: float,
    known_enu_m: Mapping[int, FloatArray] | None = None,
) -> FloatArray:
    """A beacon's prior mean (3,), metres: its known drop position if given, else the point
    ``prior_depth_m`` below the surface ``surface_m`` under the sensor of the shortest range."""
    if known_enu_m is not None and beacon in known_enu_m:
        return np.asarray(known_enu_m[beacon], dtype=float).reshape(3).copy()
    i0 = int(np.argmin(ranges_m))
    return np.array([sensors_m[i0, 0], sensors_m[i0, 1], surface_m - prior_depth_m])


MIN_BEACON_RANGES = 4
"""Ranges a beacon needs to be localized (three position coordinates, one redundancy)."""


def beacon_range_counts(aligned: AlignedRanges) -> dict[int, int]:
    """Per beacon of the log, its number of aligned ranges."""
    beacons, counts = np.unique(aligned.beacon, return_counts=True)
    return {int(b): int(c) for b, c in zip(beacons, counts, strict=True)}


def localize_beacons(
    aligned: AlignedRanges,
    *,
    sigma_range_m: float = 1.006,
    prior_sigma_enu_m: tuple[float, float, float] = (100.0, 100.0, 10.0),
    prior_depth_m: float = 2.0,
    outlier_threshold: float = 3.0,
    max_outlier_fraction: float = 0.25,
    sigma_gps_m: float = 1.0,
    gps_correlation_s: float | None = 60.0,
    skip_short: bool = False,
    prior_means_enu_m: Mapping[int, FloatArray] | None = None,
) -> list[BeaconEstimate]:
    """Localize every beacon in the log (see the module docstring).

    The prior mean is below the position of the shortest range to the beacon, ``prior_depth_m`` under
    the antenna's median height; the surface constraint keeps estimates below that height.

    Parameters
    ----------
    aligned : AlignedRanges
    sigma_range_m : float
        Total range noise ``sigma_eps`` (journal VI-B: 1.006 m), metres.
    sigma_gps_m : float
        The GPS part of it (horizontal, per axis; half of it vertically), metres; the rest,
        ``sqrt(sigma_eps^2 - sigma_gps^2)``, is white.
    gps_correlation_s : float or None
        Time constant of the GPS error; None treats it as white (the journal's model).
    skip_short : bool
        Leave out a beacon with fewer than :data:`MIN_BEACON_RANGES` ranges (else it is a
        :class:`DataError`); :func:`beacon_range_counts` says which.
    prior_means_enu_m : mapping of beacon id to (3,) float, optional
        Prior means (ENU metres) for the beacons whose drop position is known; the others get the point
        below their shortest range (:func:`prior_mean`).
    """
    if gps_correlation_s is not None:
        if gps_correlation_s <= 0.0:
            raise ConfigError(f"gps_correlation_s must be positive, got {gps_correlation_s}")
        if not 0.0 <= sigma_gps_m < sigma_range_m:
            raise ConfigError(
                f"sigma_gps_m ({sigma_gps_m} m) must be non-negative and below"
                f" sigma_range_m ({sigma_range_m} m)"
            )
    out = []
    surface = float(np.median(aligned.vehicle_enu_m[:, 2]))
    for beacon in np.unique(aligned.beacon):
        sel = aligned.select(int(beacon))
        sensors = aligned.vehicle_enu_m[sel]
        z = aligned.range_m[sel]
        if z.size < MIN_BEACON_RANGES and skip_short:
            continue
        if z.size < MIN_BEACON_RANGES:
            raise DataError(f"beacon {beacon}: {z.size} ranges, need at least 4")
        mean = prior_mean(int(beacon), sensors, z, surface, prior_depth_m, prior_means_enu_m)[None]
        prior = GaussianPrior(mean=mean, cov=np.diag(np.square(prior_sigma_enu_m)))
        opts = MapOptions(surface_z_m=surface)
        used = np.ones(z.size, dtype=bool)
        x = mean
        for _ in range(int(max_outlier_fraction * z.size) + 1):
            problem = RangeProblem.build(sensors[None], z[None], sigma_range_m, used[None])
            res = solve_map(problem, prior, opts, initial=x)
            x = res.estimate
            resid = z - np.linalg.norm(sensors - x[0], axis=1)
            scale = max(np.sqrt(np.mean(resid[used] ** 2)), sigma_range_m)
            normalized = np.where(used, np.abs(resid) / scale, 0.0)
            worst = int(np.argmax(normalized))
            if normalized[worst] <= outlier_threshold:
                break
            used[worst] = False
        if gps_correlation_s is not None:
            for _ in range(2):
                problem = CorrelatedRangeProblem.at(
                    x[0],
                    sensors,
                    z,
                    aligned.t_unix_s[sel] - aligned.t_unix_s[0],
                    used,
                    sigma_white_m=float(np.sqrt(sigma_range_m**2 - sigma_gps_m**2)),
                    sigma_gps_enu_m=np.array([1.0, 1.0, 0.5]) * sigma_gps_m,
                    correlation_s=gps_correlation_s,
                )
                res = solve_map(problem, prior, opts, initial=x)
                x = res.estimate
            resid = z - np.linalg.norm(sensors - x[0], axis=1)
        out.append(
            BeaconEstimate(
                beacon=int(beacon),
                position_enu_m=x[0].copy(),
                covariance_m2=res.covariance[0],
                used=used,
                n_excluded=int((~used).sum()),
                residual_rms_m=float(np.sqrt(np.mean(resid[used] ** 2))),
            )
        )
    return out
