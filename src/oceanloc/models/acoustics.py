"""Sound speed in sea water and the conversion between acoustic travel time and range.

Two sound-speed models:

- :func:`sound_speed_medwin_mps`, the simple formula of the AquaQuad thesis, eq. (II.1) (Medwin 1975, via
  Urick): ``c = 1449.2 + 4.6 T - 0.055 T^2 + 0.00029 T^3 + (1.34 - 0.010 T)(S - 35) + 0.016 z``, stated for
  0-35 degC, 0-45 psu and 0-1000 m;
- :func:`sound_speed_teos10_mps`, the oceanographers' standard TEOS-10 (``gsw.sound_speed``) from in-situ
  temperature, practical salinity and depth at a given latitude and longitude.

They agree to a few decimetres per second in the mixed layer (the module's tests hold them to 1 m/s there).

Travel time and range are related by a straight ray at a constant (or harmonic-mean) sound speed:
``r = c t`` one way, ``r = c t / 2`` for a two-way (round-trip) time. All functions are vectorized and
broadcast their arguments.
"""

from __future__ import annotations

import gsw
import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError, DataError


def sound_speed_medwin_mps(
    temperature_c: ArrayLike, salinity_psu: ArrayLike, depth_m: ArrayLike
) -> FloatArray:
    """Sound speed from temperature, salinity and depth, thesis eq. (II.1).

    Parameters
    ----------
    temperature_c : (...) float
        In-situ temperature, degrees Celsius.
    salinity_psu : (...) float
        Salinity, parts per thousand (practical salinity).
    depth_m : (...) float
        Depth, metres, positive down.

    Returns
    -------
    (...) float
        Sound speed, m/s (broadcast shape of the inputs).
    """
    t = np.asarray(temperature_c, dtype=float)
    s = np.asarray(salinity_psu, dtype=float)
    z = np.asarray(depth_m, dtype=float)
    return 1449.2 + 4.6 * t - 0.055 * t**2 + 0.00029 * t**3 + (1.34 - 0.010 * t) * (s - 35.0) + 0.016 * z


def sound_speed_teos10_mps(
    temperature_c: ArrayLike,
    salinity_psu: ArrayLike,
    depth_m: ArrayLike,
    latitude_deg: ArrayLike = 0.0,
    longitude_deg: ArrayLike = 0.0,
) -> FloatArray:
    """Sound speed by TEOS-10 (``gsw``) from in-situ temperature, practical salinity and depth.

    Depth is turned into sea pressure (``gsw.p_from_z``), practical into absolute salinity
    (``gsw.SA_from_SP``, which needs the position), in-situ into conservative temperature
    (``gsw.CT_from_t``), and ``gsw.sound_speed`` evaluated.

    Parameters
    ----------
    temperature_c, salinity_psu, depth_m : (...) float
        As in :func:`sound_speed_medwin_mps`.
    latitude_deg, longitude_deg : (...) float
        Position (degrees), for gravity and the absolute-salinity anomaly.

    Returns
    -------
    (...) float
        Sound speed, m/s.
    """
    z = np.asarray(depth_m, dtype=float)
    lat = np.asarray(latitude_deg, dtype=float)
    p = gsw.p_from_z(-z, lat)
    sa = gsw.SA_from_SP(np.asarray(salinity_psu, dtype=float), p, np.asarray(longitude_deg, dtype=float), lat)
    ct = gsw.CT_from_t(sa, np.asarray(temperature_c, dtype=float), p)
    return np.asarray(gsw.sound_speed(sa, ct, p), dtype=float)


def _check_speed(sound_speed_mps: ArrayLike) -> FloatArray:
    c = np.asarray(sound_speed_mps, dtype=float)
    if not np.all(np.isfinite(c) & (c > 0.0)):
        raise ConfigError(f"sound speed must be positive and finite, got {sound_speed_mps!r}")
    return c


def range_from_travel_time_m(
    time_s: ArrayLike, sound_speed_mps: ArrayLike, *, two_way: bool = False
) -> FloatArray:
    """Range from an acoustic travel time: ``r = c t`` (one way) or ``r = c t / 2`` (round trip).

    Parameters
    ----------
    time_s : (...) float
        Travel times, seconds (a time difference gives a range difference).
    sound_speed_mps : float or (...) float
        Sound speed (use the harmonic mean over the path, :func:`harmonic_mean_sound_speed_mps`).
    two_way : bool
        ``time_s`` is a round-trip time (interrogate-and-reply ranging).

    Returns
    -------
    (...) float
        Ranges, metres.
    """
    r = _check_speed(sound_speed_mps) * np.asarray(time_s, dtype=float)
    return 0.5 * r if two_way else r


