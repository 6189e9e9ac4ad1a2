"""Measurement models: each ``h(x)`` with its analytic Jacobian beside it.

Range (Garcia et al. 2019, eq. (3)-(4), Jacobian eq. (8)): the distance between a sensor and a
target, ``r = ||p_T - p_V||``, measured with additive Gaussian noise. Functions broadcast over leading
batch dimensions (runs, transponders, measurements, sigma points); they never mutate their inputs.
"""

from __future__ import annotations

from typing import Literal, TypeAlias

import numpy as np

from oceanloc._random import BatchRng, standard_normal
from oceanloc._typing import ArrayLike, FloatArray


def range_m(target_m: ArrayLike, sensor_m: ArrayLike) -> FloatArray:
    """Euclidean range between targets and sensors, eq. (3) without noise.

    Parameters
    ----------
    target_m : (..., 3) float
        Target (transponder) positions, metres.
    sensor_m : (..., 3) float
        Sensor (vehicle) positions, metres; broadcast against ``target_m``.

    Returns
    -------
    (...) float
        Ranges, metres.
    """
    diff = np.asarray(target_m, dtype=float) - np.asarray(sensor_m, dtype=float)
    return np.sqrt(np.sum(diff * diff, axis=-1))


def range_jacobian(target_m: ArrayLike, sensor_m: ArrayLike) -> FloatArray:
    """Jacobian of :func:`range_m` with respect to the target position, eq. (8).

    ``h = (p_T - p_V)^T / ||p_T - p_V||``, the unit line-of-sight vector from sensor to target. At zero
    range the derivative does not exist; the zero vector is returned there (no information).

    Parameters
    ----------
    target_m : (..., 3) float
    sensor_m : (..., 3) float

    Returns
    -------
    (..., 3) float
        Row vectors ``h``, dimensionless.
    """
    diff = np.asarray(target_m, dtype=float) - np.asarray(sensor_m, dtype=float)
    dist = np.sqrt(np.sum(diff * diff, axis=-1, keepdims=True))
    return np.divide(diff, dist, out=np.zeros_like(diff), where=dist > 0.0)


def simulate_ranges(
    target_m: ArrayLike, sensor_m: ArrayLike, sigma_range_m: float, rng: BatchRng
) -> FloatArray:
    """Noisy ranges ``z = r + w``, ``w ~ N(0, sigma^2)``, eq. (3).

    Parameters
    ----------
    target_m, sensor_m : (B, ..., 3) float
        Broadcast to a common shape whose first axis is the batch ``B``.
    sigma_range_m : float
        Noise standard deviation, metres.
    rng : Generator or sequence of B generators
        One generator per batch element keeps draws independent of batching.

    Returns
    -------
    (B, ...) float
        Measured ranges, metres.
    """
    true = range_m(target_m, sensor_m)
    true = np.atleast_1d(true)
    noise = standard_normal(rng, true.shape[0], true.shape[1:])
    return true + sigma_range_m * noise


# --- Flock tracking: planar bearing, range and TDOA to a target state [X, Y, u, v, ax, ay] ---------------
# Dillard (AquaQuad thesis), eqs. (II.3), (II.4), (II.7). The target argument is any state whose first two
# components are the horizontal position (a 2-vector position, the 4-state CV or the 6-state CA state); the
# Jacobian has one column per state component, zero beyond the position. Sensors are broadcast against the
# target's leading dimensions: ``target (..., d)`` with ``sensors_m (..., N, 2)`` gives ``(..., N)``.


MeasurementKind: TypeAlias = Literal["bearing", "range", "tdoa"]
"""Flock measurement types: bearing (II.3), horizontal range (II.4), time difference of arrival (II.7)."""
MEASUREMENT_KINDS: tuple[str, ...] = ("bearing", "range", "tdoa")


def wrap_angle_rad(angle_rad: ArrayLike) -> FloatArray:
    """Wrap angles to ``(-pi, pi]``, the range of ``atan2``; used for every bearing residual."""
    a = np.asarray(angle_rad, dtype=float)
    # a - 2 pi ceil((a - pi) / 2 pi), written with floor (several times faster than np.mod).
    return a + (2.0 * np.pi) * np.floor((np.pi - a) / (2.0 * np.pi))


