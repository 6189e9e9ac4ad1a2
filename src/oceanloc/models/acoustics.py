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
