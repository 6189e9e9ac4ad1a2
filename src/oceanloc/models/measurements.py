"""Measurement models: each ``h(x)`` with its analytic Jacobian beside it.

Range (Garcia et al. 2019, eq. (3)-(4), Jacobian eq. (8)): the distance between a sensor and a
target, ``r = ||p_T - p_V||``, measured with additive Gaussian noise. Functions broadcast over leading
batch dimensions (runs, transponders, measurements, sigma points); they never mutate their inputs.
"""

from __future__ import annotations

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
