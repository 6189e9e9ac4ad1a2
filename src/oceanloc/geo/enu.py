"""Geodetic (WGS84 latitude, longitude, ellipsoidal height) <-> local East-North-Up, through pymap3d.

The papers work in a local ENU frame "centered at the earliest collected GPS location of the ASV"
(Garcia et al. 2019, Section VI-C; thesis Section 6.1); :func:`origin_from_first_fix` builds that
origin. Degrees appear only here and at the edges (files, CLI); the frame itself is in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymap3d

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import DataError


@dataclass(frozen=True, slots=True, kw_only=True)
class EnuOrigin:
    """Origin of a local ENU frame on the WGS84 ellipsoid.

    Attributes
    ----------
    lat_deg, lon_deg : float
        Geodetic latitude and longitude of the origin, degrees.
    h_m : float
        Ellipsoidal height of the origin, metres.
    """

    lat_deg: float
    lon_deg: float
    h_m: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.lat_deg) and -90.0 <= self.lat_deg <= 90.0):
            raise DataError(f"origin latitude {self.lat_deg} deg is outside [-90, 90]")
        if not (np.isfinite(self.lon_deg) and -180.0 <= self.lon_deg <= 360.0):
            raise DataError(f"origin longitude {self.lon_deg} deg is outside [-180, 360]")
        if not np.isfinite(self.h_m):
            raise DataError(f"origin height {self.h_m} is not a number")


def geodetic_to_enu(lat_deg: ArrayLike, lon_deg: ArrayLike, h_m: ArrayLike, origin: EnuOrigin) -> FloatArray:
    """Geodetic coordinates to local ENU.

    Parameters
    ----------
    lat_deg, lon_deg, h_m : (...) float
        Points, degrees and metres.
    origin : EnuOrigin

    Returns
    -------
    (..., 3) float
        East, north, up, metres.
    """
    e, n, u = pymap3d.geodetic2enu(
        np.asarray(lat_deg, float),
        np.asarray(lon_deg, float),
        np.asarray(h_m, float),
        origin.lat_deg,
        origin.lon_deg,
        origin.h_m,
    )
    return np.stack(np.broadcast_arrays(e, n, u), axis=-1).astype(float)


def enu_to_geodetic(pos_enu_m: ArrayLike, origin: EnuOrigin) -> FloatArray:
    """Local ENU to geodetic coordinates.

    Parameters
    ----------
    pos_enu_m : (..., 3) float
        East, north, up, metres.
    origin : EnuOrigin

    Returns
    -------
    (..., 3) float
        Latitude (deg), longitude (deg), ellipsoidal height (m).
    """
    p = np.asarray(pos_enu_m, float)
    lat, lon, h = pymap3d.enu2geodetic(
        p[..., 0], p[..., 1], p[..., 2], origin.lat_deg, origin.lon_deg, origin.h_m
    )
    return np.stack(np.broadcast_arrays(lat, lon, h), axis=-1).astype(float)


def origin_from_first_fix(lat_deg: ArrayLike, lon_deg: ArrayLike, h_m: ArrayLike) -> EnuOrigin:
    """The papers' origin: the earliest fix (the first element of time-ordered arrays)."""
    lat = np.atleast_1d(np.asarray(lat_deg, float))
    if lat.size == 0:
        raise DataError("no fixes: cannot set an ENU origin")
    lon = np.atleast_1d(np.asarray(lon_deg, float))
    h = np.atleast_1d(np.asarray(h_m, float))
    return EnuOrigin(lat_deg=float(lat[0]), lon_deg=float(lon[0]), h_m=float(h[0]))
