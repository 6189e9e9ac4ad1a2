"""Realistic GPS (NMEA) and USBL (CSV) logs of a pier experiment like the journal's (Tables VI, VIII).

Two beacons 1 m below the surface at the published ENU positions, a manned boat manoeuvring near the
pier (first a stationary segment for the noise analysis, then a random wander), DGPS errors of about
1 m correlated in time (first-order Gauss-Markov, 60 s), GPS at 1 Hz, ranges at 0.67 Hz alternating
between beacons with 62 and 113 mm noise, a 0.2 m bias on beacon 1, dropouts, multipath outliers
(+5 to +30 m) and a few corrupt lines.

Beside the logs, ``truth.json`` holds the beacons' true positions (:class:`BeaconTruth`): ENU in the frame
every command uses by default (origin at the earliest GPS fix written, so ``localize logs``, ``survey``
and ``replay logs`` compare to it directly), latitude/longitude/height, the simulation's own origin and
the seed. :func:`read_truth` reads it back.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic, geodetic_to_enu
from oceanloc.io.nmea import format_gga, format_hdt, format_zda, read_nmea
from oceanloc.io.usbl import format_utc

PIER_ORIGIN = EnuOrigin(lat_deg=32.705, lon_deg=-117.236, h_m=-1.478)
"""The journal's ENU origin (Section VI-C)."""


