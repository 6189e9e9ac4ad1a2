"""Surface-vehicle kinematics.

The autonomous surface vehicle (ASV) of Garcia et al. (2019) moves on the sea surface with a constant
body-frame velocity and a commanded yaw rate, eq. (1)-(2):

    phi(n+1) = phi(n) + omega(n) T
    p(n+1)   = p(n) + R_z(phi(n+1)) v T

The heading is updated first and the new heading carries the vehicle over the period. All functions
are pure and broadcast over any leading batch shape (Monte Carlo runs, candidate plans).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray


@dataclass(frozen=True, slots=True, kw_only=True)
class VehiclePoses:
    """A batch of surface-vehicle poses.

    Attributes
    ----------
    pos_enu_m : (..., 3) float
        Positions in the local east-north-up frame, metres.
    yaw_rad : (...) float
        Headings, counter-clockwise from east (the x axis), radians.
    """

    pos_enu_m: FloatArray
    yaw_rad: FloatArray


def rotation_z(yaw_rad: ArrayLike) -> FloatArray:
    """Rotation about the up axis by ``yaw_rad``, eq. (2).

    Parameters
    ----------
    yaw_rad : (...) float

    Returns
    -------
    (..., 3, 3) float
    """
    yaw = np.asarray(yaw_rad, dtype=float)
    c, s = np.cos(yaw), np.sin(yaw)
    zero, one = np.zeros_like(yaw), np.ones_like(yaw)
    return np.stack(
        [np.stack([c, -s, zero], -1), np.stack([s, c, zero], -1), np.stack([zero, zero, one], -1)],
        axis=-2,
    )


def unicycle_step(
    pos_enu_m: ArrayLike,
    yaw_rad: ArrayLike,
    yaw_rate_rad_s: ArrayLike,
    velocity_body_mps: ArrayLike,
    period_s: float,
) -> VehiclePoses:
    """One step of eq. (1): heading first, then position with the new heading.

    Parameters
    ----------
    pos_enu_m : (..., 3) float
        Current positions, metres.
    yaw_rad : (...) float
        Current headings, radians.
    yaw_rate_rad_s : (...) float
        Commanded yaw rates over the step, rad/s.
    velocity_body_mps : (3,) or (..., 3) float
        Velocity in the vehicle frame (x forward), m/s; the papers use ``[3, 0, 0]``.
    period_s : float
        Sampling period ``T``, seconds.

    Returns
    -------
    VehiclePoses
        Positions ``(..., 3)`` and headings ``(...)`` at the next epoch.
    """
    yaw_next = np.asarray(yaw_rad, dtype=float) + np.asarray(yaw_rate_rad_s, dtype=float) * period_s
    v = np.asarray(velocity_body_mps, dtype=float)
    c, s = np.cos(yaw_next), np.sin(yaw_next)
    step = np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1], v[..., 2] + 0 * c], -1)
    return VehiclePoses(pos_enu_m=np.asarray(pos_enu_m, dtype=float) + step * period_s, yaw_rad=yaw_next)


def unicycle_rollout(
    pos_enu_m: ArrayLike,
    yaw_rad: ArrayLike,
    yaw_rates_rad_s: ArrayLike,
    speed_mps: float,
    period_s: float,
) -> VehiclePoses:
    """Poses after each of ``k`` yaw-rate commands, eq. (1) applied ``k`` times, in closed form.

    The vehicle moves forward at ``speed_mps`` (body velocity ``[speed, 0, 0]``) at constant depth.

    Parameters
    ----------
    pos_enu_m : (..., 3) float
        Start positions, metres.
    yaw_rad : (...) float
        Start headings, radians.
    yaw_rates_rad_s : (..., k) float
        Yaw-rate sequences, rad/s; ``[..., i]`` is applied over step ``i``.
    speed_mps : float
        Forward speed, m/s.
    period_s : float
        Sampling period, seconds.

    Returns
    -------
    VehiclePoses
        Positions ``(..., k, 3)`` and headings ``(..., k)`` at epochs ``N+1 .. N+k``.
    """
    rates = np.asarray(yaw_rates_rad_s, dtype=float)
    yaws = np.asarray(yaw_rad, dtype=float)[..., None] + np.cumsum(rates, axis=-1) * period_s
    step = speed_mps * period_s
    dx = np.cumsum(np.cos(yaws), axis=-1) * step
    dy = np.cumsum(np.sin(yaws), axis=-1) * step
    start = np.asarray(pos_enu_m, dtype=float)[..., None, :]
    pos = np.stack([start[..., 0] + dx, start[..., 1] + dy, np.broadcast_to(start[..., 2], dx.shape)], -1)
    return VehiclePoses(pos_enu_m=pos, yaw_rad=yaws)
