"""A local tangent-plane frame for gridded ocean products: longitude/latitude <-> metres east/north.

Gridded currents on longitude/latitude are resampled once onto a regular metric grid in this frame
(:mod:`oceanloc.models.currents_cf`), so planners work in metres; plans are mapped back to longitude and
latitude for GeoJSON output. The conversion is pymap3d's geodetic <-> ENU on the WGS84 ellipsoid at zero
height (the sea surface, to the ellipsoid's approximation): a surface point maps to the east and north
coordinates of its position in the tangent plane's frame, and back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymap3d

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError


@dataclass(frozen=True, slots=True, kw_only=True)
class LocalProjection:
    """East-north metres about an origin on the WGS84 ellipsoid.

    Attributes
    ----------
    lat0_deg, lon0_deg : float
        Origin, degrees.
    """

    lat0_deg: float
    lon0_deg: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.lat0_deg) and -90.0 < self.lat0_deg < 90.0):
            raise ConfigError(f"projection origin latitude must be within (-90, 90), got {self.lat0_deg}")
        if not (np.isfinite(self.lon0_deg) and -360.0 <= self.lon0_deg <= 360.0):
            raise ConfigError(f"projection origin longitude must be within [-360, 360], got {self.lon0_deg}")

    def to_local(self, lon_deg: ArrayLike, lat_deg: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Longitude/latitude (degrees, any broadcastable shape) to east/north metres."""
        lon = _wrap_near(np.asarray(lon_deg, dtype=float), self.lon0_deg)
        e, n, _ = pymap3d.geodetic2enu(
            np.asarray(lat_deg, dtype=float), lon, 0.0, self.lat0_deg, self.lon0_deg, 0.0
        )
        return np.asarray(e, dtype=float), np.asarray(n, dtype=float)

    def to_lonlat(self, x_m: ArrayLike, y_m: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """East/north metres to longitude/latitude in degrees (longitude within 180 of the origin's).

        The inverse of :meth:`to_local`: the sea-surface point (zero ellipsoidal height) whose east/north
        coordinates are ``(x, y)``; its "up" coordinate (the surface's drop below the tangent plane,
        about ``-(x^2 + y^2) / 2R``) is found by three Newton steps on the height.
        """
        x = np.asarray(x_m, dtype=float)
        y = np.asarray(y_m, dtype=float)
        up = -(x * x + y * y) / (2.0 * 6_371_000.0)
        for _ in range(3):
            lat, lon, h = pymap3d.enu2geodetic(x, y, up, self.lat0_deg, self.lon0_deg, 0.0)
            up = up - np.asarray(h, dtype=float)
        lat, lon, _ = pymap3d.enu2geodetic(x, y, up, self.lat0_deg, self.lon0_deg, 0.0)
        return _wrap_near(np.asarray(lon, dtype=float), self.lon0_deg), np.asarray(lat, dtype=float)


def _wrap_near(lon_deg: FloatArray, ref_deg: float) -> FloatArray:
    """Longitudes shifted by multiples of 360 to lie within 180 degrees of ``ref_deg``."""
    return ref_deg + (lon_deg - ref_deg + 180.0) % 360.0 - 180.0
