"""GPS + USBL range log pairs: read and align them, locate the beacons, measure the range noise.

One ENU convention for every command on logs (``localize logs``, ``localize noise``, ``replay logs``,
``survey``, ``simulate logs``): the origin is the one given (``--origin LAT,LON[,H]``), else the earliest
GPS fix of the log, as in the papers ("centered at the earliest collected GPS location", Garcia et al.
2019, Section VI-C). Every result carries the origin it used and how it was chosen.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.noise import (
    StationaryNoise,
    stationary_mask,
    stationary_range_noise,
    stationary_segments,
    total_range_sigma_m,
)
from oceanloc.estimation.range_logs import (
    MIN_BEACON_RANGES,
    BeaconEstimate,
    beacon_range_counts,
    localize_beacons,
)
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic
from oceanloc.io.nmea import read_nmea
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import AlignedRanges, align_ranges, format_utc, read_usbl
from oceanloc.sim.logs import read_truth

EARLIEST_FIX = "earliest fix"
"""How the default origin is chosen (printed in tables, written in records)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class LogPair:
    """A GPS log and a range log, read and aligned.

    Attributes
    ----------
    gps_path, ranges_path : str
    aligned : AlignedRanges
        Ranges with the GPS antenna position at their epochs, ENU from :attr:`origin`.
    qc : QcReport
        Lines skipped in both files, with reasons.
    origin_source : str
        ``"given"`` or :data:`EARLIEST_FIX`.
    max_gap_s : float
    """

    gps_path: str
    ranges_path: str
    aligned: AlignedRanges
    qc: QcReport
    origin_source: str
    max_gap_s: float

    @property
    def origin(self) -> EnuOrigin:
        return self.aligned.origin

    @property
    def inputs(self) -> list[str]:
        return [self.gps_path, self.ranges_path]

    def origin_record(self) -> dict:
        o = self.origin
        return {"lat_deg": o.lat_deg, "lon_deg": o.lon_deg, "h_m": o.h_m, "source": self.origin_source}


