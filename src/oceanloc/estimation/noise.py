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

from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
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


def stationary_segments(t_s: ArrayLike, stationary: ArrayLike, *, min_duration_s: float = 120.0) -> IntArray:
    """Label the contiguous stationary stretches that last at least ``min_duration_s``.

    Eq. (30) assumes one constant range, so each stretch is its own set: a boat hovering slowly at the
    edge of its area for a few seconds is not a stationary segment.

    Parameters
    ----------
    t_s : (n,) float
        Epochs in time order, seconds.
    stationary : (n,) bool
        :func:`stationary_mask` at those epochs.
    min_duration_s : float

    Returns
    -------
    (n,) int
        Segment index (0, 1, ...) of each epoch, -1 outside every kept segment.
    """
    t = np.asarray(t_s, dtype=float)
    still = np.asarray(stationary, dtype=bool)
    starts = np.flatnonzero(still & ~np.concatenate([[False], still[:-1]]))
    ends = np.flatnonzero(still & ~np.concatenate([still[1:], [False]]))
    labels = np.full(t.size, -1, dtype=np.int64)
    kept = 0
    for a, b in zip(starts, ends, strict=True):
        if t[b] - t[a] >= min_duration_s:
            labels[a : b + 1] = kept
            kept += 1
    return labels


@dataclass(frozen=True, slots=True, kw_only=True)
class StationaryNoise:
    """Eq. (30) for one beacon over the stationary epochs of a log.

    Attributes
    ----------
    beacon : int
    segment : int
        Index of the stationary segment (:func:`stationary_segments`).
    t_start_s, t_end_s : float
        Its first and last range epoch, seconds.
    running : RangeNoiseEstimate
        Running estimates over the kept stationary ranges, in time order.
    n_ranges : int
        Stationary ranges to the beacon (before outlier removal).
    n_outliers : int
        Ranges removed by the one-at-a-time 3-sigma rule (multipath returns arrive late by metres).
    """

    beacon: int
    segment: int
    t_start_s: float
    t_end_s: float
    running: RangeNoiseEstimate
    n_ranges: int
    n_outliers: int

    @property
    def sigma_m(self) -> float:
        return self.running.final_sigma_m

    @property
    def sigma_se_m(self) -> float:
        return float(self.running.sigma_of_sigma_m[-1])


def stationary_range_noise(
    t_s: ArrayLike,
    beacon: ArrayLike,
    range_m: ArrayLike,
    segment: ArrayLike,
    *,
    outlier_threshold: float = 3.0,
    min_ranges: int = 10,
) -> list[StationaryNoise]:
    """Eq. (30) per beacon and stationary segment, after removing outliers one at a time.

    A multipath return is metres long, so a plain standard deviation over a stationary set is dominated
    by the few that remain; the largest deviation above ``outlier_threshold`` standard deviations is
    removed and the statistics recomputed until none is left (the authors' rule, as in the estimators).

    Parameters
    ----------
    t_s, beacon, range_m : (n,) array
        Range epochs (s), beacon ids and ranges (m), in time order.
    segment : (n,) int
        Stationary segment of each range, -1 for none (:func:`stationary_segments`).
    outlier_threshold : float
    min_ranges : int
        Sets with fewer ranges are skipped.

    Returns
    -------
    list of StationaryNoise
        One per beacon and segment with enough ranges, by beacon id then segment.
    """
    t = np.asarray(t_s, dtype=float)
    ids = np.asarray(beacon)
    r = np.asarray(range_m, dtype=float)
    seg = np.asarray(segment)
    if not (t.shape == ids.shape == r.shape == seg.shape):
        raise DataError("noise analysis: times, beacons, ranges and segments differ in length")
    out = []
    for b, g in sorted({(int(b), int(g)) for b, g in zip(ids[seg >= 0], seg[seg >= 0], strict=True)}):
        sel = np.flatnonzero((seg == g) & (ids == b))
        sel = sel[np.argsort(t[sel], kind="stable")]
        if sel.size < min_ranges:
            continue
        keep = np.ones(sel.size, dtype=bool)
        while keep.sum() > min_ranges:
            vals = r[sel][keep]
            dev = np.abs(r[sel] - vals.mean())
            dev[~keep] = -1.0
            worst = int(np.argmax(dev))
            if dev[worst] <= outlier_threshold * vals.std(ddof=1):
                break
            keep[worst] = False
        out.append(
            StationaryNoise(
                beacon=b,
                segment=g,
                t_start_s=float(t[sel[0]]),
                t_end_s=float(t[sel[-1]]),
                running=running_range_noise(r[sel][keep]),
                n_ranges=int(sel.size),
                n_outliers=int((~keep).sum()),
            )
        )
    return out
