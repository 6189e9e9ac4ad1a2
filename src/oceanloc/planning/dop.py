"""Horizontal dilution of precision (HDOP) for bearing, range and TDOA measurements.

Dillard (AquaQuad thesis), Chapter IV.A: ``HDOP = sqrt(trace((H^T R^-1 H)^-1))`` (eq. IV.9; eq. IV.6 is the
special case ``R = I``), where ``H`` holds the Jacobians of the measurements with respect to the target's
horizontal position. With ``sigma`` the measurement standard deviation (radians for bearings, metres for
ranges, seconds for TDOA), HDOP is the square root of the trace of the position Cramer-Rao bound of one
snapshot, in metres; with ``sigma = 1`` it is the thesis' unit-weight geometric factor.

Everything is batched: ``nodes_m (..., n, 2)`` and ``target_m (..., 2)`` broadcast, so a whole grid of
candidate node positions or a time series of flock geometries is one call. Singular geometries (all lines
of sight parallel, fewer independent measurements than two) give ``inf``.
"""

from __future__ import annotations

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.estimation.bounds import hdop_from_jacobian
from oceanloc.models.measurements import (
    MEASUREMENT_KINDS,
    MeasurementKind,
    bearing_jacobian,
    horizontal_range_jacobian,
    sensor_pairs,
    tdoa_jacobian,
)

__all__ = ["MEASUREMENT_KINDS", "MeasurementKind", "hdop", "hdop_from_jacobian", "position_jacobian"]


def position_jacobian(
    nodes_m: ArrayLike,
    target_m: ArrayLike,
    kind: MeasurementKind,
    *,
    pairs: ArrayLike | None = None,
    sound_speed_mps: float = 1500.0,
) -> FloatArray:
    """Measurement Jacobian ``H`` with respect to the target's horizontal position.

    Parameters
    ----------
    nodes_m : (..., n, 2) float
        Sensor node positions, metres.
    target_m : (..., 2) float
        Target position, metres; broadcast against ``nodes_m``'s leading dimensions.
    kind : {"bearing", "range", "tdoa"}
        Measurement type: eqs. (II.3), (II.4), (II.7).
    pairs : (P, 2) int, optional
        TDOA sensor pairs; every pair ``i < j`` by default (the thesis' lab filter uses all three pairs of
        three nodes).
    sound_speed_mps : float
        Sound speed for TDOA.

    Returns
    -------
    (..., m, 2) float
        ``m = n`` for bearing and range, ``m = P`` for TDOA.
    """
    nodes = np.asarray(nodes_m, dtype=float)
    target = np.asarray(target_m, dtype=float)[..., :2]
    if kind == "bearing":
        return bearing_jacobian(target, nodes)
    if kind == "range":
        return horizontal_range_jacobian(target, nodes)
    if kind == "tdoa":
        p = sensor_pairs(nodes.shape[-2]) if pairs is None else pairs
        return tdoa_jacobian(target, nodes, p, sound_speed_mps)
    raise ValueError(f"measurement kind must be one of {', '.join(MEASUREMENT_KINDS)}; got {kind!r}")


def hdop(
    nodes_m: ArrayLike,
    target_m: ArrayLike,
    kind: MeasurementKind,
    sigma: ArrayLike = 1.0,
    *,
    pairs: ArrayLike | None = None,
    sound_speed_mps: float = 1500.0,
) -> FloatArray:
    """Horizontal dilution of precision of a flock of nodes observing a target, eqs. (IV.6)/(IV.9).

    Parameters
    ----------
    nodes_m : (..., n, 2) float
        Node positions, metres.
    target_m : (..., 2) float
        Target position, metres; broadcast against ``nodes_m``'s leading dimensions.
    kind : {"bearing", "range", "tdoa"}
        Measurement type.
    sigma : float or (..., m) float
        Measurement standard deviation: radians (bearing), metres (range) or seconds (TDOA). With
        ``sigma = 1`` the result is the thesis' geometric HDOP (eq. IV.6, in m/rad for bearings, dimensionless
        for ranges, m/s for TDOA); with the real sigma it is the snapshot position standard error in metres.
    pairs : (P, 2) int, optional
        TDOA pairs (default: all pairs).
    sound_speed_mps : float
        Sound speed ``c`` for TDOA.

    Returns
    -------
    (...) float
        HDOP; ``inf`` for singular geometries.

    Examples
    --------
    >>> import numpy as np
    >>> ring = 100.0 * np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    >>> float(hdop(ring, np.zeros(2), "range"))  # four ranges at right angles: sqrt(2 / 2)
    1.0
    """
    jac = position_jacobian(nodes_m, target_m, kind, pairs=pairs, sound_speed_mps=sound_speed_mps)
    return hdop_from_jacobian(jac, sigma)
