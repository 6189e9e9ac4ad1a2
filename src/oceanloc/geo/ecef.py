"""Earth-centred Earth-fixed (ECEF, WGS84) coordinates and covariances in a local ENU frame.

GNSS-A files give antenna or transducer positions as ECEF ``X, Y, Z`` with a full 3x3 covariance
(GNATSS's ``POS_FREED_TRANS_TWTT``); the estimators work in the local ENU frame of an origin, so both the
positions and the covariances are rotated: ``C_enu = R C_ecef R^T`` with the ENU rotation ``R`` of the
origin (:func:`enu_rotation`).
"""

from __future__ import annotations

import numpy as np
import pymap3d

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.geo.enu import EnuOrigin


def enu_rotation_at(lat_deg: ArrayLike, lon_deg: ArrayLike) -> FloatArray:
    """The rotations taking ECEF vectors to (E, N, U) at geodetic latitudes and longitudes (degrees),
    ``(..., 3, 3)``: rows the local east, north and up unit vectors in ECEF (the transpose takes ENU
    vectors to ECEF)."""
    lat, lon = np.deg2rad(np.asarray(lat_deg, dtype=float)), np.deg2rad(np.asarray(lon_deg, dtype=float))
    sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    z = np.zeros_like(sl * so)
    rows = [[-so, co, z], [-sl * co, -sl * so, cl], [cl * co, cl * so, sl]]
    return np.stack([np.stack(np.broadcast_arrays(*r), axis=-1) for r in rows], axis=-2)


def enu_rotation(origin: EnuOrigin) -> FloatArray:
    """The rotation taking ECEF vectors to (E, N, U) at the origin, ``(3, 3)``."""
    return enu_rotation_at(origin.lat_deg, origin.lon_deg)


def ecef_to_enu_m(xyz_m: ArrayLike, origin: EnuOrigin) -> FloatArray:
    """ECEF positions ``(..., 3)`` to ENU about the origin, metres."""
    p = np.asarray(xyz_m, dtype=float)
    e, n, u = pymap3d.ecef2enu(p[..., 0], p[..., 1], p[..., 2], origin.lat_deg, origin.lon_deg, origin.h_m)
    return np.stack(np.broadcast_arrays(e, n, u), axis=-1).astype(float)


def enu_to_ecef_m(enu_m: ArrayLike, origin: EnuOrigin) -> FloatArray:
    """ENU positions about the origin ``(..., 3)`` to ECEF, metres."""
    p = np.asarray(enu_m, dtype=float)
    x, y, z = pymap3d.enu2ecef(p[..., 0], p[..., 1], p[..., 2], origin.lat_deg, origin.lon_deg, origin.h_m)
    return np.stack(np.broadcast_arrays(x, y, z), axis=-1).astype(float)


def ecef_covariance_to_enu_m2(cov_ecef_m2: ArrayLike, origin: EnuOrigin) -> FloatArray:
    """ECEF covariances ``(..., 3, 3)`` rotated to ENU at the origin, square metres."""
    r = enu_rotation(origin)
    return np.einsum("ij,...jk,lk->...il", r, np.asarray(cov_ecef_m2, dtype=float), r)
