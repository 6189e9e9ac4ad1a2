"""Vessel attitude and the lever arm from the GNSS antenna to the acoustic transducer.

Frames: the body frame is forward, starboard, down (FRD, the marine convention, and GNATSS's
``forward, rightward, downward`` transducer offsets); the local frame is East, North, Up. Attitude is
roll ``phi`` (starboard down positive), pitch ``theta`` (bow up positive) and heading ``psi`` (clockwise
from north), applied as ``R_ned_body = Rz(psi) Ry(theta) Rx(phi)`` (the aerospace z-y-x sequence), and
``R_enu_body = T R_ned_body`` with ``T`` swapping north and east and flipping down to up.

The transducer sits at ``x_T = x_A + R_enu_body l`` for the antenna position ``x_A`` (ENU) and the
body-frame lever arm ``l``. Its covariance from the antenna's, the attitude's and the lever arm's is
``C_A + R C_l R^T + J_att C_att J_att^T`` (:func:`transducer_jacobians`); the lever arm's error is common
to every ping, though, so a solver should carry it as one unknown with a prior rather than add it to
each ping (:mod:`oceanloc.estimation.gnssa_array` does).

Interpolation (:func:`interpolate_track`): positions, covariances, roll and pitch linearly in time;
heading linearly on the unwrapped angle (so 359 deg -> 1 deg passes through 0, not 180).
"""

from __future__ import annotations

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError, DataError

_NED_TO_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def rotation_enu_from_body(roll_deg: ArrayLike, pitch_deg: ArrayLike, heading_deg: ArrayLike) -> FloatArray:
    """Rotation matrices taking body-frame (forward, starboard, down) vectors to ENU.

    Parameters
    ----------
    roll_deg, pitch_deg, heading_deg : (...) float
        Attitude angles, degrees (see the module docstring for signs and order).

    Returns
    -------
    (..., 3, 3) float
    """
    phi, theta, psi = np.broadcast_arrays(
        *(np.deg2rad(np.asarray(a, dtype=float)) for a in (roll_deg, pitch_deg, heading_deg))
    )
    cf, sf = np.cos(phi), np.sin(phi)
    ct, st = np.cos(theta), np.sin(theta)
    cp, sp = np.cos(psi), np.sin(psi)
    r = np.empty((*phi.shape, 3, 3))
    # R_ned_body = Rz(psi) Ry(theta) Rx(phi)
    r[..., 0, 0] = cp * ct
    r[..., 0, 1] = cp * st * sf - sp * cf
    r[..., 0, 2] = cp * st * cf + sp * sf
    r[..., 1, 0] = sp * ct
    r[..., 1, 1] = sp * st * sf + cp * cf
    r[..., 1, 2] = sp * st * cf - cp * sf
    r[..., 2, 0] = -st
    r[..., 2, 1] = ct * sf
    r[..., 2, 2] = ct * cf
    return np.einsum("ij,...jk->...ik", _NED_TO_ENU, r)


def transducer_enu_m(
    antenna_enu_m: ArrayLike, rotation: ArrayLike, lever_arm_body_m: ArrayLike
) -> FloatArray:
    """Transducer positions ``x_A + R l``, metres, ``(..., 3)``."""
    return np.asarray(antenna_enu_m, dtype=float) + np.einsum(
        "...ij,...j->...i", np.asarray(rotation, dtype=float), np.asarray(lever_arm_body_m, dtype=float)
    )


