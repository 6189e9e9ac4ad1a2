"""Secular motion of the seafloor: plate-model site velocities, to compare surveys made months apart.

A seafloor transponder moves with its tectonic plate, several centimetres a year in a global (ITRF)
frame, as much as GNSS-Acoustic surveys disagree. Positions surveyed at different epochs are therefore
compared at one reference epoch, ``x_ref = x_i - v (t_i - t_ref)``, with ``v`` from a plate-motion model
(or one the user knows, e.g. from a nearby GNSS station). The model here is rigid-plate rotation,
``v = omega x r`` at the site's Earth-centred position ``r``, rotated to local east-north-up through
pymap3d; the rotation poles are those of the ITRF2014 plate-motion model (Altamimi et al. 2017,
J. Geophys. Res. 122, Table 1) for the plates that meet off California, where the packaged La Jolla
surveys are. :func:`plate_at` finds which of those plates a site lies on from coarse outlines
(:data:`PLATE_OUTLINES_DEG`), so a survey's plate comes from its location.
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


PACIFIC_NORTH_AMERICA_BOUNDARY_DEG: tuple[tuple[float, float], ...] = (
    (23.0, -108.6), (24.0, -108.9), (26.0, -110.5), (27.5, -111.8), (29.0, -113.2), (30.5, -114.0),
    (31.7, -114.6), (32.6, -115.3), (33.2, -115.7), (33.9, -116.6), (34.3, -117.5), (34.8, -118.9),
    (35.9, -120.5), (36.8, -121.6), (37.6, -122.5), (38.3, -123.1), (39.0, -123.8), (40.3, -124.4),
)  # fmt: skip
"""The Pacific-North America boundary from the mouth of the Gulf of California to the Mendocino triple
junction, ``(lat, lon)`` degrees, south to north: the Gulf's spreading axis, the Imperial and San Andreas
faults. Sites west of it (La Jolla, Los Angeles, the California Borderland) are on the Pacific plate, east
of it (the Salton Trough's east side, Arizona) on North America. The boundary zone is a few tens of
kilometres wide here; the outline is good to about that."""

_ALASKA_ALEUTIAN_DEG: tuple[tuple[float, float], ...] = (
    (52.0, -131.8), (54.5, -134.5), (57.5, -137.5), (59.0, -143.0), (58.0, -149.0), (56.0, -154.0),
    (54.5, -158.5), (53.0, -164.0), (51.7, -170.0), (51.0, -175.0), (50.8, -180.0),
)  # fmt: skip

PLATE_OUTLINES_DEG: dict[str, tuple[tuple[tuple[float, float], ...], ...]] = {
    "PCFC": (
        (
            *PACIFIC_NORTH_AMERICA_BOUNDARY_DEG,
            (40.3, -127.5),
            (44.5, -130.3),
            (48.5, -129.2),
            (50.5, -130.5),
            *_ALASKA_ALEUTIAN_DEG,
            (-14.0, -180.0),
            (-15.5, -173.0),
            (-20.0, -173.5),
            (-25.0, -175.5),
            (-30.0, -177.0),
            (-35.0, -178.5),
            (-37.0, -180.0),
            (-63.0, -180.0),
            (-60.0, -150.0),
            (-55.0, -122.0),
            (-45.0, -113.5),
            (-35.5, -110.5),
            (-30.0, -112.0),
            (-20.0, -113.0),
            (-10.0, -110.0),
            (-5.0, -106.5),
            (0.0, -102.5),
            (5.0, -103.0),
            (10.0, -104.0),
            (15.0, -104.5),
            (19.0, -108.5),
            (21.0, -109.0),
        ),
        (
            (50.8, 180.0),
            (55.5, 164.0),
            (52.0, 159.5),
            (47.0, 154.5),
            (43.0, 147.0),
            (40.0, 144.0),
            (35.0, 142.5),
            (30.0, 142.5),
            (25.0, 143.0),
            (20.0, 146.0),
            (15.0, 147.5),
            (11.5, 145.0),
            (5.0, 150.0),
            (2.0, 154.0),
            (-5.0, 158.0),
            (-10.0, 165.0),
            (-14.0, 172.0),
            (-14.0, 180.0),
        ),
    ),
    "NOAM": (
        (
            *PACIFIC_NORTH_AMERICA_BOUNDARY_DEG,
            (42.0, -125.0),
            (46.0, -125.2),
            (48.5, -126.0),
            (50.5, -128.5),
            *_ALASKA_ALEUTIAN_DEG,
            (85.0, -180.0),
            (85.0, -10.0),
            (81.0, -5.0),
            (72.0, -8.0),
            (66.5, -18.0),
            (62.0, -25.0),
            (55.0, -35.0),
            (50.0, -29.0),
            (45.0, -28.5),
            (40.0, -29.5),
            (35.0, -36.0),
            (30.0, -42.0),
            (24.0, -46.0),
            (20.0, -45.5),
            (15.5, -47.0),
            (17.5, -61.0),
            (19.8, -66.0),
            (20.0, -73.0),
            (19.5, -78.0),
            (18.5, -84.0),
            (15.5, -88.5),
            (15.0, -93.0),
            (16.0, -97.5),
            (17.5, -102.0),
            (19.0, -105.5),
            (21.5, -106.8),
        ),
    ),
}
"""Coarse outlines ``(lat, lon)`` in degrees of the plates of :data:`ITRF2014_POLES_MAS_YR`, one or more
polygons each (split at the antimeridian): the Pacific plate between its trenches and ridges, North
America from the Pacific boundary (:data:`PACIFIC_NORTH_AMERICA_BOUNDARY_DEG`, shared by both) and the
Cascadia and Aleutian trenches to the Mid-Atlantic Ridge and the Caribbean. Good to about 100 km away from
the shared California boundary; enough to say which of the two plates a survey lies on."""


def plate_at(lat_deg: float, lon_deg: float) -> str | None:
    """The plate of :data:`PLATE_OUTLINES_DEG` holding the site ``(lat_deg, lon_deg)``, or None when the
    site lies on none of them (a plate the model does not know)."""
    lon = (float(lon_deg) + 180.0) % 360.0 - 180.0
    for plate, polygons in PLATE_OUTLINES_DEG.items():
        if any(_inside(float(lat_deg), lon, np.asarray(poly, dtype=float)) for poly in polygons):
            return plate
    return None


def _inside(lat: float, lon: float, poly: FloatArray) -> bool:
    """Even-odd ray casting in the (lon, lat) plane: is the point inside the polygon ``poly (k, 2)``?"""
    y0, x0 = poly[:, 0], poly[:, 1]
    y1, x1 = np.roll(y0, -1), np.roll(x0, -1)
    crosses = (y0 > lat) != (y1 > lat)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = x0 + (lat - y0) * (x1 - x0) / (y1 - y0)
    return bool(np.count_nonzero(crosses & (lon < x_at)) % 2)