MAX_LOG_DURATION_S = 7 * 86_400.0
"""Longest simulated log pair, seconds (a week: about 600 000 fixes, 400 000 ranges, 100 MB of text)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class PierLogSettings:
    """Settings of :func:`simulate_pier_logs` (defaults: the journal's experiment)."""

    beacons_enu_m: tuple[tuple[float, float, float], ...] = ((9.21, 1.68, -1.15), (2.79, 0.44, -1.15))
    sigma_range_m: tuple[float, ...] = (0.062, 0.113)
    bias_m: tuple[float, ...] = (0.2, 0.0)
    gps_sigma_m: float = 1.0
    gps_correlation_s: float = 60.0
    gps_rate_hz: float = 1.0
    range_rate_hz: float = 0.67
    duration_s: float = 1800.0
    stationary_s: float = 400.0
    speed_mps: float = 1.0
    wander_radius_m: float = 40.0
    dropout_fraction: float = 0.05
    outlier_fraction: float = 0.05
    outlier_range_m: tuple[float, float] = (5.0, 30.0)
    corrupt_lines: int = 5
    start_utc: dt.datetime = field(default_factory=lambda: dt.datetime(2018, 1, 4, 18, 0, tzinfo=dt.UTC))

    def __post_init__(self) -> None:
        if len(self.sigma_range_m) != len(self.beacons_enu_m) or len(self.bias_m) != len(self.beacons_enu_m):
            raise ConfigError("sigma_range_m and bias_m need one value per beacon")
        if not 0.0 <= self.outlier_fraction < 0.5 or not 0.0 <= self.dropout_fraction < 0.9:
            raise ConfigError("outlier_fraction must be in [0, 0.5) and dropout_fraction in [0, 0.9)")
        if not (math.isfinite(self.duration_s) and self.stationary_s < self.duration_s <= MAX_LOG_DURATION_S):
            raise ConfigError(
                f"duration {self.duration_s:g} s is not in ({self.stationary_s:g}, {MAX_LOG_DURATION_S:g}] s "
                "(longer than the stationary segment, at most a week of logs)"
            )
        if self.duration_s <= self.stationary_s or self.gps_rate_hz <= 0 or self.range_rate_hz <= 0:
            raise ConfigError("duration must exceed the stationary segment; rates must be positive")


@dataclass(frozen=True, slots=True, kw_only=True)
class BeaconTruth:
    """True beacon positions of a simulated log pair.

    Attributes
    ----------
    beacons : tuple of int
        Beacon ids (1, 2, ...), as in the range log.
    origin : EnuOrigin
        Origin of :attr:`enu_m`: the earliest GPS fix of the log (the default origin of every command).
    enu_m : (k, 3) float
        Positions in that frame, metres.
    geodetic : (k, 3) float
        Latitude, longitude (degrees) and ellipsoidal height (metres).
    simulation_origin : EnuOrigin or None
        The frame the simulation was set up in (the journal's pier origin).
    seed : int or None
    path : str or None
        The file it was read from.
    """

    beacons: tuple[int, ...]
    origin: EnuOrigin
    enu_m: FloatArray
    geodetic: FloatArray
    simulation_origin: EnuOrigin | None = None
    seed: int | None = None
    path: str | None = None

    def enu_in(self, origin: EnuOrigin) -> dict[int, FloatArray]:
        """The positions in the ENU frame of ``origin``, per beacon id, metres."""
        g = self.geodetic
        enu = geodetic_to_enu(g[:, 0], g[:, 1], g[:, 2], origin).reshape(-1, 3)
        return {b: enu[i] for i, b in enumerate(self.beacons)}

    def to_record(self) -> dict:
        """Plain JSON-ready data (what :func:`read_truth` reads)."""
        return {
            "kind": "oceanloc beacon truth",
            "origin": _origin_record(self.origin, "earliest GPS fix"),
            "simulation_origin": None
            if self.simulation_origin is None
            else _origin_record(self.simulation_origin, "simulation frame"),
            "seed": self.seed,
            "beacons": [
                {
                    "beacon": int(b),
                    "e_m": float(self.enu_m[i, 0]),
                    "n_m": float(self.enu_m[i, 1]),
                    "u_m": float(self.enu_m[i, 2]),
                    "lat_deg": float(self.geodetic[i, 0]),
                    "lon_deg": float(self.geodetic[i, 1]),
                    "h_m": float(self.geodetic[i, 2]),
                }
                for i, b in enumerate(self.beacons)
            ],
        }


def _origin_record(o: EnuOrigin, how: str) -> dict:
    return {"lat_deg": o.lat_deg, "lon_deg": o.lon_deg, "h_m": o.h_m, "source": how}


def read_truth(path: str | Path) -> BeaconTruth:
    """Read a ``truth.json`` written by ``oceanloc simulate logs`` (:meth:`BeaconTruth.to_record`).

    Raises
    ------
    DataError
        If the file cannot be read or is not such a file.
    """
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
        o = data["origin"]
        rows = data["beacons"]
        origin = EnuOrigin(lat_deg=float(o["lat_deg"]), lon_deg=float(o["lon_deg"]), h_m=float(o["h_m"]))
        beacons = tuple(int(r["beacon"]) for r in rows)
        geo = np.array([[r["lat_deg"], r["lon_deg"], r["h_m"]] for r in rows], dtype=float).reshape(-1, 3)
        enu = np.array([[r["e_m"], r["n_m"], r["u_m"]] for r in rows], dtype=float).reshape(-1, 3)
        so = data.get("simulation_origin")
        sim = None if so is None else EnuOrigin(lat_deg=so["lat_deg"], lon_deg=so["lon_deg"], h_m=so["h_m"])
    except OSError as exc:
        raise DataError(f"{p}: cannot read the truth file ({exc.strerror or exc})") from None
    except (ValueError, KeyError, TypeError) as exc:
        raise DataError(f"{p}: not a beacon truth file of oceanloc simulate logs ({exc!r})") from None
    if not beacons:
        raise DataError(f"{p}: the truth file lists no beacon")
    seed = data.get("seed")
    return BeaconTruth(
        beacons=beacons, origin=origin, enu_m=enu, geodetic=geo, simulation_origin=sim,
        seed=seed if isinstance(seed, int) else None, path=str(p),
    )  # fmt: skip


@dataclass(frozen=True, slots=True, kw_only=True)
class PierLogs:
    """What was written, with the truth for checks (:attr:`truth`, also written to ``truth.json``)."""

    nmea_path: Path
    ranges_path: Path
    truth_path: Path
    beacons_enu_m: FloatArray
    truth: BeaconTruth
    n_fixes: int
    n_ranges: int
    n_outliers: int
    n_corrupt: int

    def to_record(self) -> dict:
        """Plain JSON-ready data: the files written, their counts and the truth."""
        return {
            "gps": str(self.nmea_path),
            "ranges": str(self.ranges_path),
            "truth": str(self.truth_path),
            "fixes": self.n_fixes,
            "ranges_written": self.n_ranges,
            "outliers": self.n_outliers,
            "corrupt_lines": self.n_corrupt,
            "beacons": self.truth.to_record()["beacons"],
        }


def simulate_pier_logs(
    out_dir: Path,
    settings: PierLogSettings,
    rng: np.random.Generator,
    *,
    origin: EnuOrigin = PIER_ORIGIN,
    seed: int | None = None,
) -> PierLogs:
    """Write ``gps.nmea``, ``ranges.csv`` and ``truth.json`` into ``out_dir``; see the module docstring.

    ``origin`` places the experiment on the Earth (the journal's pier by default; the beacons' ENU
    positions of ``settings`` are in its frame); ``seed`` is recorded in the truth file.
    """
    s = settings
    beacons = np.asarray(s.beacons_enu_m, dtype=float)
    n_gps = int(s.duration_s * s.gps_rate_hz)
    t = np.arange(n_gps) / s.gps_rate_hz
    dt_s = 1.0 / s.gps_rate_hz
    # Boat: stationary near beacon 1, then a bounded random wander at speed_mps.
    pos = np.zeros((n_gps, 3))
    yaw = np.zeros(n_gps)
    start = beacons[0, :2] + np.array([0.5, -8.0])
    heading = rng.uniform(-np.pi, np.pi)
    p = start.copy()
    for k in range(n_gps):
        if t[k] >= s.stationary_s:
            heading += 0.15 * rng.standard_normal()
            centre = beacons[:, :2].mean(axis=0)
            if np.linalg.norm(p - centre) > s.wander_radius_m:
                heading = np.arctan2(*(centre - p)[::-1])
            p = p + s.speed_mps * dt_s * np.array([np.cos(heading), np.sin(heading)])
        pos[k, :2] = p
        yaw[k] = heading
    # HDT is a true heading: clockwise from north, where the yaw is counter-clockwise from east.
    true_heading_deg = np.mod(90.0 - np.degrees(yaw), 360.0)
    # Gauss-Markov DGPS error, stationary variance gps_sigma^2 per horizontal axis, half that vertically.
    phi = np.exp(-dt_s / s.gps_correlation_s)
    err = np.zeros((n_gps, 3))
    err[0] = rng.standard_normal(3) * s.gps_sigma_m
    drive = rng.standard_normal((n_gps, 3)) * s.gps_sigma_m * np.sqrt(1 - phi**2)
    for k in range(1, n_gps):
        err[k] = phi * err[k - 1] + drive[k]
    err[:, 2] *= 0.5
    geo = enu_to_geodetic(pos + err, origin)
    start_t = s.start_utc
    lines: list[str] = []
    for k in range(n_gps):
        stamp = start_t + dt.timedelta(seconds=float(t[k]))
        if k % 60 == 0:
            lines.append(format_zda(stamp))
        lines.append(format_gga(stamp, geo[k, 0], geo[k, 1], geo[k, 2]))
        lines.append(format_hdt(true_heading_deg[k]))
    # Ranges at range_rate_hz alternating beacons, from the true boat position.
    t_r = np.arange(0.0, s.duration_s - 1.0, 1.0 / s.range_rate_hz) + 0.37
    which = np.arange(t_r.size) % beacons.shape[0]
    boat = np.stack([np.interp(t_r, t, pos[:, j]) for j in range(3)], axis=1)
    true = np.linalg.norm(beacons[which] - boat, axis=1)
    sig = np.asarray(s.sigma_range_m)[which]
    z = true + np.asarray(s.bias_m)[which] + sig * rng.standard_normal(t_r.size)
    outlier = rng.random(t_r.size) < s.outlier_fraction
    z[outlier] += rng.uniform(*s.outlier_range_m, int(outlier.sum()))
    keep = rng.random(t_r.size) >= s.dropout_fraction
    csv = ["utc,beacon,range_m"]
    for k in np.flatnonzero(keep):
        csv.append(f"{format_utc(start_t.timestamp() + t_r[k])},{which[k] + 1},{z[k]:.3f}")
    # A few corrupt lines of each kind the readers must survive.
    corrupt = min(s.corrupt_lines, 5)
    bad_nmea = [
        "$GPGGA,1800",
        lines[5][:-2] + "00",
        "$GPGGA,180010.00,32xx.3000,N,11714.1600,W,2,09,0.9,0,M,0,M,,*00",
    ]
    bad_csv = [
        "2018-01-04T18:00:05.000Z,1,nan",
        "2018-01-04T18:00:06.000Z,1,-3.0",
        "2018-01-04T18:00:07.000Z,9,5.0",
    ]
    for j in range(corrupt):
        lines.insert(10 + 97 * j, bad_nmea[j % 3])
        csv.insert(10 + 53 * j, bad_csv[j % 3])
    out_dir.mkdir(parents=True, exist_ok=True)
    nmea_path = out_dir / "gps.nmea"
    ranges_path = out_dir / "ranges.csv"
    nmea_path.write_text("\r\n".join(lines) + "\r\n", encoding="ascii")
    ranges_path.write_text("\n".join(csv) + "\n", encoding="ascii")
    # the default frame of every command: origin at the earliest fix as read back (GPS error and the
    # NMEA rounding included), so the truth is in exactly the frame `localize logs` reports in
    fixes = read_nmea(nmea_path)
    first = EnuOrigin(
        lat_deg=float(fixes.lat_deg[0]), lon_deg=float(fixes.lon_deg[0]), h_m=float(fixes.h_m[0])
    )
    beacons_geo = enu_to_geodetic(beacons, origin).reshape(-1, 3)
    truth = BeaconTruth(
        beacons=tuple(range(1, beacons.shape[0] + 1)),
        origin=first,
        enu_m=geodetic_to_enu(beacons_geo[:, 0], beacons_geo[:, 1], beacons_geo[:, 2], first).reshape(-1, 3),
        geodetic=beacons_geo,
        simulation_origin=origin,
        seed=seed,
    )
    truth_path = out_dir / "truth.json"
    truth_path.write_text(json.dumps(truth.to_record(), indent=2) + "\n", encoding="utf-8")
    return PierLogs(
        nmea_path=nmea_path,
        ranges_path=ranges_path,
        truth_path=truth_path,
        truth=truth,
        beacons_enu_m=beacons,
        n_fixes=n_gps,
        n_ranges=int(keep.sum()),
        n_outliers=int((outlier & keep).sum()),
        n_corrupt=2 * corrupt,
    )