def transducer_jacobians(
    roll_deg: ArrayLike, pitch_deg: ArrayLike, heading_deg: ArrayLike, lever_arm_body_m: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Jacobians of the transducer's ENU position on the lever arm and on the attitude angles.

    Returns
    -------
    d_lever : (..., 3, 3) float
        ``d x_T / d l = R_enu_body`` (dimensionless).
    d_attitude : (..., 3, 3) float
        ``d x_T / d (roll, pitch, heading)``, metres per degree (columns in that order).
    """
    phi, theta, psi = np.broadcast_arrays(
        *(np.deg2rad(np.asarray(a, dtype=float)) for a in (roll_deg, pitch_deg, heading_deg))
    )
    lever = np.asarray(lever_arm_body_m, dtype=float)
    cf, sf = np.cos(phi), np.sin(phi)
    ct, st = np.cos(theta), np.sin(theta)
    cp, sp = np.cos(psi), np.sin(psi)
    zero = np.zeros_like(phi)
    one = np.ones_like(phi)

    def mat(rows: list[list[FloatArray]]) -> FloatArray:
        return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)

    rz = mat([[cp, -sp, zero], [sp, cp, zero], [zero, zero, one]])
    ry = mat([[ct, zero, st], [zero, one, zero], [-st, zero, ct]])
    rx = mat([[one, zero, zero], [zero, cf, -sf], [zero, sf, cf]])
    drz = mat([[-sp, -cp, zero], [cp, -sp, zero], [zero, zero, zero]])
    dry = mat([[-st, zero, ct], [zero, zero, zero], [-ct, zero, -st]])
    drx = mat([[zero, zero, zero], [zero, -sf, -cf], [zero, cf, -sf]])
    per_rad = np.pi / 180.0
    parts = (rz @ ry @ drx, rz @ dry @ rx, drz @ ry @ rx)
    d_att = np.stack([np.einsum("...ij,...j->...i", d, lever) for d in parts], axis=-1) * per_rad
    d_att = np.einsum("ij,...jk->...ik", _NED_TO_ENU, d_att)
    d_lever = np.einsum("ij,...jk->...ik", _NED_TO_ENU, rz @ ry @ rx)
    return d_lever, d_att


def interpolate_track(
    t_track_s: ArrayLike,
    t_query_s: ArrayLike,
    position_enu_m: ArrayLike,
    covariance_enu_m2: ArrayLike,
    attitude_deg: ArrayLike,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """A GNSS antenna track and its attitude at other times (vectorized, linear in time).

    Parameters
    ----------
    t_track_s : (k,) float
        Strictly increasing epochs of the track, seconds.
    t_query_s : (q,) float
        Times wanted; they must lie within the track (no extrapolation).
    position_enu_m : (k, 3) float
    covariance_enu_m2 : (k, 3, 3) float
    attitude_deg : (k, 3) float
        Roll, pitch, heading, degrees.

    Returns
    -------
    position (q, 3), covariance (q, 3, 3), attitude (q, 3) with heading in [0, 360).

    Raises
    ------
    DataError
        If the track is not strictly increasing or a query time lies outside it.
    """
    t = np.asarray(t_track_s, dtype=float)
    q = np.asarray(t_query_s, dtype=float)
    if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0.0):
        raise DataError("the antenna track needs at least two epochs in strictly increasing time")
    outside = (q < t[0]) | (q > t[-1])
    if outside.any():
        i = int(np.argmax(outside))
        raise DataError(
            f"time {q[i]:.3f} s lies outside the antenna track [{t[0]:.3f}, {t[-1]:.3f}] s: "
            "no extrapolation of positions or attitude"
        )
    k = np.clip(np.searchsorted(t, q, side="right") - 1, 0, t.size - 2)
    w = (q - t[k]) / (t[k + 1] - t[k])
    pos = np.asarray(position_enu_m, dtype=float)
    cov = np.asarray(covariance_enu_m2, dtype=float)
    att = np.asarray(attitude_deg, dtype=float).copy()
    if pos.shape != (t.size, 3) or cov.shape != (t.size, 3, 3) or att.shape != (t.size, 3):
        raise ConfigError("track arrays must be (k, 3), (k, 3, 3) and (k, 3) for k epochs")
    att[:, 2] = np.rad2deg(np.unwrap(np.deg2rad(att[:, 2])))

    def lerp(a: FloatArray) -> FloatArray:
        shape = (-1,) + (1,) * (a.ndim - 1)
        return a[k] + w.reshape(shape) * (a[k + 1] - a[k])

    out_att = lerp(att)
    out_att[:, 2] = np.mod(out_att[:, 2], 360.0)
    return lerp(pos), lerp(cov), out_att