def travel_time_from_range_s(
    range_m: ArrayLike, sound_speed_mps: ArrayLike, *, two_way: bool = False
) -> FloatArray:
    """Travel time of a range, the inverse of :func:`range_from_travel_time_m`.

    Returns
    -------
    (...) float
        Seconds; twice the one-way time when ``two_way``.
    """
    t = np.asarray(range_m, dtype=float) / _check_speed(sound_speed_mps)
    return 2.0 * t if two_way else t


def harmonic_mean_sound_speed_mps(
    depth_m: ArrayLike, sound_speed_mps: ArrayLike, top_m: float | None = None, bottom_m: float | None = None
) -> float:
    """Harmonic-mean sound speed of a profile between two depths: ``(z2 - z1) / integral(dz / c(z))``.

    A vertical ray crosses the layer in ``integral(dz / c)``; the harmonic mean is the one constant speed
    giving the same travel time, the usual choice for converting travel times in a stratified column.
    The profile is linear between samples (trapezoidal integration of ``1/c``) and held constant beyond
    its ends.

    Parameters
    ----------
    depth_m : (K,) float
        Profile depths, metres, positive down, strictly increasing.
    sound_speed_mps : (K,) float
        Sound speed at those depths.
    top_m, bottom_m : float, optional
        Layer limits; the profile's first and last depth by default.

    Returns
    -------
    float
        Harmonic-mean sound speed, m/s.
    """
    z = np.asarray(depth_m, dtype=float)
    c = _check_speed(sound_speed_mps)
    if z.ndim != 1 or z.shape != c.shape or z.size < 1:
        raise DataError(f"sound-speed profile needs matching 1-D depths and speeds, got {z.shape}, {c.shape}")
    if z.size > 1 and np.any(np.diff(z) <= 0):
        raise DataError("sound-speed profile depths must be strictly increasing")
    z1 = float(z[0]) if top_m is None else float(top_m)
    z2 = float(z[-1]) if bottom_m is None else float(bottom_m)
    if not z2 > z1:
        raise ConfigError(f"layer bottom ({z2} m) must be deeper than its top ({z1} m)")
    inner = z[(z > z1) & (z < z2)]
    grid = np.concatenate([[z1], inner, [z2]])
    slowness = 1.0 / np.interp(grid, z, c)
    travel = float(np.sum(0.5 * (slowness[1:] + slowness[:-1]) * np.diff(grid)))
    return (z2 - z1) / travel


def refraction_shortening_m(target_m: ArrayLike, sensor_m: ArrayLike) -> FloatArray:
    """Geometric factor of the refraction correction to a straight acoustic ray, ``L tan^2(theta)``.

    In a horizontally stratified ocean a ray bends (Snell's law), and by Fermat's principle the
    straight-ray travel time at the depth-harmonic-mean sound speed is exact to first order in the
    speed's variation along depth; the second-order error shortens the equivalent straight path by
    ``kappa L tan^2(theta)``, with ``L`` the straight slant range, ``theta`` the incidence angle from the
    vertical and ``kappa ~ Var_z(c) / (2 c^2)`` (7 ppm for 20 m/s across the water column), nearly
    independent of the profile's shape (checked against :func:`trace_layered_ray` in the tests). So
    ``path = L (1 - kappa tan^2 theta)`` per leg, with ``kappa`` an unknown of the survey.

    Parameters
    ----------
    target_m : (..., 3) float
        Transponder position (below the sensor), metres.
    sensor_m : (..., 3) float
        Surface transducer position, metres.

    Returns
    -------
    (...) float
        ``L tan^2(theta) = L h^2 / v^2`` (``h`` horizontal, ``v`` vertical separation), metres.
    """
    diff = np.asarray(sensor_m, dtype=float) - np.asarray(target_m, dtype=float)
    h2 = diff[..., 0] ** 2 + diff[..., 1] ** 2
    v2 = np.maximum(diff[..., 2] ** 2, 1e-12)
    return np.sqrt(h2 + v2) * h2 / v2


def refraction_shortening_jacobian(target_m: ArrayLike, sensor_m: ArrayLike) -> FloatArray:
    """Jacobian of :func:`refraction_shortening_m` with respect to the target position.

    Returns
    -------
    (..., 3) float
        Dimensionless.
    """
    diff = np.asarray(sensor_m, dtype=float) - np.asarray(target_m, dtype=float)
    h2 = diff[..., 0] ** 2 + diff[..., 1] ** 2
    v = diff[..., 2]
    v2 = np.maximum(v * v, 1e-12)
    length = np.sqrt(h2 + v2)
    ratio = h2 / v2
    # d/d target = -d/d diff
    d_len = -diff / length[..., None]
    d_ratio = np.empty_like(diff)
    d_ratio[..., :2] = -2.0 * diff[..., :2] / v2[..., None]
    d_ratio[..., 2] = 2.0 * h2 * v / (v2 * v2)
    return d_len * ratio[..., None] + length[..., None] * d_ratio


