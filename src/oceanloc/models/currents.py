"""Ocean surface currents: one interface, analytic fields and regular grids.

A current field gives the horizontal water velocity (east, north) in m/s at positions in a local metric
frame (metres east and north of an origin) and, for time-dependent fields, at times in seconds. Every field
implements :meth:`CurrentField.velocity_xy`, which accepts Python floats (the scalar fast path used inside
sequential planners) or NumPy arrays of any shape (the batch path), and :meth:`CurrentField.velocity` on
stacked ``(..., 2)`` positions.

A velocity is ``NaN`` where the field is undefined: outside the grid, outside its time span, or on land
(``NaN`` cells of a gridded product). Integrators stop a particle there instead of drifting it in a silent
zero current (see :mod:`oceanloc.models.drift`).

Fields
------
- :class:`UniformCurrent`, :class:`LinearCurrent` (``v = A x + b``; exact solutions exist, used to check
  the integrators).
- :class:`VortexCurrent`: the AquaQuad thesis' analytic vortex (Dillard, Appendix C):
  ``u = -x - 2 y x^2 + y``, ``v = -x - y`` in coordinates scaled by 1/10 km, velocities in m/s.
- :func:`thesis_vortex_grid`: the same vortex sampled as the thesis samples it, on a 21 x 21 mesh of
  spacing 0.05 (500 m), either piecewise constant per cell (the thesis' ``CellFinder`` lookup) or
  bilinearly interpolated.
- :class:`DoubleGyreCurrent`: the time-periodic double gyre (Shadden, Lekien and Marsden 2005), a standard
  test field with known structure.
- :class:`GridCurrent`: any regular grid in metres, with optional time axis; gridded products (CF NetCDF)
  arrive here through :mod:`oceanloc.models.currents_cf`.
- :class:`TidalCurrent`: the same velocity everywhere, oscillating in time (a tidal stream); with its exact
  displacement it gives Zermelo's time-optimal navigation in closed form.
- :class:`RankineVortexCurrent`: a Rankine vortex (solid-body core, irrotational outside) whose strength
  pulses in time and whose centre is carried by a background current.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Protocol, TypeAlias, runtime_checkable

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError, DataError

Interpolation: TypeAlias = Literal["linear", "cell"]
INTERPOLATIONS: tuple[str, ...] = ("linear", "cell")

Scalar: TypeAlias = float | FloatArray


@runtime_checkable
class CurrentField(Protocol):
    """Horizontal current velocity in a local metric frame.

    ``velocity_xy(x_m, y_m, time_s)`` works on floats and on broadcastable arrays and returns
    ``(u_mps, v_mps)`` (east, north); ``NaN`` where the field is undefined.
    """

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]: ...

    def velocity(self, positions_m: ArrayLike, time_s: ArrayLike = 0.0) -> FloatArray: ...

    @property
    def bounds_m(self) -> tuple[float, float, float, float] | None:
        """``(x_min, x_max, y_min, y_max)`` where the field is defined, or ``None`` if unbounded."""
        ...


class _FieldBase:
    """Shared ``velocity`` on stacked positions, built on ``velocity_xy``."""

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        raise NotImplementedError

    def velocity(self, positions_m: ArrayLike, time_s: ArrayLike = 0.0) -> FloatArray:
        """Velocity at stacked positions.

        Parameters
        ----------
        positions_m : (..., 2) float
            East, north in metres.
        time_s : float or (...) float
            Time in seconds (ignored by steady fields).

        Returns
        -------
        (..., 2) float
            East and north velocity, m/s; ``NaN`` where undefined.
        """
        p = np.asarray(positions_m, dtype=float)
        if p.shape[-1:] != (2,):
            raise ValueError(f"positions must have shape (..., 2), got {p.shape}")
        u, v = self.velocity_xy(p[..., 0], p[..., 1], np.asarray(time_s, dtype=float))
        return np.stack(np.broadcast_arrays(u, v), axis=-1).astype(float)

    @property
    def bounds_m(self) -> tuple[float, float, float, float] | None:
        return None


@dataclass(frozen=True, slots=True, kw_only=True)
class UniformCurrent(_FieldBase):
    """The same velocity everywhere, ``(u, v)`` in m/s."""

    velocity_mps: tuple[float, float] = (0.0, 0.0)

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        u, v = self.velocity_mps
        if isinstance(x_m, float | int):
            return float(u), float(v)
        shape = np.broadcast_shapes(np.shape(x_m), np.shape(y_m))
        return np.full(shape, float(u)), np.full(shape, float(v))


@dataclass(frozen=True, slots=True, kw_only=True)
class LinearCurrent(_FieldBase):
    """A linear field ``v = A p + b``: rotation, shear, strain; exact trajectories via the matrix exponential.

    Attributes
    ----------
    matrix_per_s : ((2, 2) nested tuple) float
        ``A`` in 1/s.
    offset_mps : (2,) float
        ``b`` in m/s.
    """

    matrix_per_s: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 0.0), (0.0, 0.0))
    offset_mps: tuple[float, float] = (0.0, 0.0)

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        (a, b), (c, d) = self.matrix_per_s
        return a * x_m + b * y_m + self.offset_mps[0], c * x_m + d * y_m + self.offset_mps[1]


@dataclass(frozen=True, slots=True, kw_only=True)
class TidalCurrent(_FieldBase):
    """A uniform current oscillating in time: ``w(t) = mean + amplitude sin(2 pi t / period + phase)``.

    Attributes
    ----------
    mean_mps, amplitude_mps : (2,) float
        Mean and amplitude of the east and north components, m/s.
    period_s : float
        Period (44 714 s for the M2 tide).
    phase_rad : float
    """

    mean_mps: tuple[float, float] = (0.0, 0.0)
    amplitude_mps: tuple[float, float] = (0.0, 0.0)
    period_s: float = 44_714.0
    phase_rad: float = 0.0

    def __post_init__(self) -> None:
        if not self.period_s > 0:
            raise ConfigError(f"tidal period must be positive, got {self.period_s}")

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        w = 2.0 * math.pi / self.period_s
        if isinstance(x_m, float | int) and isinstance(time_s, float | int):
            k = math.sin(w * time_s + self.phase_rad)
            return self.mean_mps[0] + self.amplitude_mps[0] * k, self.mean_mps[1] + self.amplitude_mps[1] * k
        k = np.sin(w * np.asarray(time_s, dtype=float) + self.phase_rad)
        shape = np.broadcast_shapes(np.shape(x_m), np.shape(y_m), np.shape(k))
        u = np.broadcast_to(self.mean_mps[0] + self.amplitude_mps[0] * k, shape).astype(float)
        v = np.broadcast_to(self.mean_mps[1] + self.amplitude_mps[1] * k, shape).astype(float)
        return u, v

    def displacement_m(self, t0_s: ArrayLike, t1_s: ArrayLike) -> FloatArray:
        """``(..., 2)`` exact displacement of a drifter from ``t0`` to ``t1``: the integral of ``w``."""
        t0 = np.asarray(t0_s, dtype=float)
        t1 = np.asarray(t1_s, dtype=float)
        w = 2.0 * math.pi / self.period_s
        osc = (np.cos(w * t0 + self.phase_rad) - np.cos(w * t1 + self.phase_rad)) / w
        return np.stack(
            [self.mean_mps[i] * (t1 - t0) + self.amplitude_mps[i] * osc for i in range(2)], axis=-1
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class RankineVortexCurrent(_FieldBase):
    """A Rankine vortex whose strength pulses and whose centre drifts with a background current.

    Around the centre ``c(t) = centre + background t`` the azimuthal speed is ``V(t) r / R`` inside the core
    (radius ``R``, solid-body rotation) and ``V(t) R / r`` outside (irrotational), counter-clockwise for
    ``V > 0``, with ``V(t) = peak (1 + pulse sin(2 pi t / period))``; the background current is added
    everywhere, so the vortex is carried by the flow it sits in (an eddy shed by a headland).

    Attributes
    ----------
    centre_m : (2,) float
    core_radius_m : float
    peak_speed_mps : float
    pulse : float
        Relative amplitude of the strength's oscillation (0: steady strength).
    period_s : float
    background_mps : (2,) float
    """

    centre_m: tuple[float, float] = (0.0, 0.0)
    core_radius_m: float = 2000.0
    peak_speed_mps: float = 0.5
    pulse: float = 0.0
    period_s: float = 21_600.0
    background_mps: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if not (self.core_radius_m > 0 and self.period_s > 0):
            raise ConfigError("a Rankine vortex needs a positive core radius and period")

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        bu, bv = self.background_mps
        t = np.asarray(time_s, dtype=float)
        if t.ndim == 0:
            tf = float(t)
            strength = self.peak_speed_mps * (1.0 + self.pulse * math.sin(2.0 * math.pi * tf / self.period_s))
            cx, cy = self.centre_m[0] + bu * tf, self.centre_m[1] + bv * tf
        else:
            strength = self.peak_speed_mps * (1.0 + self.pulse * np.sin((2.0 * math.pi / self.period_s) * t))
            cx, cy = self.centre_m[0] + bu * t, self.centre_m[1] + bv * t
        dx = np.asarray(x_m, dtype=float) - cx
        dy = np.asarray(y_m, dtype=float) - cy
        r2 = dx * dx + dy * dy
        big_r = self.core_radius_m
        # v_theta / r: V / R inside the core, V R / r^2 outside.
        k = np.maximum(r2, big_r * big_r)
        k = (strength * big_r) / k
        u = bu - k * dy
        v = bv + k * dx
        if np.ndim(u) == 0:
            return float(u), float(v)
        return u, v


THESIS_VORTEX_SCALE_M = 10_000.0
"""The thesis scales its unit-square vortex mesh by 10 km (``SF = 10000``)."""

THESIS_VORTEX_SPACING = 0.05
"""Mesh spacing of the thesis vortex in unscaled units (500 m after scaling)."""


def is_steady(field: CurrentField) -> bool:
    """Whether ``field`` is the same at every time (planners may then drift every leg from any time).

    Uniform, linear and vortex fields are steady; a double gyre is steady only with ``epsilon = 0``, a grid
    only without a time axis (or with a single slice). Any other field is taken as time-varying, which is
    always safe: planners then integrate every leg from its own start time.
    """
    if isinstance(field, UniformCurrent | LinearCurrent | VortexCurrent):
        return True
    if isinstance(field, DoubleGyreCurrent):
        return field.epsilon == 0.0 or field.omega_rad_s == 0.0
    if isinstance(field, GridCurrent):
        return field.time_s is None or field.time_s.size < 2
    if isinstance(field, TidalCurrent):
        return field.amplitude_mps == (0.0, 0.0)
    if isinstance(field, RankineVortexCurrent):
        return field.pulse == 0.0 and field.background_mps == (0.0, 0.0)
    return False


def time_span_s(field: CurrentField) -> tuple[float, float] | None:
    """``(first, last)`` time the field is defined at, seconds, or ``None`` if defined at every time."""
    if isinstance(field, GridCurrent) and field.time_s is not None and field.time_s.size >= 2:
        return float(field.time_s[0]), float(field.time_s[-1])
    return None


def vortex_velocity_xy(
    x_m: Scalar, y_m: Scalar, scale_m: float = THESIS_VORTEX_SCALE_M
) -> tuple[Scalar, Scalar]:
    """The thesis' analytic vortex (Dillard, Appendix C), velocities in m/s.

    With ``x = x_m / scale_m`` and ``y = y_m / scale_m``: ``u = -x - 2 y x^2 + y``, ``v = -x - y``. The
    origin is a stable focus (eigenvalues ``(-1 +- i) / scale_m`` per second): drifters spiral into the
    centre with an e-folding time of ``scale_m`` seconds (2.8 h at 10 km).
    """
    x = x_m / scale_m
    y = y_m / scale_m
    return -x - 2.0 * y * x * x + y, -x - y


@dataclass(frozen=True, slots=True, kw_only=True)
class VortexCurrent(_FieldBase):
    """The thesis vortex evaluated analytically (the continuous field), optionally bounded.

    Attributes
    ----------
    scale_m : float
        Metres per unscaled unit (10 km in the thesis).
    half_width_m : float or None
        If given, the field is defined on ``[-w, w]^2`` only (``NaN`` outside), like the thesis map.
    """

    scale_m: float = THESIS_VORTEX_SCALE_M
    half_width_m: float | None = None

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        u, v = vortex_velocity_xy(x_m, y_m, self.scale_m)
        w = self.half_width_m
        if w is None:
            return u, v
        if isinstance(x_m, float | int) and isinstance(y_m, float | int):
            if abs(x_m) > w or abs(y_m) > w:
                return math.nan, math.nan
            return u, v
        outside = (np.abs(x_m) > w) | (np.abs(y_m) > w)
        return np.where(outside, np.nan, u), np.where(outside, np.nan, v)

    @property
    def bounds_m(self) -> tuple[float, float, float, float] | None:
        w = self.half_width_m
        return None if w is None else (-w, w, -w, w)


@dataclass(frozen=True, slots=True, kw_only=True)
class DoubleGyreCurrent(_FieldBase):
    """Time-periodic double gyre on ``[0, 2L] x [0, L]`` (Shadden, Lekien, Marsden 2005).

    Stream function ``psi = (A L / pi) sin(pi f(s, t)) sin(pi y / L)`` with ``s = x / L``,
    ``f = a s^2 + b s``, ``a = eps sin(omega t)``, ``b = 1 - 2 a``; ``u = -d psi / dy``, ``v = d psi / dx``.
    Outside the domain the velocity is ``NaN``.

    Attributes
    ----------
    length_m : float
        Gyre size ``L``, metres.
    amplitude_mps : float
        Peak speed ``A``, m/s.
    epsilon : float
        Oscillation amplitude of the dividing streamline (0 gives a steady field).
    omega_rad_s : float
        Angular frequency of the oscillation.
    origin_m : (2,) float
        South-west corner of the domain.
    """

    length_m: float = 5000.0
    amplitude_mps: float = 0.5
    epsilon: float = 0.0
    omega_rad_s: float = 2.0 * math.pi / 86_400.0
    origin_m: tuple[float, float] = (0.0, 0.0)

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        if isinstance(x_m, float | int) and isinstance(y_m, float | int) and isinstance(time_s, float | int):
            return self._scalar(float(x_m), float(y_m), float(time_s))
        inv = 1.0 / self.length_m
        s = (np.asarray(x_m, dtype=float) - self.origin_m[0]) * inv
        r = (np.asarray(y_m, dtype=float) - self.origin_m[1]) * inv
        t = np.asarray(time_s, dtype=float)
        a = (
            self.epsilon * np.sin(self.omega_rad_s * t)
            if t.ndim
            else self.epsilon * math.sin(self.omega_rad_s * float(t))
        )
        b = 1.0 - 2.0 * a
        dfds = 2.0 * a * s + b
        pf = (dfds - a * s) * s * math.pi  # pi f, with f = a s^2 + b s
        pr = r * math.pi
        amp = self.amplitude_mps
        u = np.sin(pf)
        u *= np.cos(pr)
        u *= -amp
        v = np.cos(pf)
        v *= np.sin(pr)
        v *= dfds
        v *= amp
        outside = (s < 0.0) | (s > 2.0) | (r < 0.0) | (r > 1.0)
        if outside.any():
            u = np.where(outside, np.nan, u)
            v = np.where(outside, np.nan, v)
        if u.ndim == 0:
            return float(u), float(v)
        return u, v

    def _scalar(self, x: float, y: float, t: float) -> tuple[float, float]:
        """The same formula on Python floats (sequential planners and single drifts)."""
        s = (x - self.origin_m[0]) / self.length_m
        r = (y - self.origin_m[1]) / self.length_m
        if not (0.0 <= s <= 2.0 and 0.0 <= r <= 1.0):
            return math.nan, math.nan
        a = self.epsilon * math.sin(self.omega_rad_s * t)
        b = 1.0 - 2.0 * a
        f = a * s * s + b * s
        amp = self.amplitude_mps
        return (
            -amp * math.sin(math.pi * f) * math.cos(math.pi * r),
            amp * math.cos(math.pi * f) * math.sin(math.pi * r) * (2.0 * a * s + b),
        )

    @property
    def bounds_m(self) -> tuple[float, float, float, float]:
        x0, y0 = self.origin_m
        return (x0, x0 + 2.0 * self.length_m, y0, y0 + self.length_m)


@dataclass(frozen=True, slots=True, kw_only=True)
class GridCurrent(_FieldBase):
    """Velocity on a regular grid in metres, with an optional time axis.

    Attributes
    ----------
    x_m : (nx,) float
        Increasing, evenly spaced east coordinates of the grid nodes.
    y_m : (ny,) float
        Increasing, evenly spaced north coordinates.
    u_mps, v_mps : (ny, nx) or (nt, ny, nx) float
        East and north velocity at the nodes; ``NaN`` marks land or missing cells.
    time_s : (nt,) float or None
        Increasing times of the slices, seconds; ``None`` for a steady field.
    interpolation : {"linear", "cell"}
        ``linear``: bilinear in space (``NaN`` if any of the four surrounding nodes is ``NaN``, so land
        never bleeds a fake current into the sea) and linear in time. ``cell``: piecewise constant, the
        value of the node at the lower-left corner of the cell holding the point, as the thesis'
        ``CellFinder`` does; a point on the upper or right edge of the grid takes the last node.

    Outside ``[x_m[0], x_m[-1]] x [y_m[0], y_m[-1]]`` and outside ``[time_s[0], time_s[-1]]`` the velocity is
    ``NaN``: a drift simulation stops there rather than extrapolating.
    """

    x_m: FloatArray
    y_m: FloatArray
    u_mps: FloatArray
    v_mps: FloatArray
    time_s: FloatArray | None = None
    interpolation: Interpolation = "linear"
    _tables: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        x = np.asarray(self.x_m, dtype=float)
        y = np.asarray(self.y_m, dtype=float)
        u = np.asarray(self.u_mps, dtype=float)
        v = np.asarray(self.v_mps, dtype=float)
        if self.interpolation not in INTERPOLATIONS:
            raise ConfigError(
                f"interpolation must be one of {', '.join(INTERPOLATIONS)}; got '{self.interpolation}'"
            )
        for name, axis in (("x", x), ("y", y)):
            if axis.ndim != 1 or axis.size < 2:
                raise DataError(f"grid axis {name} needs at least two nodes, got shape {axis.shape}")
            step = np.diff(axis)
            if not np.all(step > 0):
                raise DataError(f"grid axis {name} must be strictly increasing")
            if not np.allclose(step, step[0], rtol=1e-6, atol=0.0):
                raise DataError(f"grid axis {name} must be evenly spaced (regrid irregular products first)")
        t = None if self.time_s is None else np.asarray(self.time_s, dtype=float)
        if u.ndim == 2:
            u, v = u[None], v[None]
        expected = (1 if t is None else t.size, y.size, x.size)
        if u.shape != expected or v.shape != expected:
            raise DataError(
                f"velocity arrays must have shape {expected} (time, y, x); got {u.shape}, {v.shape}"
            )
        if t is not None and (t.ndim != 1 or (t.size > 1 and not np.all(np.diff(t) > 0))):
            raise DataError("time axis must be one-dimensional and strictly increasing")
        for name, value in (("x_m", x), ("y_m", y), ("u_mps", u), ("v_mps", v), ("time_s", t)):
            if value is not None:
                value.setflags(write=False)
                object.__setattr__(self, name, value)
        # Python lists for the scalar path of the steady cell lookup (sequential planners).
        lists = (u[0].tolist(), v[0].tolist()) if u.shape[0] == 1 else None
        object.__setattr__(
            self, "_tables", (float(x[0]), float(y[0]), float(x[1] - x[0]), float(y[1] - y[0]), lists)
        )

    @property
    def bounds_m(self) -> tuple[float, float, float, float]:
        return (float(self.x_m[0]), float(self.x_m[-1]), float(self.y_m[0]), float(self.y_m[-1]))

    @property
    def spacing_m(self) -> tuple[float, float]:
        """Grid spacing ``(dx, dy)`` in metres."""
        return (float(self.x_m[1] - self.x_m[0]), float(self.y_m[1] - self.y_m[0]))

    def with_interpolation(self, interpolation: Interpolation) -> GridCurrent:
        """The same grid with another interpolation."""
        return GridCurrent(
            x_m=self.x_m,
            y_m=self.y_m,
            u_mps=self.u_mps,
            v_mps=self.v_mps,
            time_s=self.time_s,
            interpolation=interpolation,
        )

    def land_mask(self) -> np.ndarray:
        """``(ny, nx)`` bool: nodes whose velocity is ``NaN`` in any time slice (land or missing)."""
        return np.any(np.isnan(self.u_mps) | np.isnan(self.v_mps), axis=0)

    def velocity_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        x0, y0, dx, dy, lists = self._tables
        if lists is not None and self.interpolation == "cell" and isinstance(x_m, float | int):
            return self._cell_scalar(float(x_m), float(y_m), x0, y0, dx, dy, lists)
        x = np.asarray(x_m, dtype=float)
        y = np.asarray(y_m, dtype=float)
        nx, ny = self.x_m.size, self.y_m.size
        fx = (x - x0) / dx
        fy = (y - y0) / dy
        if lists is not None and x.ndim == 1 and fx.shape == fy.shape:
            if self.interpolation == "cell":
                return self._cell_steady(fx, fy, nx, ny)
            return self._linear_steady(fx, fy, nx, ny)
        outside = (fx < 0.0) | (fx > nx - 1) | (fy < 0.0) | (fy > ny - 1) | ~np.isfinite(fx + fy)
        fx = np.where(outside, 0.0, fx)
        fy = np.where(outside, 0.0, fy)
        slices, weights = self._time_weights(np.asarray(time_s, dtype=float))
        if self.interpolation == "cell":
            ix = np.minimum(fx.astype(np.intp), nx - 1)
            iy = np.minimum(fy.astype(np.intp), ny - 1)

            def gather(a: FloatArray, it: np.ndarray) -> FloatArray:
                return a[it, iy, ix]

        else:
            ix = np.minimum(fx.astype(np.intp), nx - 2)
            iy = np.minimum(fy.astype(np.intp), ny - 2)
            tx = fx - ix
            ty = fy - iy

            def gather(a: FloatArray, it: np.ndarray) -> FloatArray:
                return (a[it, iy, ix] * (1.0 - tx) + a[it, iy, ix + 1] * tx) * (1.0 - ty) + (
                    a[it, iy + 1, ix] * (1.0 - tx) + a[it, iy + 1, ix + 1] * tx
                ) * ty

        u = _blend_time(self.u_mps, slices, weights, gather)
        v = _blend_time(self.v_mps, slices, weights, gather)
        bad = outside | ~np.isfinite(weights[0])
        u = np.where(bad, np.nan, u)
        v = np.where(bad, np.nan, v)
        if u.ndim == 0:
            return float(u), float(v)
        return u, v

    def _cell_steady(self, fx: FloatArray, fy: FloatArray, nx: int, ny: int) -> tuple[FloatArray, FloatArray]:
        """Fast path of the steady cell lookup on 1-D arrays (planners' rollouts)."""
        ok = (fx >= 0.0) & (fx <= nx - 1) & (fy >= 0.0) & (fy <= ny - 1)
        ix = np.where(ok, fx, 0.0).astype(np.intp)
        iy = np.where(ok, fy, 0.0).astype(np.intp)
        np.minimum(ix, nx - 1, out=ix)
        np.minimum(iy, ny - 1, out=iy)
        k = iy * nx + ix
        u = self.u_mps[0].ravel()[k]
        v = self.v_mps[0].ravel()[k]
        if not ok.all():
            u[~ok] = np.nan
            v[~ok] = np.nan
        return u, v

    def _linear_steady(
        self, fx: FloatArray, fy: FloatArray, nx: int, ny: int
    ) -> tuple[FloatArray, FloatArray]:
        """Fast path of steady bilinear interpolation on 1-D arrays (planners' rollouts)."""
        ok = (fx >= 0.0) & (fx <= nx - 1) & (fy >= 0.0) & (fy <= ny - 1)
        fxc = np.where(ok, fx, 0.0)
        fyc = np.where(ok, fy, 0.0)
        ix = np.minimum(fxc.astype(np.intp), nx - 2)
        iy = np.minimum(fyc.astype(np.intp), ny - 2)
        tx = fxc - ix
        ty = fyc - iy
        k = iy * nx + ix
        out = []
        for table in (self.u_mps[0].ravel(), self.v_mps[0].ravel()):
            a = table[k]
            b = table[k + 1]
            c = table[k + nx]
            d = table[k + nx + 1]
            low = a + (b - a) * tx
            out.append(low + (c + (d - c) * tx - low) * ty)
        u, v = out
        if not ok.all():
            u[~ok] = np.nan
            v[~ok] = np.nan
        return u, v

    def _cell_scalar(
        self, x: float, y: float, x0: float, y0: float, dx: float, dy: float, lists: tuple
    ) -> tuple[float, float]:
        fx = (x - x0) / dx
        fy = (y - y0) / dy
        nx, ny = len(lists[0][0]), len(lists[0])
        if not (0.0 <= fx <= nx - 1 and 0.0 <= fy <= ny - 1):
            return math.nan, math.nan
        ix = min(int(fx), nx - 1)
        iy = min(int(fy), ny - 1)
        return lists[0][iy][ix], lists[1][iy][ix]

    def _time_weights(self, time_s: FloatArray) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
        """Slice indices ``(i0, i1)`` and weights ``(w0, w1)`` for linear interpolation in time."""
        t = self.time_s
        if t is None or t.size == 1:
            # A steady field, or a single snapshot used as one.
            zero = np.zeros(np.shape(time_s), dtype=np.intp)
            w0 = np.ones(np.shape(time_s))
            return (zero, zero), np.stack([w0, np.zeros_like(w0)])
        i1 = np.clip(np.searchsorted(t, time_s, side="right"), 1, t.size - 1)
        i0 = i1 - 1
        w1 = (time_s - t[i0]) / (t[i1] - t[i0])
        inside = (time_s >= t[0]) & (time_s <= t[-1])
        w1 = np.where(inside, w1, np.nan)
        return (i0, i1), np.stack([1.0 - w1, w1])


def _blend_time(
    values: FloatArray,
    slices: tuple[np.ndarray, np.ndarray],
    weights: np.ndarray,
    gather,
) -> FloatArray:
    """Interpolate ``gather(values, slice)`` linearly between two time slices (each point its own pair)."""
    i0, i1 = slices
    w0, w1 = weights
    if values.shape[0] == 1:
        return gather(values, np.zeros_like(i0)) * np.where(np.isfinite(w0), 1.0, np.nan)
    a0 = gather(values, i0)
    a1 = gather(values, i1)
    return a0 * w0 + np.where(w1 == 0.0, 0.0, a1 * w1)


def thesis_vortex_grid(
    interpolation: Interpolation = "cell",
    *,
    scale_m: float = THESIS_VORTEX_SCALE_M,
    spacing: float = THESIS_VORTEX_SPACING,
) -> GridCurrent:
    """The thesis vortex sampled on its mesh (Dillard, Appendix C): 21 x 21 nodes over ``[-0.5, 0.5]^2``.

    With the default scale the nodes are 500 m apart over ``[-5000, 5000]^2`` m. ``interpolation="cell"``
    reproduces the thesis' lookup (the value of the lower-left node of the cell, constant over the
    500 m cell); ``"linear"`` interpolates the same samples bilinearly (a continuous field).
    """
    n = round(1.0 / spacing) + 1
    axis = np.linspace(-0.5, 0.5, n)
    gx, gy = np.meshgrid(axis, axis)
    u, v = vortex_velocity_xy(gx * scale_m, gy * scale_m, scale_m)
    return GridCurrent(x_m=axis * scale_m, y_m=axis * scale_m, u_mps=u, v_mps=v, interpolation=interpolation)
