"""Powered legs of a drifting vehicle: through the air (unaffected by the current) or through the water.

A drift plan alternates passive drift with powered legs. How long a straight leg from ``a`` to ``b``
takes depends on what the vehicle moves through:

- ``"air"``: a flying vehicle (the AquaQuad, Dillard II.C) crosses the leg at its flight speed ``F``
  whatever the water does: ``tau = |b - a| / F``; its energy is ``P tau`` (IV.14).
- ``"water"``: a boat, a surface vehicle or a glider moves at ``F`` through the water and is carried by the
  current ``w``. Holding its course over ground along ``a -> b`` (what an autopilot's line following does,
  crabbing into the cross current), its ground speed along the track is

      g = w . e + sqrt(F^2 - (w . n)^2)

  with ``e`` the unit vector of the track and ``n`` its normal (Zermelo's navigation problem with the
  heading chosen to stay on the line). The leg's time is ``tau = integral_0^L ds / g(s, t(s))``, integrated
  here with classical Runge-Kutta in the arc length (``dt/ds = 1 / g``), so a current that changes in time
  during the leg is followed. A leg is infeasible where the cross current reaches ``F``, where the vehicle
  would make no headway, or where the current is undefined (land, off the grid). The energy is again
  ``P tau``.

Both are pure functions on batches of legs (the batch dimension first), used by the planners, the
re-simulation of plans and the path follower.
"""

from __future__ import annotations

import math
from typing import Literal, TypeAlias, get_args

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray
from oceanloc.errors import ConfigError
from oceanloc.models.currents import CurrentField

Propulsion: TypeAlias = Literal["air", "water"]
PROPULSIONS: tuple[str, ...] = get_args(Propulsion)

MIN_HEADWAY = 1e-3
"""Slowest ground speed along a water leg, as a fraction of the vehicle's speed (slower: infeasible)."""

MAX_LEG_SUBSTEP_S = 300.0
"""Longest Runge-Kutta step of a water leg at the vehicle's own speed, seconds (a current that changes over
hours is followed to well under a second per leg)."""


def check_propulsion(name: str, where: str = "propulsion") -> Propulsion:
    """``name`` as a propulsion medium; a ConfigError naming ``where`` and the choices otherwise."""
    if name not in PROPULSIONS:
        raise ConfigError(f"{where} must be one of {', '.join(PROPULSIONS)}; got '{name}'")
    return name  # type: ignore[return-value]


def water_ground_speed(
    u_mps: FloatArray, v_mps: FloatArray, ex: FloatArray, ey: FloatArray, speed_mps: float
) -> FloatArray:
    """Ground speed along a track of unit direction ``(ex, ey)`` of a vehicle holding that course at
    ``speed_mps`` through water moving at ``(u, v)``; ``NaN`` where it cannot hold the course or make
    headway (cross current at least the speed, or along-track ground speed below :data:`MIN_HEADWAY`)."""
    along = u_mps * ex + v_mps * ey
    cross = -u_mps * ey + v_mps * ex
    rest = speed_mps * speed_mps - cross * cross
    with np.errstate(invalid="ignore"):
        g = along + np.sqrt(np.where(rest > 0.0, rest, np.nan))
    return np.where(g > MIN_HEADWAY * speed_mps, g, np.nan)


def leg_times_s(
    propulsion: Propulsion,
    field: CurrentField,
    start_m: ArrayLike,
    end_m: ArrayLike,
    t0_s: ArrayLike,
    speed_mps: float,
    *,
    substeps: int | None = None,
) -> tuple[FloatArray, BoolArray]:
    """Time of straight powered legs ``start -> end`` begun at ``t0``, and whether each is feasible.

    Parameters
    ----------
    propulsion : {"air", "water"}
        See the module docstring.
    field : CurrentField
        The current (unused in the air).
    start_m, end_m : (..., 2) float
        Leg ends, metres.
    t0_s : (...) float
        Start times, seconds (broadcast against the legs).
    speed_mps : float
        Speed through the medium.
    substeps : int, optional
        Runge-Kutta steps per leg (water); by default enough that none is longer than
        :data:`MAX_LEG_SUBSTEP_S` at the vehicle's speed (at least 2).

    Returns
    -------
    tau_s : (...) float
        Leg times; ``inf`` where infeasible, 0 for legs of zero length.
    feasible : (...) bool
    """
    if not speed_mps > 0:
        raise ConfigError(f"powered speed must be positive, got {speed_mps}")
    a = np.asarray(start_m, dtype=float)
    b = np.asarray(end_m, dtype=float)
    a, b = np.broadcast_arrays(a, b)
    d = b - a
    length = np.sqrt(d[..., 0] ** 2 + d[..., 1] ** 2)
    if propulsion == "air":
        tau = length / speed_mps
        ok = np.isfinite(tau)
        return np.where(ok, tau, np.inf), ok
    check_propulsion(propulsion)
    t0 = np.broadcast_to(np.asarray(t0_s, dtype=float), length.shape)
    safe = np.where(length > 0.0, length, 1.0)
    ex = d[..., 0] / safe
    ey = d[..., 1] / safe
    if substeps is None:
        longest = float(np.max(length, initial=0.0)) if length.size else 0.0
        substeps = max(2, math.ceil(longest / (speed_mps * MAX_LEG_SUBSTEP_S)))
    n = int(substeps)
    h = length / n

    def rate(s: FloatArray, t: FloatArray) -> FloatArray:
        x = a[..., 0] + s * ex
        y = a[..., 1] + s * ey
        u, v = field.velocity_xy(x, y, t)
        return 1.0 / water_ground_speed(np.asarray(u), np.asarray(v), ex, ey, speed_mps)

    t = t0.copy()
    s = np.zeros_like(length)
    for _ in range(n):
        k1 = rate(s, t)
        k2 = rate(s + 0.5 * h, t + 0.5 * h * k1)
        k3 = rate(s + 0.5 * h, t + 0.5 * h * k2)
        k4 = rate(s + h, t + h * k3)
        t = t + h / 6.0 * (k1 + 2.0 * (k2 + k3) + k4)
        s = s + h
    tau = np.where(length > 0.0, t - t0, 0.0)
    ok = np.isfinite(tau)
    return np.where(ok, tau, np.inf), ok
