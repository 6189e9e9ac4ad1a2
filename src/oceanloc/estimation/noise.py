"""Range-noise analysis on stationary segments (PLANS 2018 eq. 30, thesis eq. 6.1, journal VI-B).

With the vehicle held still, ``N`` ranges to a beacon give the maximum-likelihood range and noise
standard deviation

    r_hat = (1/N) sum r(n),     sigma_hat = sqrt( 1/(N-1) sum (r(n) - r_hat)^2 )       (30) / (6.1)

evaluated after each measurement ``i`` to show their convergence (the papers' Fig. 5 / 6.2). The total
range noise with GPS error is ``sigma_eps^2 = sigma_USBL^2 + sigma_GPS^2`` (journal Section VI-B, the GPS
error projected on the line of sight): 113 mm and 1 m give 1.006 m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray
from oceanloc.errors import DataError


@dataclass(frozen=True, slots=True, kw_only=True)
class RangeNoiseEstimate:
    """Running estimates of eq. (30) over one stationary set of ranges.

    Attributes
    ----------
    range_m : (N,) float
        Running mean after each measurement (``r_hat_i``).
    sigma_m : (N,) float
        Running standard deviation (``sigma_hat_i``; NaN for ``i = 1``).
    sigma_of_sigma_m : (N,) float
        Standard error of ``sigma_hat_i`` under Gaussian noise, ``sigma_hat / sqrt(2 (i - 1))``.
    """

    range_m: FloatArray
    sigma_m: FloatArray
    sigma_of_sigma_m: FloatArray

    @property
    def final_range_m(self) -> float:
        return float(self.range_m[-1])

    @property
    def final_sigma_m(self) -> float:
        return float(self.sigma_m[-1])


def running_range_noise(ranges_m: ArrayLike) -> RangeNoiseEstimate:
    """Eq. (30) / (6.1) after each of ``N`` stationary ranges, vectorized (Welford-free cumulative sums
    on ranges centred at their first value, which keeps the sums well conditioned)."""
    r = np.asarray(ranges_m, dtype=float)
    if r.ndim != 1 or r.size < 2:
        raise DataError("noise analysis needs at least two ranges")
    if not np.all(np.isfinite(r)):
        raise DataError("noise analysis: ranges contain NaN or infinite values")
    x = r - r[0]
    i = np.arange(1, r.size + 1, dtype=float)
    s1 = np.cumsum(x)
    s2 = np.cumsum(x * x)
    mean = s1 / i
    with np.errstate(invalid="ignore", divide="ignore"):
        var = np.where(i > 1, (s2 - i * mean * mean) / (i - 1), np.nan)
        sigma = np.sqrt(np.maximum(var, 0.0))
        sos = sigma / np.sqrt(2.0 * (i - 1))
    return RangeNoiseEstimate(range_m=mean + r[0], sigma_m=sigma, sigma_of_sigma_m=sos)


def stationary_mask(
    t_s: ArrayLike, pos_enu_m: ArrayLike, *, max_speed_mps: float = 0.3, window_s: float = 30.0
) -> BoolArray:
    """Epochs where the vehicle is stationary: the horizontal displacement over a centred window of
    ``window_s`` is below ``max_speed_mps * window_s`` (robust to metre-level GPS noise when the window is
    long enough)."""
    t = np.asarray(t_s, dtype=float)
    p = np.asarray(pos_enu_m, dtype=float)
    lo = np.searchsorted(t, t - window_s / 2)
    hi = np.clip(np.searchsorted(t, t + window_s / 2, side="right") - 1, 0, t.size - 1)
    disp = np.hypot(p[hi, 0] - p[lo, 0], p[hi, 1] - p[lo, 1])
    return disp <= max_speed_mps * window_s


def total_range_sigma_m(sigma_usbl_m: float, sigma_gps_m: float) -> float:
    """``sqrt(sigma_USBL^2 + sigma_GPS^2)`` (journal Section VI-B): 0.113 and 1.0 give 1.006 m."""
    return float(np.hypot(sigma_usbl_m, sigma_gps_m))
