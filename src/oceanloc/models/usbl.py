"""USBL measurement models: the beacon's direction in the head's frame and the calibrated range, each ``h``
with its Jacobians beside it.

Frames and angles (radians inside, as everywhere in the package):

* **ENU** is the local frame (east, north, up) of the antenna positions and the beacons.
* **Vessel body** is forward, starboard, down (FRD), the frame of :mod:`oceanloc.models.attitude`. The
  vessel's attitude is roll ``phi`` (starboard down positive), pitch ``theta`` (bow up positive) and
  heading ``psi`` (clockwise from north), ``R_enu_body = T Rz(psi) Ry(theta) Rx(phi)`` with ``T`` taking
  NED to ENU.
* **Head** is the USBL transceiver's own FRD frame. Its *misalignment* is its roll, pitch and heading
  ``(a_r, a_p, a_h)`` in the vessel body frame, ``R_body_head = Rz(a_h) Ry(a_p) Rx(a_r)``, the same
  z-y-x Euler sequence (SeaTrac's guide applies its attitudes "in the Euler sequence Yaw, Pitch then
  Roll"). Zero misalignment: the head's forward mark on the bow, its face level.

The transducer sits at ``p_T = p_A + R_enu_body l`` (antenna ``p_A``, body-frame lever arm ``l``), and
the head sees the beacon ``p_B`` along

    d = R_body_head^T R_enu_body^T (p_B - p_T)                                            (1)

* **Azimuth** ``az = atan2(d_y, d_x)``: clockwise from the head's forward axis seen from above, in
  ``(-pi, pi]`` (a file's ``0..360`` degrees is the same angle on the circle: residuals are wrapped).
* **Elevation** ``el = atan2(-d_z, sqrt(d_x^2 + d_y^2))``: above the head's horizontal plane, so a
  beacon below is negative (SeaTrac's ``USBL_ELEVATION`` in ``-90..+90`` degrees).

**Range with calibration terms.** A USBL turns the round-trip time into a range with the sound speed
it was told, after removing the beacon's turn-around delay as it was told. With the true speed ``c``,
a configured ``c_0``, and an uncompensated turn-around ``tau`` (the beacon's actual delay less the one
removed), the reported range is ``(c_0 / c) |p_B - p_T| + c_0 tau / 2``. The model is

    r = s |p_B - p_T| + c_0 tau / 2 + b                                                    (2)

with the *sound-speed scale* ``s = c_0 / c`` (1 when the speed is right), the *turn-around delay*
``tau`` (seconds) and an optional *constant range bias* ``b`` (metres: electronics, a cable). ``tau``
and ``b`` enter the same way, so no track separates them: the calibration holds one at its prior and
says so (:mod:`oceanloc.estimation.usbl_calibration`).

All functions broadcast over leading batch dimensions and never mutate their inputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.models.measurements import wrap_angle_rad

_NED_TO_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])

DEFAULT_SOUND_SPEED_MPS = 1500.0
"""The configured sound speed ``c_0`` that turns the delay into metres in eq. (2) when none is given."""


def rotation_zyx(roll_rad: ArrayLike, pitch_rad: ArrayLike, yaw_rad: ArrayLike) -> FloatArray:
    """``Rz(yaw) Ry(pitch) Rx(roll)``, the z-y-x Euler rotation, ``(..., 3, 3)``."""
    return _rotation_and_derivatives(roll_rad, pitch_rad, yaw_rad, derivatives=False)[0]


def rotation_zyx_derivatives(roll_rad: ArrayLike, pitch_rad: ArrayLike, yaw_rad: ArrayLike) -> FloatArray:
    """Derivatives of :func:`rotation_zyx` on roll, pitch and yaw, ``(..., 3, 3, 3)`` (index -3 the angle)."""
    return _rotation_and_derivatives(roll_rad, pitch_rad, yaw_rad, derivatives=True)[1]


def _rotation_and_derivatives(
    roll_rad: ArrayLike, pitch_rad: ArrayLike, yaw_rad: ArrayLike, *, derivatives: bool
) -> tuple[FloatArray, FloatArray | None]:
    phi, theta, psi = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (roll_rad, pitch_rad, yaw_rad))
    )
    cf, sf, ct, st, cp, sp = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta), np.cos(psi), np.sin(psi)
    r = np.empty((*phi.shape, 3, 3))
    r[..., 0, 0] = cp * ct
    r[..., 0, 1] = cp * st * sf - sp * cf
    r[..., 0, 2] = cp * st * cf + sp * sf
    r[..., 1, 0] = sp * ct
    r[..., 1, 1] = sp * st * sf + cp * cf
    r[..., 1, 2] = sp * st * cf - cp * sf
    r[..., 2, 0] = -st
    r[..., 2, 1] = ct * sf
    r[..., 2, 2] = ct * cf
    if not derivatives:
        return r, None
    d = np.zeros((*phi.shape, 3, 3, 3))
    # d/droll
    d[..., 0, 0, 1] = cp * st * cf + sp * sf
    d[..., 0, 0, 2] = -cp * st * sf + sp * cf
    d[..., 0, 1, 1] = sp * st * cf - cp * sf
    d[..., 0, 1, 2] = -sp * st * sf - cp * cf
    d[..., 0, 2, 1] = ct * cf
    d[..., 0, 2, 2] = -ct * sf
    # d/dpitch
    d[..., 1, 0, 0] = -cp * st
    d[..., 1, 0, 1] = cp * ct * sf
    d[..., 1, 0, 2] = cp * ct * cf
    d[..., 1, 1, 0] = -sp * st
    d[..., 1, 1, 1] = sp * ct * sf
    d[..., 1, 1, 2] = sp * ct * cf
    d[..., 1, 2, 0] = -ct
    d[..., 1, 2, 1] = -st * sf
    d[..., 1, 2, 2] = -st * cf
    # d/dyaw
    d[..., 2, 0, 0] = -sp * ct
    d[..., 2, 0, 1] = -sp * st * sf - cp * cf
    d[..., 2, 0, 2] = -sp * st * cf + cp * sf
    d[..., 2, 1, 0] = cp * ct
    d[..., 2, 1, 1] = cp * st * sf - sp * cf
    d[..., 2, 1, 2] = cp * st * cf + sp * sf
    return r, d


def vessel_rotation(attitude_rad: ArrayLike) -> FloatArray:
    """``R_enu_body`` of vessel attitudes ``(..., 3)`` = roll, pitch, heading (clockwise from north)."""
    att = np.asarray(attitude_rad, dtype=float)
    return _NED_TO_ENU @ rotation_zyx(att[..., 0], att[..., 1], att[..., 2])


@dataclass(frozen=True, slots=True, kw_only=True)
class _Geometry:
    """Everything eqs. (1)-(2) and their Jacobians share for one batch of pings."""

    r_eb: FloatArray  # (..., 3, 3) ENU <- body
    d_r_eb: FloatArray | None  # (..., 3, 3, 3) its derivatives on the vessel attitude
    r_bh: FloatArray  # (..., 3, 3) body <- head
    d_r_bh: FloatArray | None  # (..., 3, 3, 3) its derivatives on the misalignment
    lever: FloatArray  # (..., 3)
    rel_enu: FloatArray  # (..., 3) p_B - p_T
    head: FloatArray  # (..., 3) d of eq. (1)


def _geometry(
    beacon_enu_m: ArrayLike,
    antenna_enu_m: ArrayLike,
    attitude_rad: ArrayLike,
    lever_arm_m: ArrayLike,
    misalignment_rad: ArrayLike,
    *,
    derivatives: bool,
    pose: bool = True,
    rotation: FloatArray | None = None,
) -> _Geometry:
    mis = np.asarray(misalignment_rad, dtype=float)
    lever = np.asarray(lever_arm_m, dtype=float)
    if rotation is not None and not (derivatives and pose):
        r_eb, d_r_eb = rotation, None
    else:
        att = np.asarray(attitude_rad, dtype=float)
        r_v, d_v = _rotation_and_derivatives(
            att[..., 0], att[..., 1], att[..., 2], derivatives=derivatives and pose
        )
        r_eb = _NED_TO_ENU @ r_v
        d_r_eb = None if d_v is None else _NED_TO_ENU @ d_v
    r_bh, d_r_bh = _rotation_and_derivatives(mis[..., 0], mis[..., 1], mis[..., 2], derivatives=derivatives)
    transducer = np.asarray(antenna_enu_m, dtype=float) + (r_eb @ lever[..., None])[..., 0]
    rel = np.asarray(beacon_enu_m, dtype=float) - transducer
    body = (np.swapaxes(r_eb, -1, -2) @ rel[..., None])[..., 0]
    head = (np.swapaxes(r_bh, -1, -2) @ body[..., None])[..., 0]
    return _Geometry(r_eb=r_eb, d_r_eb=d_r_eb, r_bh=r_bh, d_r_bh=d_r_bh, lever=lever, rel_enu=rel, head=head)


def head_vector_m(
    beacon_enu_m: ArrayLike,
    antenna_enu_m: ArrayLike,
    attitude_rad: ArrayLike,
    lever_arm_m: ArrayLike,
    misalignment_rad: ArrayLike,
) -> FloatArray:
    """The beacon as the head sees it, ``d`` of eq. (1), metres, ``(..., 3)`` (head FRD)."""
    return _geometry(
        beacon_enu_m, antenna_enu_m, attitude_rad, lever_arm_m, misalignment_rad, derivatives=False
    ).head


def _angles(head: FloatArray) -> FloatArray:
    dx, dy, dz = head[..., 0], head[..., 1], head[..., 2]
    return np.stack([np.arctan2(dy, dx), np.arctan2(-dz, np.hypot(dx, dy))], axis=-1)


def usbl_direction_rad(
    beacon_enu_m: ArrayLike,
    antenna_enu_m: ArrayLike,
    attitude_rad: ArrayLike,
    lever_arm_m: ArrayLike,
    misalignment_rad: ArrayLike,
    *,
    rotation: FloatArray | None = None,
) -> FloatArray:
    """Azimuth and elevation of the beacon in the head's frame, eq. (1).

    Parameters
    ----------
    beacon_enu_m : (..., 3) float
        Beacon positions, ENU metres.
    antenna_enu_m : (..., 3) float
        Vessel reference (GNSS antenna) positions at the pings, ENU metres.
    attitude_rad : (..., 3) float
        Vessel roll, pitch and heading (clockwise from north), radians.
    lever_arm_m : (..., 3) float
        Transducer offset from the antenna in the vessel frame (forward, starboard, down), metres.
    misalignment_rad : (..., 3) float
        Head roll, pitch and heading in the vessel frame, radians.
    rotation : (..., 3, 3) float, optional
        :func:`vessel_rotation` of ``attitude_rad``, when the caller has it (an estimator evaluating the
        same pings many times); it is then used instead of recomputing it.

    Returns
    -------
    (..., 2) float
        Azimuth in ``(-pi, pi]`` and elevation in ``[-pi/2, pi/2]``, radians.
    """
    g = _geometry(
        beacon_enu_m,
        antenna_enu_m,
        attitude_rad,
        lever_arm_m,
        misalignment_rad,
        derivatives=False,
        rotation=rotation,
    )
    return _angles(g.head)


@dataclass(frozen=True, slots=True, kw_only=True)
class DirectionJacobians:
    """Jacobians of :func:`usbl_direction_rad`: rows azimuth, elevation; radians per unit of the column.

    Attributes
    ----------
    angles : (..., 2) float
        The azimuth and elevation themselves (computed on the way), radians.
    beacon : (..., 2, 3) float
        On the beacon position, rad/m.
    misalignment : (..., 2, 3) float
        On the head's roll, pitch and heading misalignment, rad/rad.
    lever_arm : (..., 2, 3) float
        On the lever arm (forward, starboard, down), rad/m.
    antenna : (..., 2, 3) float
        On the antenna position (for folding GNSS noise into the angles), rad/m.
    attitude : (..., 2, 3) float
        On the vessel roll, pitch and heading (for folding attitude noise), rad/rad.
    """

    angles: FloatArray
    beacon: FloatArray
    misalignment: FloatArray
    lever_arm: FloatArray
    antenna: FloatArray
    attitude: FloatArray


def usbl_direction_jacobian(
    beacon_enu_m: ArrayLike,
    antenna_enu_m: ArrayLike,
    attitude_rad: ArrayLike,
    lever_arm_m: ArrayLike,
    misalignment_rad: ArrayLike,
    *,
    pose: bool = True,
    rotation: FloatArray | None = None,
) -> DirectionJacobians:
    """Jacobians of :func:`usbl_direction_rad` (same arguments), by the chain rule through eq. (1).

    With ``h^2 = d_x^2 + d_y^2`` and ``rho^2 = h^2 + d_z^2``:
    ``d az / d d = (-d_y, d_x, 0) / h^2`` and ``d el / d d = (d_z d_x / h, d_z d_y / h, -h) / rho^2``;
    ``d d / d p_B = R^T``, ``d d / d p_A = -R^T``, ``d d / d l = -R_body_head^T`` (``R = R_enu_body
    R_body_head``); the angle derivatives through those of the rotations. Directly above or below the
    head (``h = 0``) the azimuth is undefined: its row is zero there (no information). ``pose=False``
    skips the antenna and attitude Jacobians (zero-size arrays then; an estimator needs only the others),
    and then uses ``rotation`` (see :func:`usbl_direction_rad`) where given.
    """
    g = _geometry(
        beacon_enu_m,
        antenna_enu_m,
        attitude_rad,
        lever_arm_m,
        misalignment_rad,
        derivatives=True,
        pose=pose,
        rotation=rotation,
    )
    assert g.d_r_bh is not None
    d = g.head
    dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
    h2 = dx * dx + dy * dy
    h = np.sqrt(h2)
    rho2 = h2 + dz * dz
    on = h2 > 0.0
    inv_h2 = np.where(on, 1.0 / np.where(on, h2, 1.0), 0.0)
    k = np.where(on, dz / (np.where(on, h, 1.0) * np.where(rho2 > 0.0, rho2, 1.0)), 0.0)
    d_angles = np.empty((*dx.shape, 2, 3))
    d_angles[..., 0, 0] = -dy * inv_h2
    d_angles[..., 0, 1] = dx * inv_h2
    d_angles[..., 0, 2] = 0.0
    d_angles[..., 1, 0] = dx * k
    d_angles[..., 1, 1] = dy * k
    d_angles[..., 1, 2] = -h / np.where(rho2 > 0.0, rho2, 1.0)
    r_enu_head = g.r_eb @ g.r_bh
    d_beacon = d_angles @ np.swapaxes(r_enu_head, -1, -2)
    body = (np.swapaxes(g.r_eb, -1, -2) @ g.rel_enu[..., None])[..., 0]  # R_eb^T (p_B - p_T)
    # d d / d a_i = (d R_bh / d a_i)^T body: column i of (..., 3 comps, 3 angles)
    d_head_mis = np.swapaxes((np.swapaxes(g.d_r_bh, -1, -2) @ body[..., None, :, None])[..., 0], -1, -2)
    d_lever = -(d_angles @ np.swapaxes(g.r_bh, -1, -2))
    if pose:
        assert g.d_r_eb is not None
        # d d / d att_i = R_bh^T [(dR_eb_i)^T (p_B - p_T) - R_eb^T dR_eb_i l]
        term1 = (np.swapaxes(g.d_r_eb, -1, -2) @ g.rel_enu[..., None, :, None])[..., 0]
        term2 = (np.swapaxes(g.r_eb, -1, -2)[..., None, :, :] @ (g.d_r_eb @ g.lever[..., None, :, None]))[
            ..., 0
        ]
        d_body_att = term1 - term2  # (..., 3 angles, 3 comps)
        d_head_att = np.swapaxes(
            (np.swapaxes(g.r_bh, -1, -2)[..., None, :, :] @ d_body_att[..., None])[..., 0], -1, -2
        )
        antenna, attitude = -d_beacon, d_angles @ d_head_att
    else:
        antenna = attitude = np.zeros((0,))
    return DirectionJacobians(
        angles=_angles(d),
        beacon=d_beacon,
        misalignment=d_angles @ d_head_mis,
        lever_arm=d_lever,
        antenna=antenna,
        attitude=attitude,
    )


def direction_residual_rad(measured_rad: ArrayLike, predicted_rad: ArrayLike) -> FloatArray:
    """``measured - predicted`` for azimuth and elevation ``(..., 2)``, the azimuth wrapped on the circle
    (a measured 359.9 degrees against a predicted -0.2 degrees is a residual of 0.1 degrees)."""
    diff = np.asarray(measured_rad, dtype=float) - np.asarray(predicted_rad, dtype=float)
    return np.stack([wrap_angle_rad(diff[..., 0]), diff[..., 1]], axis=-1)


def usbl_range_m(
    beacon_enu_m: ArrayLike,
    antenna_enu_m: ArrayLike,
    attitude_rad: ArrayLike,
    lever_arm_m: ArrayLike,
    scale: ArrayLike = 1.0,
    delay_s: ArrayLike = 0.0,
    bias_m: ArrayLike = 0.0,
    sound_speed_mps: float = DEFAULT_SOUND_SPEED_MPS,
    *,
    rotation: FloatArray | None = None,
) -> FloatArray:
    """The calibrated USBL range, eq. (2): ``s |p_B - p_T| + c_0 tau / 2 + b``, metres ``(...)``.

    Parameters
    ----------
    beacon_enu_m, antenna_enu_m, attitude_rad, lever_arm_m
        As for :func:`usbl_direction_rad`.
    scale : (...) float
        Sound-speed scale ``s = c_0 / c`` (dimensionless, 1 when the configured speed is right).
    delay_s : (...) float
        Uncompensated turn-around delay ``tau``, seconds (two-way time; it adds ``c_0 tau / 2``).
    bias_m : (...) float
        Constant range bias ``b``, metres.
    sound_speed_mps : float
        The configured sound speed ``c_0``, m/s.
    rotation : (..., 3, 3) float, optional
        :func:`vessel_rotation` of ``attitude_rad``, when the caller has it.
    """
    r_eb = vessel_rotation(attitude_rad) if rotation is None else rotation
    transducer = (
        np.asarray(antenna_enu_m, dtype=float)
        + (r_eb @ np.asarray(lever_arm_m, dtype=float)[..., None])[..., 0]
    )
    rel = np.asarray(beacon_enu_m, dtype=float) - transducer
    dist = np.sqrt(np.sum(rel * rel, axis=-1))
    return (
        np.asarray(scale, dtype=float) * dist
        + 0.5 * sound_speed_mps * np.asarray(delay_s, dtype=float)
        + np.asarray(bias_m, dtype=float)
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class RangeJacobians:
    """Jacobians of :func:`usbl_range_m` (metres per unit of the column).

    Attributes
    ----------
    range_m : (...) float
        The range itself.
    distance_m : (...) float
        ``|p_B - p_T|``.
    beacon, lever_arm, antenna, attitude : (..., 3) float
        On the beacon position, the lever arm, the antenna position and the vessel attitude (m/rad).
    scale : (...) float
        ``|p_B - p_T|``.
    delay : (...) float
        ``c_0 / 2``, metres per second.
    bias : (...) float
        1.
    """

    range_m: FloatArray
    distance_m: FloatArray
    beacon: FloatArray
    lever_arm: FloatArray
    antenna: FloatArray
    attitude: FloatArray
    scale: FloatArray
    delay: FloatArray
    bias: FloatArray


def usbl_range_jacobian(
    beacon_enu_m: ArrayLike,
    antenna_enu_m: ArrayLike,
    attitude_rad: ArrayLike,
    lever_arm_m: ArrayLike,
    scale: ArrayLike = 1.0,
    delay_s: ArrayLike = 0.0,
    bias_m: ArrayLike = 0.0,
    sound_speed_mps: float = DEFAULT_SOUND_SPEED_MPS,
    *,
    pose: bool = True,
    rotation: FloatArray | None = None,
) -> RangeJacobians:
    """Jacobians of :func:`usbl_range_m` (same arguments; ``pose=False`` skips the antenna and attitude
    Jacobians and then uses ``rotation`` where given).

    With the unit line of sight ``u = (p_B - p_T) / |p_B - p_T|``: ``d r / d p_B = s u`` (eq. 8 of the
    journal, scaled), ``d r / d p_A = -s u``, ``d r / d l = -s u^T R_enu_body``, ``d r / d att_i = -s u^T
    (d R_enu_body / d att_i) l``, ``d r / d s = |p_B - p_T|``, ``d r / d tau = c_0 / 2``, ``d r / d b = 1``.
    At zero distance the direction rows are zero (no information).
    """
    lever = np.asarray(lever_arm_m, dtype=float)
    if pose or rotation is None:
        att = np.asarray(attitude_rad, dtype=float)
        r_v, d_v = _rotation_and_derivatives(att[..., 0], att[..., 1], att[..., 2], derivatives=pose)
        r_eb = _NED_TO_ENU @ r_v
    else:
        r_eb, d_v = rotation, None
    rel = np.asarray(beacon_enu_m, dtype=float) - (
        np.asarray(antenna_enu_m, dtype=float) + (r_eb @ lever[..., None])[..., 0]
    )
    dist = np.sqrt(np.sum(rel * rel, axis=-1))
    s = np.asarray(scale, dtype=float)
    unit = np.divide(rel, dist[..., None], out=np.zeros_like(rel), where=dist[..., None] > 0.0)
    su = s[..., None] * unit
    rng = (
        s * dist + 0.5 * sound_speed_mps * np.asarray(delay_s, dtype=float) + np.asarray(bias_m, dtype=float)
    )
    if d_v is not None:
        d_r_eb = _NED_TO_ENU @ d_v
        lev = np.broadcast_to(lever, rel.shape)
        attitude = -(su[..., None, None, :] @ (d_r_eb @ lev[..., None, :, None]))[..., 0, 0]
        antenna = -su
    else:
        attitude = antenna = np.zeros((0,))
    return RangeJacobians(
        range_m=rng,
        distance_m=dist,
        beacon=su,
        lever_arm=-(su[..., None, :] @ r_eb)[..., 0, :],
        antenna=antenna,
        attitude=attitude,
        scale=dist,
        delay=np.full(dist.shape, 0.5 * sound_speed_mps),
        bias=np.ones_like(dist),
    )


def heading_from_yaw(yaw_rad: ArrayLike) -> FloatArray:
    """Heading clockwise from north of a yaw counter-clockwise from east (the planners' angle), radians."""
    return wrap_angle_rad(0.5 * np.pi - np.asarray(yaw_rad, dtype=float))


def apparent_beacon_enu_m(
    range_m: ArrayLike,
    direction_rad: ArrayLike,
    antenna_enu_m: ArrayLike,
    attitude_rad: ArrayLike,
    lever_arm_m: ArrayLike,
    misalignment_rad: ArrayLike,
    scale: ArrayLike = 1.0,
    delay_s: ArrayLike = 0.0,
    bias_m: ArrayLike = 0.0,
    sound_speed_mps: float = DEFAULT_SOUND_SPEED_MPS,
) -> FloatArray:
    """Where one USBL fix puts the beacon: eqs. (1)-(2) inverted for ``p_B``.

    ``p_B = p_T + R_enu_body R_body_head |d| (cos el cos az, cos el sin az, -sin el)`` with
    ``|d| = (r - c_0 tau / 2 - b) / s``: what a USBL displays with these calibration values (the crews'
    "scatter" of fixes seen from each heading).

    Parameters
    ----------
    range_m : (...) float
    direction_rad : (..., 2) float
        Measured azimuth and elevation.
    antenna_enu_m, attitude_rad, lever_arm_m, misalignment_rad
        As for :func:`usbl_direction_rad`.
    scale, delay_s, bias_m, sound_speed_mps
        As for :func:`usbl_range_m`.

    Returns
    -------
    (..., 3) float
        ENU metres.
    """
    direc = np.asarray(direction_rad, dtype=float)
    az, el = direc[..., 0], direc[..., 1]
    dist = (
        np.asarray(range_m, dtype=float)
        - 0.5 * sound_speed_mps * np.asarray(delay_s, dtype=float)
        - np.asarray(bias_m, dtype=float)
    ) / np.asarray(scale, dtype=float)
    unit_head = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), -np.sin(el)], axis=-1)
    mis = np.asarray(misalignment_rad, dtype=float)
    r_eb = vessel_rotation(attitude_rad)
    r_eh = r_eb @ rotation_zyx(mis[..., 0], mis[..., 1], mis[..., 2])
    transducer = np.asarray(antenna_enu_m, dtype=float) + np.einsum(
        "...ij,...j->...i", r_eb, np.asarray(lever_arm_m, dtype=float)
    )
    return transducer + dist[..., None] * np.einsum("...ij,...j->...i", r_eh, unit_head)
