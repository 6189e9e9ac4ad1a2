"""Drift integration: where a passive drifter goes in a current field.

Two one-step maps, both usable on Python floats (sequential planners) and on arrays (whole batches of
particles or tree nodes at once):

- :func:`euler_step`, ``p + dt v(p, t)``: the thesis' dead-reckoning step (Dillard, IV.C, ``dt = 60 s``),
  first order; on the thesis' piecewise-constant field it *is* the thesis' dynamics.
- :func:`rk4_step`, classical fourth-order Runge-Kutta: for continuous fields, global error ``O(dt^4)``.

:func:`integrate` runs either over many particles and steps and stops each particle where the current is
undefined (``NaN``: off the grid, on land, outside the time span) or where the optional ``is_free`` check
fails (an obstacle, the map boundary). A stopped particle keeps its last valid position and is flagged;
nothing is ever advanced with a zero current it does not have.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, TypeAlias

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.models.currents import CurrentField, Scalar

Method: TypeAlias = Literal["rk4", "euler"]
METHODS: tuple[str, ...] = ("rk4", "euler")

STOP_COMPLETED = 0
STOP_NO_CURRENT = 1
STOP_BLOCKED = 2
STOP_REASONS: tuple[str, ...] = (
    "completed",
    "no current (off the field, land or outside its time span)",
    "blocked",
)


def euler_step(
    field: CurrentField, x_m: Scalar, y_m: Scalar, time_s: Scalar, dt_s: float
) -> tuple[Scalar, Scalar]:
    """One explicit Euler step ``p + dt v(p, t)``; ``NaN`` where the current is undefined."""
    u, v = field.velocity_xy(x_m, y_m, time_s)
    return x_m + dt_s * u, y_m + dt_s * v


def rk4_step(
    field: CurrentField, x_m: Scalar, y_m: Scalar, time_s: Scalar, dt_s: float
) -> tuple[Scalar, Scalar]:
    """One classical Runge-Kutta step (global error ``O(dt^4)``); ``NaN`` if any stage is undefined."""
    half = 0.5 * dt_s
    u1, v1 = field.velocity_xy(x_m, y_m, time_s)
    u2, v2 = field.velocity_xy(x_m + half * u1, y_m + half * v1, time_s + half)
    u3, v3 = field.velocity_xy(x_m + half * u2, y_m + half * v2, time_s + half)
    u4, v4 = field.velocity_xy(x_m + dt_s * u3, y_m + dt_s * v3, time_s + dt_s)
    sixth = dt_s / 6.0
    return (
        x_m + sixth * (u1 + 2.0 * (u2 + u3) + u4),
        y_m + sixth * (v1 + 2.0 * (v2 + v3) + v4),
    )


def step_function(method: Method) -> Callable[..., tuple[Scalar, Scalar]]:
    """The one-step map for ``method``."""
    if method == "rk4":
        return rk4_step
    if method == "euler":
        return euler_step
    raise ConfigError(f"drift integrator must be one of {', '.join(METHODS)}; got '{method}'")


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftTrack:
    """Trajectories of a batch of drifters.

    Attributes
    ----------
    positions_m : (P, K + 1, 2) float
        Positions at every step; after a particle stops, its last valid position repeats.
    times_s : (K + 1,) float
        Times of the steps.
    alive : (P, K + 1) bool
        Whether the particle was still drifting at each step (``False`` after it stopped).
    stop_step : (P,) int
        Index of the last valid step of each particle.
    stop_reason : (P,) int
        ``STOP_COMPLETED``, ``STOP_NO_CURRENT`` or ``STOP_BLOCKED``; see :data:`STOP_REASONS`.
    """

    positions_m: FloatArray
    times_s: FloatArray
    alive: BoolArray
    stop_step: IntArray
    stop_reason: IntArray

    @property
    def final_m(self) -> FloatArray:
        """``(P, 2)`` last valid position of each particle."""
        return self.positions_m[np.arange(self.positions_m.shape[0]), self.stop_step]


def integrate(
    field: CurrentField,
    positions_m: ArrayLike,
    *,
    dt_s: float,
    n_steps: int,
    t0_s: float = 0.0,
    method: Method = "rk4",
    is_free: Callable[[FloatArray, FloatArray], BoolArray] | None = None,
) -> DriftTrack:
    """Drift a batch of particles for ``n_steps`` steps of ``dt_s``.

    Parameters
    ----------
    field : CurrentField
        The current.
    positions_m : (P, 2) float
        Initial positions, metres.
    dt_s : float
        Step, seconds (negative integrates backward in time).
    n_steps : int
        Number of steps ``K``.
    t0_s : float
        Initial time.
    method : {"rk4", "euler"}
        One-step map.
    is_free : callable ``(x (n,), y (n,)) -> (n,) bool``, optional
        Validity of a new position (obstacles, map bounds); a particle stops before entering an invalid
        position.

    Returns
    -------
    DriftTrack
    """
    step = step_function(method)
    p0 = np.atleast_2d(np.asarray(positions_m, dtype=float))
    if p0.shape[-1] != 2 or p0.ndim != 2:
        raise ValueError(f"positions must have shape (P, 2), got {np.shape(positions_m)}")
    if n_steps < 0 or not math.isfinite(dt_s) or dt_s == 0.0:
        raise ConfigError(f"drift needs n_steps >= 0 and a finite non-zero dt, got {n_steps} and {dt_s}")
    n = p0.shape[0]
    out = np.empty((n, n_steps + 1, 2))
    out[:, 0] = p0
    alive = np.zeros((n, n_steps + 1), dtype=bool)
    alive[:, 0] = np.all(np.isfinite(p0), axis=1)
    stop_step = np.zeros(n, dtype=np.int64)
    reason = np.full(n, STOP_COMPLETED, dtype=np.int64)
    reason[~alive[:, 0]] = STOP_NO_CURRENT
    x = p0[:, 0].copy()
    y = p0[:, 1].copy()
    active = np.flatnonzero(alive[:, 0])
    times = t0_s + dt_s * np.arange(n_steps + 1)
    for k in range(1, n_steps + 1):
        if active.size:
            xn, yn = step(field, x[active], y[active], times[k - 1], dt_s)
            # A particle never steps onto a point where the current is undefined (land, off the grid).
            un, vn = field.velocity_xy(xn, yn, times[k])
            defined = np.isfinite(xn) & np.isfinite(yn) & np.isfinite(un) & np.isfinite(vn)
            ok = defined.copy()
            if is_free is not None and ok.any():
                ok[ok] = is_free(xn[ok], yn[ok])
            reason[active[~defined]] = STOP_NO_CURRENT
            reason[active[defined & ~ok]] = STOP_BLOCKED
            active = active[ok]
            x[active] = xn[ok]
            y[active] = yn[ok]
            stop_step[active] = k
            alive[active, k] = True
        out[:, k, 0] = x
        out[:, k, 1] = y
    return DriftTrack(positions_m=out, times_s=times, alive=alive, stop_step=stop_step, stop_reason=reason)