def _offsets(target: ArrayLike, sensors_m: ArrayLike) -> FloatArray:
    t = np.asarray(target, dtype=float)
    s = np.asarray(sensors_m, dtype=float)
    if t.shape[-1] < 2 or s.shape[-1] != 2:
        raise ValueError(f"target needs (..., d>=2) and sensors (..., N, 2); got {t.shape} and {s.shape}")
    return t[..., None, :2] - s


def _state_jacobian(d_xy: FloatArray, n_state: int) -> FloatArray:
    if n_state == 2:
        return d_xy
    jac = np.zeros((*d_xy.shape[:-1], n_state))
    jac[..., :2] = d_xy
    return jac


def bearing_rad(target: ArrayLike, sensors_m: ArrayLike) -> FloatArray:
    """Four-quadrant bearing from each sensor to the target, eq. (II.3).

    ``theta_i = atan2(Y - y_i, X - x_i)``, counter-clockwise from the +X (east) axis, in ``(-pi, pi]``.

    Parameters
    ----------
    target : (..., d) float
        Target states; components 0 and 1 are the position ``X, Y`` in metres.
    sensors_m : (..., N, 2) float
        Sensor positions, metres; leading dimensions broadcast against ``target``'s.

    Returns
    -------
    (..., N) float
        Bearings, radians.
    """
    diff = _offsets(target, sensors_m)
    return np.arctan2(diff[..., 1], diff[..., 0])


def bearing_jacobian(target: ArrayLike, sensors_m: ArrayLike) -> FloatArray:
    """Jacobian of :func:`bearing_rad` with respect to the target state.

    ``d theta / dX = -(Y - y_i) / r_i^2``, ``d theta / dY = (X - x_i) / r_i^2`` (the rows of the thesis'
    bearing-only HDOP matrix, Appendix B). At zero range the bearing is undefined; the row is zero there
    (no information), as for :func:`range_jacobian`.

    Returns
    -------
    (..., N, d) float
        Rows ``dh_i / dx``, radians per metre in the position columns, zero elsewhere.
    """
    t = np.asarray(target, dtype=float)
    diff = _offsets(t, sensors_m)
    r2 = np.sum(diff * diff, axis=-1, keepdims=True)
    rot = np.stack([-diff[..., 1], diff[..., 0]], axis=-1)
    d_xy = np.divide(rot, r2, out=np.zeros_like(rot), where=r2 > 0.0)
    return _state_jacobian(d_xy, t.shape[-1])


def horizontal_range_m(target: ArrayLike, sensors_m: ArrayLike) -> FloatArray:
    """Horizontal range from each sensor to the target, eq. (II.4).

    Parameters
    ----------
    target : (..., d) float
        Target states; components 0 and 1 are ``X, Y`` in metres.
    sensors_m : (..., N, 2) float

    Returns
    -------
    (..., N) float
        Ranges, metres.
    """
    diff = _offsets(target, sensors_m)
    return np.sqrt(np.sum(diff * diff, axis=-1))


def horizontal_range_jacobian(target: ArrayLike, sensors_m: ArrayLike) -> FloatArray:
    """Jacobian of :func:`horizontal_range_m`: the unit vector from sensor to target, eq. (IV.11).

    Zero at zero range, where the derivative does not exist.

    Returns
    -------
    (..., N, d) float
        Dimensionless in the position columns, zero elsewhere.
    """
    t = np.asarray(target, dtype=float)
    diff = _offsets(t, sensors_m)
    dist = np.sqrt(np.sum(diff * diff, axis=-1, keepdims=True))
    unit = np.divide(diff, dist, out=np.zeros_like(diff), where=dist > 0.0)
    return _state_jacobian(unit, t.shape[-1])


