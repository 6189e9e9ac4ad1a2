"""Beacon localization from aligned GPS + USBL range logs: robust MAP per beacon (eqs. 10-22).

Each beacon is one :class:`~oceanloc.estimation.map_gauss_newton.RangeProblem` solved in a batch. The
range noise is the journal's total ``sigma_eps`` (USBL noise and GPS error projected on the line of
sight, Section VI-B). Multipath returns arrive late (ranges too long by metres); the authors' rule
removes the largest normalized residual above ``outlier_threshold`` one at a time, re-solving after
each removal, and every exclusion is listed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import BoolArray, FloatArray
from oceanloc.errors import DataError
from oceanloc.estimation.map_gauss_newton import GaussianPrior, MapOptions, RangeProblem, solve_map
from oceanloc.io.usbl import AlignedRanges


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


def localize_beacons(
    aligned: AlignedRanges,
    *,
    sigma_range_m: float = 1.006,
    prior_sigma_enu_m: tuple[float, float, float] = (100.0, 100.0, 10.0),
    prior_depth_m: float = 2.0,
    outlier_threshold: float = 3.0,
    max_outlier_fraction: float = 0.25,
) -> list[BeaconEstimate]:
    """Localize every beacon in the log (see the module docstring).

    The prior mean is below the position of the shortest range to the beacon, ``prior_depth_m`` under
    the antenna's median height; the surface constraint keeps estimates below that height.
    """
    out = []
    surface = float(np.median(aligned.vehicle_enu_m[:, 2]))
    for beacon in np.unique(aligned.beacon):
        sel = aligned.select(int(beacon))
        sensors = aligned.vehicle_enu_m[sel]
        z = aligned.range_m[sel]
        if z.size < 4:
            raise DataError(f"beacon {beacon}: {z.size} ranges, need at least 4")
        i0 = int(np.argmin(z))
        mean = np.array([[sensors[i0, 0], sensors[i0, 1], surface - prior_depth_m]])
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
