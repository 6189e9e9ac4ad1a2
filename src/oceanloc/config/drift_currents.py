"""The ``[currents]`` table of a drift scenario: analytic fields and forecast products, and the physical
ranges every drift scenario field is checked against (:mod:`oceanloc.config.drift`).

A product (``kind = "netcdf"``: a Copernicus Marine or HYCOM NetCDF or Zarr subset, a ROMS subset) is read
by :func:`oceanloc.models.currents_cf.open_current_product` with the level (``depth_m`` or
``depth_index``) and the time window (``time_window = [start, end]``, ISO 8601) the table asks for; an
ensemble product keeps its members for planning on the expected energy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc.config.toml_fields import Table
from oceanloc.geo.projection import LocalProjection
from oceanloc.models.currents import (
    CurrentField,
    DoubleGyreCurrent,
    LinearCurrent,
    RankineVortexCurrent,
    TidalCurrent,
    UniformCurrent,
    VortexCurrent,
    thesis_vortex_grid,
)
from oceanloc.models.currents_cf import CurrentProduct, land_obstacles, open_current_product
from oceanloc.models.obstacles import OccupancyGrid
from oceanloc.units import DEG

CURRENT_KINDS = ("thesis-vortex", "vortex", "double-gyre", "uniform", "tidal", "linear", "rankine", "netcdf")

# Physical ranges of the scenario fields (every value outside is a one-line error naming the field).
MAX_CURRENT_MPS = 10.0
"""Fastest current accepted, m/s (the strongest tidal races run at about 5 m/s)."""
MAX_COORD_M = 1e7
"""Largest coordinate of a local frame, metres (a quarter of the Earth's circumference)."""
MAX_LENGTH_M = 1e6
"""Largest length scale of an analytic field, metres."""
MIN_DT_S, MAX_DT_S = 1.0, 3600.0
"""Drift step range, seconds."""
MAX_HORIZON_H = 24.0 * 30
"""Longest drift horizon, hours (a month)."""
MAX_HORIZON_STEPS = 200_000
"""Most drift steps in one horizon (horizon / step)."""
MAX_SEED = 2**63 - 1


def _coords(t: Table, key: str, length: int, default: object = None) -> np.ndarray:
    """A vector of ``length`` finite coordinates (m) within plus or minus :data:`MAX_COORD_M`."""
    value = t.vector(key, length) if default is None else t.vector(key, length, default)
    if not np.all(np.abs(value) <= MAX_COORD_M):
        raise t.error(
            key, f"coordinates must lie within [-{MAX_COORD_M:g}, {MAX_COORD_M:g}] m, got {value.tolist()}"
        )
    return value


@dataclass(frozen=True, slots=True, kw_only=True)
class CurrentSettings:
    """``[currents]``: the planning current, its georeference, a one-line description, land cells."""

    field: CurrentField
    projection: LocalProjection | None
    description: str
    land: OccupancyGrid | None = None
    data_files: tuple[str, ...] = ()
    time_origin: str | None = None
    members: tuple[CurrentField, ...] = ()


def _currents(t: Table, base_dir: Path) -> CurrentSettings:
    kind = t.str("kind", "thesis-vortex", choices=CURRENT_KINDS)
    if kind == "thesis-vortex":
        interp = t.str("interpolation", "cell", choices=("cell", "linear"))
        scale = t.float("scale_m", 10_000.0, lo=1.0, hi=MAX_LENGTH_M)
        f: CurrentField = thesis_vortex_grid(interp, scale_m=scale)  # type: ignore[arg-type]
        how = "piecewise constant per cell" if interp == "cell" else "bilinear"
        return CurrentSettings(
            field=f, projection=None, description=f"thesis vortex sampled every {0.05 * scale:g} m ({how})"
        )
    if kind == "vortex":
        scale = t.float("scale_m", 10_000.0, lo=1.0, hi=MAX_LENGTH_M)
        half = t.float("half_width_m", 0.5 * scale, lo=0.0, lo_open=True, hi=MAX_LENGTH_M)
        return CurrentSettings(
            field=VortexCurrent(scale_m=scale, half_width_m=half),
            projection=None,
            description=f"analytic thesis vortex (scale {scale:g} m)",
        )
    if kind == "double-gyre":
        length = t.float("length_m", 5000.0, lo=1.0, hi=MAX_LENGTH_M)
        amp = t.float("amplitude_mps", 0.5, lo=0.0, hi=MAX_CURRENT_MPS)
        eps = t.float("epsilon", 0.0, lo=0.0, hi=1.0)
        period_h = t.float("period_h", 24.0, lo=0.01, hi=24.0 * 365)
        origin = _coords(t, "origin_m", 2, [0.0, 0.0])
        f = DoubleGyreCurrent(
            length_m=length,
            amplitude_mps=amp,
            epsilon=eps,
            omega_rad_s=2 * math.pi / (period_h * 3600.0),
            origin_m=(float(origin[0]), float(origin[1])),
        )
        desc = f"double gyre L = {length:g} m, A = {amp:g} m/s, eps = {eps:g}"
        return CurrentSettings(field=f, projection=None, description=desc)
    if kind == "uniform":
        vel = t.vector("velocity_mps", 2)
        if not np.all(np.abs(vel) <= MAX_CURRENT_MPS):
            raise t.error(
                "velocity_mps",
                f"components must lie within [-{MAX_CURRENT_MPS:g}, {MAX_CURRENT_MPS:g}] m/s, "
                f"got {vel.tolist()}",
            )
        return CurrentSettings(
            field=UniformCurrent(velocity_mps=(float(vel[0]), float(vel[1]))),
            projection=None,
            description=f"uniform {vel.tolist()} m/s",
        )
    if kind == "tidal":
        mean = _velocity(t, "mean_mps", [0.0, 0.0])
        amp = _velocity(t, "amplitude_mps")
        period_h = t.float("period_h", 12.42, lo=0.01, hi=24.0 * 365)
        phase = t.float("phase_deg", 0.0, lo=-360.0, hi=360.0)
        f = TidalCurrent(
            mean_mps=(float(mean[0]), float(mean[1])),
            amplitude_mps=(float(amp[0]), float(amp[1])),
            period_s=period_h * 3600.0,
            phase_rad=phase * DEG,
        )
        desc = f"tidal stream {mean.tolist()} + {amp.tolist()} sin(2 pi t / {period_h:g} h) m/s"
        return CurrentSettings(field=f, projection=None, description=desc)
    if kind == "linear":
        raw = t._get("matrix_per_s", None)
        try:
            mat = np.asarray(raw, dtype=float).reshape(2, 2)
        except (TypeError, ValueError):
            raise t.error("matrix_per_s", f"must be [[a, b], [c, d]] in 1/s, got {raw!r}") from None
        if not (np.all(np.isfinite(mat)) and np.all(np.abs(mat) <= 1.0)):
            raise t.error(
                "matrix_per_s", f"entries must be finite and within [-1, 1] 1/s, got {mat.tolist()}"
            )
        off = _velocity(t, "offset_mps", [0.0, 0.0])
        f = LinearCurrent(
            matrix_per_s=((mat[0, 0], mat[0, 1]), (mat[1, 0], mat[1, 1])),
            offset_mps=(float(off[0]), float(off[1])),
        )
        return CurrentSettings(
            field=f, projection=None, description=f"linear v = {mat.tolist()} p + {off.tolist()}"
        )
    if kind == "rankine":
        centre = _coords(t, "centre_m", 2, [0.0, 0.0])
        radius = t.float("core_radius_m", 2000.0, lo=1.0, hi=MAX_LENGTH_M)
        peak = t.float("peak_speed_mps", 0.5, lo=-MAX_CURRENT_MPS, hi=MAX_CURRENT_MPS)
        pulse = t.float("pulse", 0.0, lo=0.0, hi=1.0)
        period_h = t.float("period_h", 6.0, lo=0.01, hi=24.0 * 365)
        bg = _velocity(t, "background_mps", [0.0, 0.0])
        f = RankineVortexCurrent(
            centre_m=(float(centre[0]), float(centre[1])),
            core_radius_m=radius,
            peak_speed_mps=peak,
            pulse=pulse,
            period_s=period_h * 3600.0,
            background_mps=(float(bg[0]), float(bg[1])),
        )
        desc = (
            f"Rankine vortex R = {radius:g} m, {peak:g} m/s pulsing {pulse:g} over {period_h:g} h, "
            f"carried at {bg.tolist()} m/s"
        )
        return CurrentSettings(field=f, projection=None, description=desc)
    return _netcdf_currents(t, base_dir)


def _velocity(t: Table, key: str, default: object = None) -> np.ndarray:
    """A ``[u, v]`` velocity in m/s within plus or minus :data:`MAX_CURRENT_MPS`."""
    vel = t.vector(key, 2) if default is None else t.vector(key, 2, default)
    if not np.all(np.abs(vel) <= MAX_CURRENT_MPS):
        raise t.error(
            key,
            f"components must lie within [-{MAX_CURRENT_MPS:g}, {MAX_CURRENT_MPS:g}] m/s, got {vel.tolist()}",
        )
    return vel


def _netcdf_currents(t: Table, base_dir: Path) -> CurrentSettings:
    rel = t.str("path")
    path = Path(rel) if Path(rel).is_absolute() else base_dir / rel
    u = t.str("u", "") or None
    v = t.str("v", "") or None
    depth = t.int("depth_index", -1, lo=-1)
    depth_m = t.float("depth_m", 0.0, lo=0.0, hi=12_000.0) if t.has("depth_m") else None
    if depth >= 0 and depth_m is not None:
        raise t.error("depth_m", "give depth_m or depth_index, not both")
    window = None
    if t.has("time_window"):
        raw = t._get("time_window", None)
        if not (isinstance(raw, list) and len(raw) == 2 and all(isinstance(w, str) for w in raw)):
            raise t.error("time_window", f'must be ["start", "end"] in ISO 8601, got {raw!r}')
        window = (raw[0], raw[1])
    origin = t.vector("origin_lonlat_deg", 2, []) if t.has("origin_lonlat_deg") else None
    if origin is not None and not (-180.0 <= origin[0] <= 360.0 and -90.0 <= origin[1] <= 90.0):
        raise t.error(
            "origin_lonlat_deg",
            f"must be [lon, lat] within [-180, 360] and [-90, 90] degrees, got {origin.tolist()}",
        )
    interp = t.str("interpolation", "linear", choices=("cell", "linear"))
    product = open_current_product(
        path,
        u_var=u,
        v_var=v,
        depth_index=None if depth < 0 else depth,
        depth_m=depth_m,
        time_window=window,
        origin_lonlat_deg=None if origin is None else (float(origin[0]), float(origin[1])),
        interpolation=interp,  # type: ignore[arg-type]
    )
    try:
        check_product_speeds(product, path.name)
    except ValueError as exc:
        raise t.error("path", str(exc)) from None
    return product_settings(product, (str(path),))


def check_product_speeds(product: CurrentProduct, name: str) -> None:
    """A ValueError if a product (or one of its members) holds currents beyond :data:`MAX_CURRENT_MPS`."""
    for f in (product.field, *product.members):
        with np.errstate(invalid="ignore"):
            peak = float(np.nanmax(np.hypot(f.u_mps, f.v_mps))) if np.isfinite(f.u_mps).any() else 0.0
        if not peak <= MAX_CURRENT_MPS:
            raise ValueError(
                f"{name} holds currents up to {peak:.3g} m/s; speeds must lie within "
                f"[0, {MAX_CURRENT_MPS:g}] m/s (check the variables' units and fill values)"
            )


def product_settings(product: CurrentProduct, data_files: tuple[str, ...]) -> CurrentSettings:
    """The settings of a product read from ``data_files``: its field, frame, land and members."""
    land = land_obstacles(product.field)
    return CurrentSettings(
        field=product.field,
        projection=product.projection,
        description=product.description,
        land=land,
        data_files=data_files,
        time_origin=product.time_origin,
        members=product.members,
    )
