"""Secular motion of the seafloor: plate-model site velocities, to compare surveys made months apart.

A seafloor transponder moves with its tectonic plate, several centimetres a year in a global (ITRF)
frame, as much as GNSS-Acoustic surveys disagree. Positions surveyed at different epochs are therefore
compared at one reference epoch, ``x_ref = x_i - v (t_i - t_ref)``, with ``v`` from a plate-motion model
(or one the user knows, e.g. from a nearby GNSS station). The model here is rigid-plate rotation,
``v = omega x r`` at the site's Earth-centred position ``r``, rotated to local east-north-up through
pymap3d; the rotation poles are those of the ITRF2014 plate-motion model (Altamimi et al. 2017,
J. Geophys. Res. 122, Table 1) for the plates that meet off California, where the packaged La Jolla
surveys are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymap3d

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError

MAS_PER_YEAR_RAD_S: float = np.pi / (180.0 * 3600.0e3) / (365.25 * 86400.0)
"""One milliarcsecond per (Julian) year, in radians per second."""

SECONDS_PER_YEAR: float = 365.25 * 86400.0
"""A Julian year, seconds (velocities are quoted in mm/yr)."""

ITRF2014_POLES_MAS_YR: dict[str, tuple[float, float, float]] = {
    "PCFC": (-0.409, 1.047, -2.169),
    "NOAM": (0.024, -0.694, -0.063),
}
"""Cartesian rotation rates ``(omega_x, omega_y, omega_z)`` of the ITRF2014 plate-motion model, mas/yr,
keyed by the model's plate code (Pacific, North America)."""

PLATE_MODEL_SIGMA_MPS: float = 5e-3 / SECONDS_PER_YEAR
"""1-sigma per horizontal axis given to a plate-model velocity at a site in a plate-boundary zone
(5 mm/yr: sites near the coast of southern California move within a few mm/yr of the rigid Pacific
plate; the model's own fit to stable-plate sites is a fraction of a mm/yr)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class SiteVelocity:
    """A secular site velocity and its uncertainty.

    Attributes
    ----------
    velocity_enu_mps : (3,) float
        East, north, up velocity, metres per second.
    sigma_enu_mps : (3,) float
        Its 1-sigma per axis, metres per second.
    source : str
        Where it comes from (``"ITRF2014 PCFC"``, ``"given"``).
    """

    velocity_enu_mps: FloatArray
    sigma_enu_mps: FloatArray
    source: str

    @property
    def velocity_enu_mm_yr(self) -> FloatArray:
        """The velocity in millimetres per year, (3,)."""
        return self.velocity_enu_mps * SECONDS_PER_YEAR * 1e3


def plate_velocity_enu_mps(lat_deg: float, lon_deg: float, plate: str) -> FloatArray:
    """Velocity of a point on a rigid plate, ``omega x r`` in local east-north-up (up is zero), m/s,
    shape (3,).

    Parameters
    ----------
    lat_deg, lon_deg : float
        Geodetic latitude and longitude of the site, degrees (height does not matter at this precision).
    plate : str
        A key of :data:`ITRF2014_POLES_MAS_YR`.
    """
    if plate not in ITRF2014_POLES_MAS_YR:
        raise ConfigError(f"unknown plate {plate!r}; known: {', '.join(ITRF2014_POLES_MAS_YR)}")
    omega = np.array(ITRF2014_POLES_MAS_YR[plate]) * MAS_PER_YEAR_RAD_S
    r = np.array(pymap3d.geodetic2ecef(lat_deg, lon_deg, 0.0))
    v = np.cross(omega, r)
    east, north, _ = pymap3d.ecef2enuv(v[0], v[1], v[2], lat_deg, lon_deg)
    # omega x r is tangent to the sphere; its 1e-3 part along the ellipsoid's normal is not uplift
    return np.array([east, north, 0.0])


def plate_site_velocity(lat_deg: float, lon_deg: float, plate: str) -> SiteVelocity:
    """:func:`plate_velocity_enu_mps` with :data:`PLATE_MODEL_SIGMA_MPS` horizontally (none vertically:
    rigid plates do not move up)."""
    return SiteVelocity(
        velocity_enu_mps=plate_velocity_enu_mps(lat_deg, lon_deg, plate),
        sigma_enu_mps=np.array([PLATE_MODEL_SIGMA_MPS, PLATE_MODEL_SIGMA_MPS, 0.0]),
        source=f"ITRF2014 {plate}",
    )


def given_site_velocity(velocity_enu_mm_yr: tuple[float, ...]) -> SiteVelocity:
    """A velocity the user knows, ``(v_E, v_N[, v_U])`` in mm/yr, taken as exact."""
    v = np.zeros(3)
    if len(velocity_enu_mm_yr) not in (2, 3) or not np.all(np.isfinite(velocity_enu_mm_yr)):
        raise ConfigError(f"a site velocity is 2 or 3 finite numbers in mm/yr, got {velocity_enu_mm_yr}")
    v[: len(velocity_enu_mm_yr)] = velocity_enu_mm_yr
    return SiteVelocity(
        velocity_enu_mps=v * 1e-3 / SECONDS_PER_YEAR, sigma_enu_mps=np.zeros(3), source="given"
    )
