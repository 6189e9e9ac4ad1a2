"""The AquaQuad energy budget (Dillard, Chapter II.C, Table 1) and the energy of drift/flight paths (IV.14).

Table 1 (one day)::

    load               power   time    energy
    base               5 W     24 h    120 Wh
    sensing & comms    10 W    6 h     60 Wh
    flight             200 W   1.1 h   220 Wh
    solar (income)     -       24 h    400 Wh   (mean of June 608 Wh and December 184 Wh)

Equation (IV.14): ``FlightEnergy = 200 W * FlightDist(nm) / 20 kn`` and
``SolarEnergy = 400 Wh / 24 h * DriftTime(h)``.

Units: the thesis converts metres to nautical miles with 2000 m (its code divides by ``2000 * 20``), which
makes direct flight on its scenario 49.5 Wh. oceanloc uses the international nautical mile (1852 m) by
default and the thesis' 2000 m only to reproduce its figures (:data:`THESIS_NAUTICAL_MILE_M`); every
output that prints energies says which one it used (:meth:`EnergyBudget.convention`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError
from oceanloc.units import NAUTICAL_MILE_M

THESIS_NAUTICAL_MILE_M = 2000.0
"""The thesis' conversion (``/2000/20`` in its listing): used only to reproduce its numbers."""

HOURS_PER_DAY = 24.0


@dataclass(frozen=True, slots=True, kw_only=True)
class EnergyBudget:
    """Power figures of Table 1 and the flight model of (IV.14).

    Attributes
    ----------
    base_load_w : float
        Always-on load (5 W).
    sensing_w : float
        Sensing and communications load while on (10 W).
    sensing_hours_per_day : float
        Hours per day the sensing load is on (6 h).
    flight_power_w : float
        Electrical power in flight (200 W: 2 kg at a figure of merit of 10 g/W).
    flight_speed_kn : float
        Cruise speed in flight (20 kn).
    solar_wh_per_day : float
        Mean solar income per day (400 Wh).
    max_flight_time_s : float
        Longest single flight (hop): 2 minutes in the thesis' DR-RRT*.
    nautical_mile_m : float
        Metres per nautical mile for the knot: 1852 by default, 2000 to reproduce the thesis.
    """

    base_load_w: float = 5.0
    sensing_w: float = 10.0
    sensing_hours_per_day: float = 6.0
    flight_power_w: float = 200.0
    flight_speed_kn: float = 20.0
    solar_wh_per_day: float = 400.0
    max_flight_time_s: float = 120.0
    nautical_mile_m: float = NAUTICAL_MILE_M

    def __post_init__(self) -> None:
        for name in ("flight_power_w", "flight_speed_kn", "max_flight_time_s", "nautical_mile_m"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"energy budget {name} must be positive, got {getattr(self, name)}")
        for name in ("base_load_w", "sensing_w", "solar_wh_per_day"):
            if getattr(self, name) < 0:
                raise ConfigError(f"energy budget {name} must not be negative, got {getattr(self, name)}")
        if not 0 <= self.sensing_hours_per_day <= HOURS_PER_DAY:
            raise ConfigError(
                f"sensing_hours_per_day must be within [0, 24], got {self.sensing_hours_per_day}"
            )

    @property
    def flight_speed_mps(self) -> float:
        """Flight speed in m/s under this budget's nautical mile."""
        return self.flight_speed_kn * self.nautical_mile_m / 3600.0

    @property
    def max_hop_m(self) -> float:
        """Longest single hop: ``max_flight_time * flight_speed`` (1333 m in the thesis, 1235 m at 1852 m)."""
        return self.max_flight_time_s * self.flight_speed_mps

    @property
    def flight_wh_per_m(self) -> float:
        """Flight energy per metre flown, Wh/m (IV.14)."""
        return self.flight_power_w / (self.flight_speed_mps * 3600.0)

    @property
    def solar_w(self) -> float:
        """Mean solar power, W (400 Wh / 24 h = 16.7 W)."""
        return self.solar_wh_per_day / HOURS_PER_DAY

    @property
    def convention(self) -> str:
        """One line naming the unit convention, for every output that prints energies."""
        which = "thesis convention" if self.nautical_mile_m == THESIS_NAUTICAL_MILE_M else "international"
        return (
            f"flight {self.flight_power_w:g} W at {self.flight_speed_kn:g} kn, "
            f"1 nmi = {self.nautical_mile_m:g} m ({which}): {self.flight_speed_mps:.3f} m/s, "
            f"{1000.0 * self.flight_wh_per_m:.3f} Wh/km"
        )

    def flight_energy_wh(self, distance_m: ArrayLike) -> FloatArray:
        """Flight energy of ``distance_m`` metres flown (IV.14), Wh; same shape as the input."""
        return np.asarray(distance_m, dtype=float) * self.flight_wh_per_m

    def flight_time_s(self, distance_m: ArrayLike) -> FloatArray:
        """Time to fly ``distance_m`` at cruise speed, seconds."""
        return np.asarray(distance_m, dtype=float) / self.flight_speed_mps

    def solar_energy_wh(self, duration_s: ArrayLike) -> FloatArray:
        """Mean solar income over ``duration_s`` seconds (IV.14), Wh."""
        return np.asarray(duration_s, dtype=float) / 3600.0 * self.solar_w

    def load_energy_wh(self, duration_s: ArrayLike) -> FloatArray:
        """Base and (duty-cycled) sensing loads over ``duration_s`` seconds, Wh."""
        mean_w = self.base_load_w + self.sensing_w * self.sensing_hours_per_day / HOURS_PER_DAY
        return np.asarray(duration_s, dtype=float) / 3600.0 * mean_w

    def direct_flight_wh(self, start_m: ArrayLike, goal_m: ArrayLike) -> FloatArray:
        """Baseline: fly the straight line from start to goal, Wh; ``start_m, goal_m : (..., 2)``."""
        d = np.linalg.norm(np.asarray(goal_m, dtype=float) - np.asarray(start_m, dtype=float), axis=-1)
        return self.flight_energy_wh(d)

    def table1(self) -> list[tuple[str, float, float, float]]:
        """Table 1 rows ``(load, power W, hours per day, Wh per day)``; solar power is its daily mean."""
        flight_hours = (self.solar_wh_per_day - self._daily_loads_wh()) / self.flight_power_w
        return [
            ("base", self.base_load_w, HOURS_PER_DAY, self.base_load_w * HOURS_PER_DAY),
            (
                "sensing & comms",
                self.sensing_w,
                self.sensing_hours_per_day,
                self.sensing_w * self.sensing_hours_per_day,
            ),
            ("flight", self.flight_power_w, flight_hours, self.flight_power_w * flight_hours),
            ("solar (income)", self.solar_w, HOURS_PER_DAY, self.solar_wh_per_day),
        ]

    def daily_flight_budget_wh(self) -> float:
        """Energy left for flight per day once the base and sensing loads are met (220 Wh in Table 1)."""
        return self.solar_wh_per_day - self._daily_loads_wh()

    def _daily_loads_wh(self) -> float:
        return self.base_load_w * HOURS_PER_DAY + self.sensing_w * self.sensing_hours_per_day


def thesis_budget() -> EnergyBudget:
    """Table 1 with the thesis' 2000 m nautical mile: direct flight on its scenario is 49.5 Wh."""
    return EnergyBudget(nautical_mile_m=THESIS_NAUTICAL_MILE_M)
