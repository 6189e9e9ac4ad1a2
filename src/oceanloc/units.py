"""Physical constants and unit conversions. Radians inside the package; degrees only at the edges."""

from __future__ import annotations

import math

NAUTICAL_MILE_M: float = 1852.0
"""International nautical mile in metres."""

KNOT_MPS: float = NAUTICAL_MILE_M / 3600.0
"""One knot in metres per second."""

DEG: float = math.pi / 180.0
"""One degree in radians: ``30 * DEG`` is 30 degrees in radians."""

GRAVITY_MPS2: float = 9.80665
"""Standard gravity."""


def deg_to_rad(value_deg: float) -> float:
    """Degrees to radians."""
    return value_deg * DEG


def rad_to_deg(value_rad: float) -> float:
    """Radians to degrees."""
    return value_rad / DEG


def kn_to_mps(speed_kn: float) -> float:
    """Knots to metres per second."""
    return speed_kn * KNOT_MPS


def mps_to_kn(speed_mps: float) -> float:
    """Metres per second to knots."""
    return speed_mps / KNOT_MPS