def read_log_pair(
    gps: str | Path,
    ranges: str | Path,
    *,
    origin: EnuOrigin | None = None,
    sound_speed_mps: float = 1500.0,
    max_gap_s: float = 2.0,
    beacons: Collection[int] | None = None,
) -> LogPair:
    """Read an NMEA GPS log and a USBL range CSV and align the ranges to the GPS track.

    With ``beacons`` (the expected beacon ids) a range to any other beacon is a QC line (unknown beacon).

    Raises
    ------
    ConfigError
        If no range has a GPS fix within ``max_gap_s``.
    """
    gps_log = read_nmea(gps)
    range_log = read_usbl(ranges, sound_speed_mps=sound_speed_mps, beacons=beacons)
    aligned = align_ranges(gps_log, range_log, origin=origin, max_gap_s=max_gap_s)
    if aligned.range_m.size == 0:
        raise ConfigError(f"{ranges}: no range has a GPS fix within {max_gap_s:g} s in {gps}")
    return LogPair(
        gps_path=str(gps),
        ranges_path=str(ranges),
        aligned=aligned,
        qc=gps_log.qc.merge(range_log.qc),
        origin_source="given" if origin is not None else EARLIEST_FIX,
        max_gap_s=max_gap_s,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class LogLocalization:
    """The beacons of a log pair located (``localize logs``).

    Attributes
    ----------
    logs : LogPair
    estimates : tuple of BeaconEstimate
    geodetic : (k, 3) float
        Each estimate as latitude, longitude (degrees), ellipsoidal height (metres).
    truth_enu_m : dict of int to (3,) float, or None
        True positions in this frame (from a truth file), when given.
    truth_path : str or None
    """

    logs: LogPair
    estimates: tuple[BeaconEstimate, ...]
    geodetic: np.ndarray
    truth_enu_m: dict[int, np.ndarray] | None = None
    truth_path: str | None = None
    not_localized: tuple[tuple[int, int], ...] = ()

    @property
    def inputs(self) -> list[str]:
        return self.logs.inputs + ([self.truth_path] if self.truth_path else [])

    def not_localized_lines(self) -> list[str]:
        """One line per beacon left out: ``beacon 9: 1 range, not localized (needs 4)``."""
        return [
            f"beacon {b}: {n} range{'' if n == 1 else 's'}, not localized (needs {MIN_BEACON_RANGES})"
            for b, n in self.not_localized
        ]

    def error_m(self, i: int) -> float | None:
        """Distance from estimate ``i`` to its true position, metres (None without truth)."""
        if self.truth_enu_m is None or self.estimates[i].beacon not in self.truth_enu_m:
            return None
        e = self.estimates[i]
        return float(np.linalg.norm(e.position_enu_m - self.truth_enu_m[e.beacon]))

    def to_record(self) -> dict:
        """Plain JSON-ready data: the origin, per beacon ENU, 1-sigma, latitude/longitude, counts."""
        beacons = []
        for i, e in enumerate(self.estimates):
            row = {
                "beacon": int(e.beacon),
                "enu_m": [float(v) for v in e.position_enu_m],
                "sigma_enu_m": [float(v) for v in np.sqrt(np.diag(e.covariance_m2))],
                "lat_deg": float(self.geodetic[i, 0]),
                "lon_deg": float(self.geodetic[i, 1]),
                "h_m": float(self.geodetic[i, 2]),
                "ranges_used": int(e.used.sum()),
                "ranges_excluded": int(e.n_excluded),
                "residual_rms_m": float(e.residual_rms_m),
            }
            if self.truth_enu_m is not None:
                truth = self.truth_enu_m.get(int(e.beacon))
                row["truth_enu_m"] = None if truth is None else [float(v) for v in truth]
                row["error_m"] = self.error_m(i)
            beacons.append(row)
        return {
            "origin": self.logs.origin_record(),
            "beacons": beacons,
            "qc": self.logs.qc.counts(),
            "dropped_no_gps": self.logs.aligned.dropped_no_gps,
            "not_localized": [{"beacon": b, "ranges": n} for b, n in self.not_localized],
            "truth_file": self.truth_path,
        }


def localize_log_files(
    gps: str | Path,
    ranges: str | Path,
    *,
    origin: EnuOrigin | None = None,
    truth: str | Path | None = None,
    sound_speed_mps: float = 1500.0,
    max_gap_s: float = 2.0,
    sigma_range_m: float = 1.006,
    sigma_gps_m: float = 1.0,
    gps_correlation_s: float | None = 60.0,
    beacons: Collection[int] | None = None,
) -> LogLocalization:
    """Locate every beacon of a GPS + range log pair (:func:`oceanloc.estimation.range_logs.
    localize_beacons`); with ``truth`` (a ``truth.json`` of ``simulate logs``) each error is measured.

    ``beacons`` names the expected beacons: ranges to any other are QC'd (unknown beacon). A beacon with
    fewer than :data:`MIN_BEACON_RANGES` ranges (a stray reply, or an expected beacon barely heard) is
    not localized but listed in :attr:`LogLocalization.not_localized`, and the others are solved.

    Raises
    ------
    DataError
        If no beacon has enough ranges.
    """
    known = None if truth is None else read_truth(truth)  # a bad truth file fails before the work
    logs = read_log_pair(
        gps, ranges, origin=origin, sound_speed_mps=sound_speed_mps, max_gap_s=max_gap_s, beacons=beacons
    )
    counts = beacon_range_counts(logs.aligned)
    counts.update({int(b): 0 for b in beacons or () if int(b) not in counts})
    short = tuple(sorted((b, n) for b, n in counts.items() if n < MIN_BEACON_RANGES))
    if len(short) == len(counts):
        listed = ", ".join(f"{b}: {n}" for b, n in short)
        raise DataError(
            f"{ranges}: no beacon has the {MIN_BEACON_RANGES} ranges with GPS it needs (ranges per beacon: "
            f"{listed})"
        )
    estimates = localize_beacons(
        logs.aligned,
        sigma_range_m=sigma_range_m,
        sigma_gps_m=sigma_gps_m,
        gps_correlation_s=gps_correlation_s,
        skip_short=True,
    )
    pos = np.array([e.position_enu_m for e in estimates]).reshape(-1, 3)
    geo = enu_to_geodetic(pos, logs.origin).reshape(-1, 3)
    truth_enu = None if known is None else known.enu_in(logs.origin)
    return LogLocalization(
        logs=logs,
        estimates=tuple(estimates),
        geodetic=geo,
        truth_enu_m=truth_enu,
        truth_path=None if truth is None else str(truth),
        not_localized=short,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class NoiseAnalysis:
    """Range noise of each beacon on the stationary segments of a log pair (``localize noise``).

    Attributes
    ----------
    logs : LogPair
    estimates : tuple of StationaryNoise
        Eq. (30) per beacon and segment.
    sigma_usbl_m : float
        The largest of them: the USBL part of the total range sigma, metres.
    sigma_gps_m : float
        GPS error projected on the line of sight, metres.
    sigma_total_m : float
        ``sqrt(sigma_usbl^2 + sigma_gps^2)`` (journal VI-B), metres.
    """

    logs: LogPair
    estimates: tuple[StationaryNoise, ...]
    sigma_usbl_m: float
    sigma_gps_m: float
    sigma_total_m: float

    @property
    def t0_unix_s(self) -> float:
        return float(self.logs.aligned.t_unix_s[0])

    def to_record(self) -> dict:
        """Plain JSON-ready data: per beacon and segment the noise estimate, then the total sigma."""
        return {
            "origin": self.logs.origin_record(),
            "beacons": [
                {
                    "beacon": int(e.beacon),
                    "segment": int(e.segment),
                    "t_start_utc": format_utc(e.t_start_s),
                    "t_end_utc": format_utc(e.t_end_s),
                    "stationary_ranges": int(e.n_ranges),
                    "outliers": int(e.n_outliers),
                    "range_m": float(e.running.final_range_m),
                    "sigma_m": float(e.sigma_m),
                    "sigma_se_m": float(e.sigma_se_m),
                }
                for e in self.estimates
            ],
            "sigma_usbl_m": self.sigma_usbl_m,
            "sigma_gps_m": self.sigma_gps_m,
            "sigma_total_m": self.sigma_total_m,
        }


def range_noise_files(
    gps: str | Path,
    ranges: str | Path,
    *,
    sound_speed_mps: float = 1500.0,
    sigma_gps_m: float = 1.0,
    max_speed_mps: float = 0.3,
    window_s: float = 30.0,
    min_duration_s: float = 120.0,
    max_gap_s: float = 2.0,
) -> NoiseAnalysis:
    """Range noise per beacon on the stationary segments (PLANS eq. 30) and the total range sigma.

    Raises
    ------
    ConfigError
        If a setting is out of range or no beacon has 10 or more ranges on a long enough segment.
    """
    if sigma_gps_m < 0.0 or max_speed_mps <= 0.0 or window_s <= 0.0:
        raise ConfigError("--sigma-gps must be >= 0, --max-speed and --window positive")
    logs = read_log_pair(gps, ranges, sound_speed_mps=sound_speed_mps, max_gap_s=max_gap_s)
    a = logs.aligned
    still = stationary_mask(a.t_unix_s, a.vehicle_enu_m, max_speed_mps=max_speed_mps, window_s=window_s)
    segments = stationary_segments(a.t_unix_s, still, min_duration_s=min_duration_s)
    estimates = stationary_range_noise(a.t_unix_s, a.beacon, a.range_m, segments)
    if not estimates:
        raise ConfigError(
            f"{ranges}: no beacon has 10 or more ranges on a stationary segment of "
            f"{min_duration_s:g} s or more"
        )
    sigma_usbl = max(e.sigma_m for e in estimates)
    return NoiseAnalysis(
        logs=logs,
        estimates=tuple(estimates),
        sigma_usbl_m=float(sigma_usbl),
        sigma_gps_m=float(sigma_gps_m),
        sigma_total_m=float(total_range_sigma_m(sigma_usbl, sigma_gps_m)),
    )
