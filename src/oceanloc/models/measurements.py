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