def sensor_pairs(n_sensors: int, kind: str = "all") -> np.ndarray:
    """Sensor index pairs ``(i, j)`` for TDOA measurements ``tau_ij = tau_i - tau_j``.

    Parameters
    ----------
    n_sensors : int
        Number of sensors ``N >= 2``.
    kind : {"all", "reference"}
        ``all``: every pair ``i < j`` (``N (N - 1) / 2`` rows; for three sensors ``(0, 1), (0, 2), (1, 2)``);
        ``reference``: ``(0, j)`` for ``j = 1 .. N-1``, the ``N - 1`` independent differences.

    Returns
    -------
    (P, 2) int
    """
    if n_sensors < 2:
        raise ValueError(f"TDOA needs at least two sensors, got {n_sensors}")
    if kind == "all":
        return np.array([(i, j) for i in range(n_sensors) for j in range(i + 1, n_sensors)], dtype=np.int64)
    if kind == "reference":
        return np.array([(0, j) for j in range(1, n_sensors)], dtype=np.int64)
    raise ValueError(f"pair kind must be 'all' or 'reference', got {kind!r}")


def _check_pairs(pairs: ArrayLike, n_sensors: int) -> np.ndarray:
    p = np.asarray(pairs, dtype=np.int64)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] == 0:
        raise ValueError(f"pairs must be a (P, 2) integer array, got shape {p.shape}")
    if p.min() < 0 or p.max() >= n_sensors or np.any(p[:, 0] == p[:, 1]):
        raise ValueError(f"pairs must index two different sensors among {n_sensors}")
    return p


def tdoa_s(
    target: ArrayLike, sensors_m: ArrayLike, pairs: ArrayLike, sound_speed_mps: float = 1500.0
) -> FloatArray:
    """Time differences of arrival, eq. (II.7): ``tau_ij = (r_i - r_j) / c``.

    Sign convention: ``tau_ij > 0`` when the signal reaches sensor ``j`` first (sensor ``i`` is farther).

    Parameters
    ----------
    target : (..., d) float
    sensors_m : (..., N, 2) float
    pairs : (P, 2) int
        Sensor indices ``(i, j)`` of each measurement (:func:`sensor_pairs`).
    sound_speed_mps : float
        Sound speed ``c``.

    Returns
    -------
    (..., P) float
        Time differences, seconds.
    """
    r = horizontal_range_m(target, sensors_m)
    p = _check_pairs(pairs, r.shape[-1])
    return (r[..., p[:, 0]] - r[..., p[:, 1]]) / sound_speed_mps


def tdoa_jacobian(
    target: ArrayLike, sensors_m: ArrayLike, pairs: ArrayLike, sound_speed_mps: float = 1500.0
) -> FloatArray:
    """Jacobian of :func:`tdoa_s`, eq. (IV.13): ``(u_i - u_j) / c`` with ``u`` the unit line-of-sight vectors.

    Returns
    -------
    (..., P, d) float
        Seconds per metre in the position columns, zero elsewhere.
    """
    unit = horizontal_range_jacobian(target, sensors_m)
    p = _check_pairs(pairs, unit.shape[-2])
    return (unit[..., p[:, 0], :] - unit[..., p[:, 1], :]) / sound_speed_mps


# --- Two-way travel time (GNSS-Acoustic): down from the transmit position, back up to the receive one ---


def two_way_range_m(target_m: ArrayLike, transmit_m: ArrayLike, receive_m: ArrayLike) -> FloatArray:
    """Acoustic path length of a two-way ping, ``|p_T - p_tx| + |p_T - p_rx|``.

    The surface transducer moves between transmit and receive (a Wave Glider travels ~0.3 m in a
    0.4 s two-way time), so the down and up legs start and end at different points: the two-leg
    generalization of Garcia et al. (2019) eq. (3).

    Parameters
    ----------
    target_m : (..., 3) float
        Transponder positions, metres.
    transmit_m, receive_m : (..., 3) float
        Transducer positions at transmit and at receive, metres; broadcast against ``target_m``.

    Returns
    -------
    (...) float
        Two-way path length, metres.
    """
    return range_m(target_m, transmit_m) + range_m(target_m, receive_m)


