"""ROMS subsets on their own curvilinear grid, interpolated onto a regular metric grid; FVCOM detection.

A ROMS history or average file keeps its velocities on a staggered Arakawa C grid that follows the
coastline: ``u(ocean_time, s_rho, eta_u, xi_u)`` between rho points along xi, ``v(..., eta_v, xi_v)``
between them along eta, in the grid's own directions, which turn by ``angle(eta_rho, xi_rho)`` (radians,
from east to the xi axis) across the domain. :func:`read_roms`

1. picks the vertical level (``s_rho``: the last is the surface; or ``depth_index``) and the time window;
2. averages ``u`` and ``v`` onto the rho points (NaN on the edges and where either neighbour is masked or a
   fill value), masks land with ``mask_rho``, and rotates them to east and north:
   ``u_e = u cos(angle) - v sin(angle)``, ``v_n = u sin(angle) + v cos(angle)``;
3. maps ``lon_rho``/``lat_rho`` to the local tangent plane and interpolates linearly (on the Delaunay
   triangles of the rho points, once for every slice and both components) onto a regular grid with the
   grid's median spacing. A triangle touching a land point is land; points outside the domain are NaN.

The s-coordinate depth of a level depends on the bathymetry and the free surface, so a depth in metres is
refused, except 0 (the surface), with a message naming ``depth_index``. FVCOM's unstructured triangles
(``nele``, ``nv``) are detected by :func:`is_fvcom` so the reader can refuse them clearly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import DataError
from oceanloc.geo.projection import LocalProjection
from oceanloc.models.currents import Interpolation


def is_roms(ds) -> bool:
    """A ROMS subset: rho-point longitude/latitude and a staggered u grid."""
    return (
        "lon_rho" in ds.variables and "lat_rho" in ds.variables and ("xi_u" in ds.dims or "eta_v" in ds.dims)
    )


def is_fvcom(ds) -> bool:
    """An FVCOM subset: velocities on the elements of an unstructured mesh."""
    return "nele" in ds.dims and ("nv" in ds.variables or "lonc" in ds.variables)


def read_roms(
    ds,
    path: Path,
    *,
    u_var: str | None,
    v_var: str | None,
    depth_index: int | None,
    depth_m: float | None,
    time_window: tuple[str, str] | None,
    origin_lonlat_deg: tuple[float, float] | None,
    interpolation: Interpolation,
):
    """Read a ROMS subset (see the module docstring); returns a
    :class:`~oceanloc.models.currents_cf.CurrentProduct`."""
    from oceanloc.models.currents_cf import (
        _time_seconds,
        _velocity_scale,
        assemble_product,
        time_slices,
    )

    un, vn = u_var or "u", v_var or "v"
    for name in (un, vn, "angle"):
        if name not in ds.variables:
            raise DataError(
                f"{path}: ROMS file without '{name}'; variables: {', '.join(map(str, ds.data_vars))}"
            )
    u_da, v_da = ds[un], ds[vn]
    if depth_m is not None and depth_m > 0.0:
        raise DataError(
            f"{path}: ROMS s-coordinate levels have no fixed depth in metres: depth 0 reads the surface, "
            "a depth index (s_rho index, the last is the surface) any other level"
        )
    notes: list[str] = []
    zdim = next((d for d in u_da.dims if d.startswith("s_")), None)
    if zdim is not None:
        n = ds.sizes[zdim]
        k = n - 1 if depth_index is None else depth_index
        if not 0 <= k < n:
            raise DataError(f"{path}: depth index {k} outside 0..{n - 1} of '{zdim}'")
        u_da = u_da.isel({zdim: k})
        v_da = v_da.isel({zdim: min(k, ds.sizes[next(d for d in v_da.dims if d.startswith("s_"))] - 1)})
        notes.append(f"level {k} of '{zdim}'" + (" (the surface)" if k == n - 1 else ""))
    tname = next((d for d in u_da.dims if "time" in d), None)
    times, t_origin = None, None
    if tname is not None:
        keep, note = time_slices(ds, path, tname, time_window)
        if keep is not None:
            u_da, v_da = u_da.isel({tname: keep}), v_da.isel({tname: keep})
            notes.append(note)
        times, t_origin = _time_seconds(u_da, path, tname)
    u = _with_time(u_da, tname) * _velocity_scale(path, u_da)
    v = _with_time(v_da, tname) * _velocity_scale(path, v_da)
    ue, vn_ = _to_rho(u, v, ds)
    lon = np.asarray(ds["lon_rho"].values, dtype=float)
    lat = np.asarray(ds["lat_rho"].values, dtype=float)
    if origin_lonlat_deg is None:
        origin_lonlat_deg = (float(np.nanmean(lon)), float(np.nanmean(lat)))
    proj = LocalProjection(lat0_deg=float(origin_lonlat_deg[1]), lon0_deg=float(origin_lonlat_deg[0]))
    x_m, y_m, gu, gv = _regrid_curvilinear(proj, lon, lat, ue, vn_)
    if not (np.isfinite(gu).any()):
        raise DataError(f"{path}: {un}/{vn} hold no finite value on the sea (all land or missing)")
    notes.append(f"ROMS curvilinear grid interpolated to {x_m[1] - x_m[0]:.0f} m")
    desc = f"{path.name}: ROMS {un}/{vn} on {len(x_m)} x {len(y_m)} nodes"
    if times is not None:
        desc += f", {len(times)} times from {t_origin}"
    return assemble_product(
        x_m, y_m, gu[None], gv[None], times, t_origin, proj, desc, notes, interpolation, layout="roms"
    )


def _with_time(da, tname: str | None) -> FloatArray:
    order = [d for d in da.dims if d == tname] + [d for d in da.dims if d != tname]
    out = np.asarray(da.transpose(*order).values, dtype=float)
    return out if tname is not None else out[None]


def _to_rho(u: FloatArray, v: FloatArray, ds) -> tuple[FloatArray, FloatArray]:
    """``u (nt, eta_rho, xi_rho - 1)`` and ``v (nt, eta_rho - 1, xi_rho)`` averaged to the rho points,
    masked and rotated to east and north."""
    nt = u.shape[0]
    ny, nx = u.shape[1], u.shape[2] + 1
    ur = np.full((nt, ny, nx), np.nan)
    vr = np.full((nt, ny, nx), np.nan)
    ur[:, :, 1:-1] = 0.5 * (u[:, :, :-1] + u[:, :, 1:])
    vr[:, 1:-1, :] = 0.5 * (v[:, :-1, :] + v[:, 1:, :])
    if "mask_rho" in ds.variables:
        land = np.asarray(ds["mask_rho"].values, dtype=float) < 0.5
        ur[:, land] = np.nan
        vr[:, land] = np.nan
    angle = np.asarray(ds["angle"].values, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    return ur * c - vr * s, ur * s + vr * c


def _regrid_curvilinear(
    proj: LocalProjection, lon: FloatArray, lat: FloatArray, u: FloatArray, v: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    from scipy.interpolate import LinearNDInterpolator

    x, y = proj.to_local(lon, lat)
    pts = np.column_stack([x.ravel(), y.ravel()])
    dx = np.hypot(np.diff(x, axis=1), np.diff(y, axis=1))
    dy = np.hypot(np.diff(x, axis=0), np.diff(y, axis=0))
    step = float(np.median(np.concatenate([dx.ravel(), dy.ravel()])))
    # The regular grid over the rho points (the interpolation leaves NaN outside their hull).
    xs = np.arange(float(x.min()), float(x.max()) + 1e-6, step)
    ys = np.arange(float(y.min()), float(y.max()) + 1e-6, step)
    nt = u.shape[0]
    values = np.concatenate([u.reshape(nt, -1).T, v.reshape(nt, -1).T], axis=1)  # (points, 2 nt)
    interp = LinearNDInterpolator(pts, values, fill_value=np.nan)
    gx, gy = np.meshgrid(xs, ys)
    out = interp(np.column_stack([gx.ravel(), gy.ravel()]))  # (grid points, 2 nt)
    gu = out[:, :nt].T.reshape(nt, ys.size, xs.size)
    gv = out[:, nt:].T.reshape(nt, ys.size, xs.size)
    return xs, ys, gu, gv