def trace_layered_ray(
    sound_speed_mps: ArrayLike, thickness_m: ArrayLike, tan_incidence: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Travel time and horizontal reach of rays through a horizontally layered ocean (Snell's law).

    For each requested straight-line incidence ``X / D`` (``D`` the total depth), the ray parameter
    ``p = sin(theta_i) / c_i`` is found by bisection so that the ray's horizontal reach is ``X``; the
    ray is then traced layer by layer. Vectorized over the requested incidences.

    Parameters
    ----------
    sound_speed_mps : (L,) float
        Sound speed of each layer, m/s.
    thickness_m : (L,) float
        Layer thicknesses, metres (positive).
    tan_incidence : (R,) float
        Horizontal offset over depth of the end points, ``X / D`` (non-negative).

    Returns
    -------
    travel_time_s : (R,) float
        One-way travel time along the ray, seconds.
    reach_m : (R,) float
        Horizontal reach of the traced ray (equals ``tan_incidence * D`` to ~1e-9 relative), metres.
    """
    c = _check_speed(sound_speed_mps).reshape(-1)
    dz = np.asarray(thickness_m, dtype=float).reshape(-1)
    if c.shape != dz.shape or np.any(dz <= 0.0):
        raise ConfigError("trace_layered_ray needs one positive thickness per sound-speed layer")
    target = np.asarray(tan_incidence, dtype=float).reshape(-1) * dz.sum()
    if np.any(target < 0.0) or not np.all(np.isfinite(target)):
        raise ConfigError("tan_incidence must be finite and non-negative")

    def reach(p: FloatArray) -> tuple[FloatArray, FloatArray]:
        s = np.minimum(p[:, None] * c[None, :], 1.0 - 1e-15)
        cos = np.sqrt(1.0 - s * s)
        return np.sum(dz * s / cos, axis=1), np.sum(dz / (c * cos), axis=1)

    lo = np.zeros_like(target)
    hi = np.full_like(target, (1.0 - 1e-12) / c.max())
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        too_short = reach(mid)[0] < target
        lo = np.where(too_short, mid, lo)
        hi = np.where(too_short, hi, mid)
    x_m, t_s = reach(0.5 * (lo + hi))
    return t_s, x_m


def gradient_path_m2(target_m: ArrayLike, sensor_m: ArrayLike) -> FloatArray:
    """Sensitivity of a straight acoustic leg to a horizontal gradient of slowness.

    With slowness ``s(x) = s0 (1 + g . (x_h - p_h))`` varying linearly in the horizontal (the usual
    GNSS-A gradient model, e.g. Kido 2007; Honsho et al. 2019), the travel time along the straight leg
    from the transponder ``p`` to the sensor ``a`` is ``s0 L (1 + g . (a_h - p_h) / 2)``: the mean
    horizontal offset along the leg is half the end point's. In equivalent path length the leg
    lengthens by ``g . (L (a_h - p_h) / 2)``; this function returns that vector factor.

    Parameters
    ----------
    target_m : (..., 3) float
        Transponder position, metres.
    sensor_m : (..., 3) float
        Surface transducer position, metres.

    Returns
    -------
    (..., 2) float
        ``L (a_h - p_h) / 2`` (east, north), square metres; multiply by a gradient in 1/m.
    """
    diff = np.asarray(sensor_m, dtype=float) - np.asarray(target_m, dtype=float)
    length = np.sqrt(np.sum(diff * diff, axis=-1, keepdims=True))
    return 0.5 * length * diff[..., :2]


def gradient_path_jacobian(target_m: ArrayLike, sensor_m: ArrayLike) -> FloatArray:
    """Jacobian of :func:`gradient_path_m2` with respect to the target position.

    Returns
    -------
    (..., 2, 3) float
        Metres.
    """
    diff = np.asarray(sensor_m, dtype=float) - np.asarray(target_m, dtype=float)
    length = np.sqrt(np.sum(diff * diff, axis=-1, keepdims=True))
    d_len = -diff / np.maximum(length, 1e-12)  # d L / d target
    jac = 0.5 * diff[..., :2, None] * d_len[..., None, :]
    jac[..., 0, 0] -= 0.5 * length[..., 0]
    jac[..., 1, 1] -= 0.5 * length[..., 0]
    return jac