def two_way_range_jacobian(target_m: ArrayLike, transmit_m: ArrayLike, receive_m: ArrayLike) -> FloatArray:
    """Jacobian of :func:`two_way_range_m` with respect to the target: the sum of the two unit
    line-of-sight vectors (eq. (8) for each leg).

    Returns
    -------
    (..., 3) float
    """
    return range_jacobian(target_m, transmit_m) + range_jacobian(target_m, receive_m)


def two_way_travel_time_s(
    target_m: ArrayLike,
    transmit_m: ArrayLike,
    receive_m: ArrayLike,
    sound_speed_mps: ArrayLike,
    turnaround_s: ArrayLike = 0.0,
) -> FloatArray:
    """Two-way travel time under a straight-ray, constant-sound-speed model.

    ``TWTT = (|p_T - p_tx| + |p_T - p_rx|) / c + tau``, with ``tau`` the transponder's turn-around
    delay (zero for files that have already removed it, as the La Jolla files have).

    Parameters
    ----------
    target_m, transmit_m, receive_m : (..., 3) float
        Metres.
    sound_speed_mps : (...) float
        Effective (harmonic-mean) sound speed along the path, m/s.
    turnaround_s : (...) float
        Turn-around delay, seconds.

    Returns
    -------
    (...) float
        Seconds.
    """
    c = np.asarray(sound_speed_mps, dtype=float)
    return two_way_range_m(target_m, transmit_m, receive_m) / c + np.asarray(turnaround_s, dtype=float)


def two_way_travel_time_jacobian(
    target_m: ArrayLike, transmit_m: ArrayLike, receive_m: ArrayLike, sound_speed_mps: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Jacobians of :func:`two_way_travel_time_s` with respect to the target and the sound speed.

    Returns
    -------
    d_target : (..., 3) float
        ``(u_tx + u_rx) / c``, seconds per metre.
    d_sound_speed : (...) float
        ``-(|p_T - p_tx| + |p_T - p_rx|) / c^2``, seconds per (m/s).
    """
    c = np.asarray(sound_speed_mps, dtype=float)
    d_target = two_way_range_jacobian(target_m, transmit_m, receive_m) / c[..., None]
    d_speed = -two_way_range_m(target_m, transmit_m, receive_m) / (c * c)
    return d_target, d_speed


def two_way_range_sigma_m(
    target_m: ArrayLike,
    transmit_m: ArrayLike,
    receive_m: ArrayLike,
    sigma_transmit_m: ArrayLike,
    sigma_receive_m: ArrayLike,
    sigma_path_m: ArrayLike = 0.0,
) -> FloatArray:
    """Standard deviation of a two-way path-length measurement ``c * TWTT`` (journal eqs. 46-52,
    generalized to two legs and per-axis GNSS sigmas).

    The journal folds the GPS error into the range noise: the range residual is
    ``delta z = h delta p_T + w - h delta p_V`` (52), so the GPS error contributes ``q = h delta p_V``
    with variance ``h Sigma_V h^T`` (the GPS covariance projected on the line of sight). Here each leg
    has its own line of sight ``u_tx``, ``u_rx`` and its own (independent, diagonal) GNSS covariance:

        sigma^2 = sigma_path^2 + sum_axes (u_tx * sigma_tx)^2 + sum_axes (u_rx * sigma_rx)^2

    where ``sigma_path`` is everything else (timing noise ``c sigma_t``, unmodelled propagation).

    Parameters
    ----------
    target_m, transmit_m, receive_m : (..., 3) float
        Metres.
    sigma_transmit_m, sigma_receive_m : (..., 3) float
        1-sigma of the transducer positions per axis, metres.
    sigma_path_m : (...) float
        Remaining path-length noise, metres.

    Returns
    -------
    (...) float
        Metres.
    """
    u_tx = range_jacobian(target_m, transmit_m)
    u_rx = range_jacobian(target_m, receive_m)
    s_tx = np.asarray(sigma_transmit_m, dtype=float)
    s_rx = np.asarray(sigma_receive_m, dtype=float)
    var = np.sum((u_tx * s_tx) ** 2, axis=-1) + np.sum((u_rx * s_rx) ** 2, axis=-1)
    return np.sqrt(var + np.asarray(sigma_path_m, dtype=float) ** 2)
