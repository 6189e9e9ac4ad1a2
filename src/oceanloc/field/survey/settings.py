"""Settings of a field survey kept in a journal: planner, vehicle, sensor, frame, beacons and prior.

``oceanloc survey start`` validates them once and stores them in the journal's ``meta`` table
(:meth:`JournalSettings.to_meta`, one JSON value per key, so ``sqlite3 survey.db 'select * from meta'``
shows them); every later command reads them back (:meth:`JournalSettings.from_meta`) so that the
estimates and the next waypoint are a pure function of the journal.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from oceanloc.config.survey import PlannerSettings
from oceanloc.errors import ConfigError, DataError
from oceanloc.geo.enu import EnuOrigin
from oceanloc.planning.site_planners import SITE_PLANNER_KINDS
from oceanloc.units import DEG


@dataclass(frozen=True, slots=True, kw_only=True)
class JournalSettings:
    """A field survey's settings (defaults: the journal's pier experiment, Section VI).

    Attributes
    ----------
    planner : PlannerSettings
        Planner kind, look-ahead steps ``k`` and reach ``d_max`` (metres).
    max_yaw_rate_rad_s : float
        ``w_max`` of the yaw-rate planners, rad/s.
    speed_mps : float
        Vehicle speed assumed by the yaw-rate planners, m/s.
    period_s : float
        Time between planned measurement sites, s.
    sigma_range_m : float
        Total range sigma (USBL and GPS projected on the line of sight), metres.
    origin : EnuOrigin or None
        ENU origin; None: the earliest fix in the journal (as in the papers).
    beacons : tuple of int
        Beacon ids of the survey; ranges to others are rejected. Empty: any id is accepted.
    prior_sigma_enu_m : (3,) float
        Prior 1-sigma per axis around the point below the shortest range, metres.
    prior_depth_m : float
        Prior depth below the antenna's median height, metres.
    drops : tuple of (beacon, lat_deg, lon_deg, depth_m)
        Known drop positions: the prior mean of those beacons (``depth_m`` below the antenna's median
        height), with the spread ``prior_sigma_enu_m``; the others get the point below their shortest
        range.
    heading_deg : float or None
        Vehicle true heading at the start (degrees clockwise from north), used until the journal holds
        an HDT heading or two distinct fixes.
    sound_speed_mps : float
        Sound speed for travel-time columns of range files, m/s.
    max_gap_s : float
        Largest GPS gap a range is interpolated across, seconds.
    sigma_gps_m : float or None
        The GPS part of ``sigma_range_m`` (horizontal, per axis), metres; below it. The pier journal's
        differential GPS: 1 m; an RTK receiver: a few centimetres. None: 1 m where ``sigma_range_m`` is
        above it, else 0 (see :attr:`gps_sigma_m`).
    gps_correlation_s : float or None
        Time constant of the GPS error (Gauss-Markov), seconds; None treats it as white.
    """

    planner: PlannerSettings = dataclasses.field(default_factory=lambda: PlannerSettings(kind="greedy"))
    max_yaw_rate_rad_s: float = 30.0 * DEG
    speed_mps: float = 1.0
    period_s: float = 5.0
    sigma_range_m: float = 1.006
    origin: EnuOrigin | None = None
    beacons: tuple[int, ...] = ()
    prior_sigma_enu_m: tuple[float, float, float] = (100.0, 100.0, 10.0)
    prior_depth_m: float = 2.0
    drops: tuple[tuple[int, float, float, float], ...] = ()
    heading_deg: float | None = None
    sound_speed_mps: float = 1500.0
    max_gap_s: float = 2.0
    sigma_gps_m: float | None = None
    gps_correlation_s: float | None = 60.0

    def __post_init__(self) -> None:
        positive = ("max_yaw_rate_rad_s", "speed_mps", "period_s", "sigma_range_m", "max_gap_s")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"survey setting {name} must be a positive number, got {value}")
        gps = self.sigma_gps_m
        if gps is not None and not (math.isfinite(gps) and 0.0 <= gps < self.sigma_range_m):
            raise ConfigError(
                f"survey setting sigma_gps_m ({gps} m) must be 0 or more and below sigma_range_m "
                f"({self.sigma_range_m} m), the total range sigma it is part of"
            )
        if self.gps_correlation_s is not None and not (
            math.isfinite(self.gps_correlation_s) and self.gps_correlation_s > 0.0
        ):
            raise ConfigError(
                "survey setting gps_correlation_s must be a positive number of seconds, "
                f"got {self.gps_correlation_s}"
            )
        if len(self.prior_sigma_enu_m) != 3 or not all(
            math.isfinite(s) and s > 0 for s in self.prior_sigma_enu_m
        ):
            raise ConfigError(
                f"survey setting prior_sigma_enu_m needs 3 positive values, got {self.prior_sigma_enu_m}"
            )
        for drop in self.drops:
            b, lat, lon, depth = drop
            if self.beacons and b not in self.beacons:
                raise ConfigError(f"survey setting drops: beacon {b} is not one of the survey's beacons")
            if not (
                -90.0 <= lat <= 90.0 and -180.0 <= lon <= 360.0 and math.isfinite(depth) and depth >= 0.0
            ):
                raise ConfigError(
                    f"survey setting drops: beacon {b} at {lat}, {lon}, depth {depth}: latitude in "
                    "[-90, 90], longitude in [-180, 360] and depth >= 0 m required"
                )
        if len({d[0] for d in self.drops}) != len(self.drops):
            raise ConfigError("survey setting drops: one drop position per beacon")
        if not (math.isfinite(self.prior_depth_m) and self.prior_depth_m >= 0.0):
            raise ConfigError(f"survey setting prior_depth_m must be >= 0, got {self.prior_depth_m}")
        if self.heading_deg is not None and not (
            math.isfinite(self.heading_deg) and -360.0 <= self.heading_deg <= 360.0
        ):
            raise ConfigError(f"survey setting heading_deg must be in [-360, 360], got {self.heading_deg}")
        if not 1300.0 <= self.sound_speed_mps <= 1700.0:
            raise ConfigError(
                f"survey setting sound_speed_mps {self.sound_speed_mps} is outside [1300, 1700]"
            )
        if len(set(self.beacons)) != len(self.beacons) or any(b < 0 for b in self.beacons):
            raise ConfigError(f"survey setting beacons must be distinct non-negative ids, got {self.beacons}")

    @property
    def gps_sigma_m(self) -> float:
        """The GPS part of the range sigma in use, metres (``sigma_gps_m`` or its default)."""
        if self.sigma_gps_m is not None:
            return self.sigma_gps_m
        return 1.0 if self.sigma_range_m > 1.0 else 0.0

    def to_meta(self) -> dict[str, str]:
        """The settings as journal meta entries (JSON values; angles in degrees)."""
        o = self.origin
        values: dict[str, Any] = {
            "planner": self.planner.kind,
            "horizon": self.planner.horizon,
            "max_distance_m": self.planner.max_distance_m,
            "max_yaw_rate_deg_s": self.max_yaw_rate_rad_s / DEG,
            "speed_mps": self.speed_mps,
            "period_s": self.period_s,
            "sigma_range_m": self.sigma_range_m,
            "origin_lat_lon_h": None if o is None else [o.lat_deg, o.lon_deg, o.h_m],
            "beacons": list(self.beacons),
            "prior_sigma_enu_m": list(self.prior_sigma_enu_m),
            "prior_depth_m": self.prior_depth_m,
            "drops": [list(d) for d in self.drops],
            "heading_deg": self.heading_deg,
            "sound_speed_mps": self.sound_speed_mps,
            "max_gap_s": self.max_gap_s,
            "sigma_gps_m": self.sigma_gps_m,
            "gps_correlation_s": self.gps_correlation_s,
        }
        return {k: json.dumps(v) for k, v in values.items()}

    @staticmethod
    def from_meta(meta: Mapping[str, str], source: str = "journal") -> JournalSettings:
        """Read the settings back; a missing or malformed entry is a :class:`DataError` naming it."""

        def get(key: str) -> Any:
            if key not in meta:
                raise DataError(f"{source}: survey setting {key!r} missing from the journal")
            try:
                return json.loads(meta[key])
            except json.JSONDecodeError:
                raise DataError(
                    f"{source}: survey setting {key!r} is not valid JSON: {meta[key]!r}"
                ) from None

        try:
            kind = get("planner")
            if kind not in SITE_PLANNER_KINDS:
                raise DataError(f"{source}: survey setting 'planner' is {kind!r}")
            origin = get("origin_lat_lon_h")
            return JournalSettings(
                planner=PlannerSettings(
                    kind=kind, horizon=int(get("horizon")), max_distance_m=float(get("max_distance_m"))
                ),
                max_yaw_rate_rad_s=float(get("max_yaw_rate_deg_s")) * DEG,
                speed_mps=float(get("speed_mps")),
                period_s=float(get("period_s")),
                sigma_range_m=float(get("sigma_range_m")),
                origin=None
                if origin is None
                else EnuOrigin(lat_deg=float(origin[0]), lon_deg=float(origin[1]), h_m=float(origin[2])),
                beacons=tuple(int(b) for b in get("beacons")),
                prior_sigma_enu_m=tuple(float(s) for s in get("prior_sigma_enu_m")),  # type: ignore[arg-type]
                prior_depth_m=float(get("prior_depth_m")),
                drops=tuple(
                    (int(d[0]), float(d[1]), float(d[2]), float(d[3]))
                    for d in (json.loads(meta["drops"]) if "drops" in meta else [])
                ),
                heading_deg=None if get("heading_deg") is None else float(get("heading_deg")),
                sound_speed_mps=float(get("sound_speed_mps")),
                max_gap_s=float(get("max_gap_s")),
                **_gps_settings(meta, get),
            )
        except (TypeError, ValueError, IndexError) as exc:
            if isinstance(exc, DataError):
                raise
            raise DataError(f"{source}: malformed survey settings ({exc})") from None


def _gps_settings(meta: Mapping[str, str], get: Any) -> dict[str, Any]:
    """The GPS error settings; a journal started before they existed keeps the defaults."""
    if "sigma_gps_m" in meta:
        corr = get("gps_correlation_s")
        gps = get("sigma_gps_m")
        return {
            "sigma_gps_m": None if gps is None else float(gps),
            "gps_correlation_s": None if corr is None else float(corr),
        }
    return {}
