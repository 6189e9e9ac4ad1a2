"""Gridded currents from ocean forecast products: Copernicus Marine, HYCOM, ROMS, as NetCDF or Zarr.

:func:`open_current_product` reads eastward and northward velocity through xarray and returns a
:class:`~oceanloc.models.currents.GridCurrent` on a regular metric grid, ready for drift integration:

- a NetCDF file, or a Zarr store (a directory, as ``copernicusmarine subset --file-format zarr`` writes);
- velocity variables are found by CF ``standard_name`` (``eastward_sea_water_velocity``,
  ``surface_eastward_sea_water_velocity``, ... and their northward twins) or by the products' names
  (``uo/vo`` for Copernicus Marine, ``water_u/water_v`` for HYCOM, ``u/v`` ...), or named explicitly;
  packed integers (``scale_factor``, ``add_offset``) and ``_FillValue``/``missing_value`` are decoded;
- units must be velocities (``m s-1``, ``m/s``, ``cm s-1`` ...); anything else, or no units, is an error
  naming the file and the variable;
- horizontal coordinates are longitude/latitude (degrees, -180..180 or 0..360) or projected ``x/y`` (m or
  km); longitude and latitude grids are resampled once onto a regular grid in a local tangent plane
  (:class:`~oceanloc.geo.projection.LocalProjection`) with the same resolution;
- a ROMS subset on its own curvilinear grid (``u``/``v`` on the staggered ``xi_u``/``eta_v`` points,
  ``lon_rho``/``lat_rho``, ``angle``, ``mask_rho``) is interpolated onto the same kind of regular grid
  (:mod:`oceanloc.models.currents_roms`); an FVCOM subset (an unstructured triangular mesh) is refused
  with a message saying so;
- the time axis becomes seconds since its first slice, optionally cut to a window (``time_window``: the
  slices covering it); a depth axis is reduced to the level nearest to ``depth_m`` metres (the surface
  by default) or to a chosen index;
- an ensemble (a ``member``/``realization``/``number`` dimension) gives one field per member and their mean
  (:attr:`CurrentProduct.members`);
- land and missing cells stay ``NaN``: drift stops there and :func:`land_obstacles` turns them into an
  occupancy grid for the planner. A file without one sea value is an error. Nothing ever becomes a silent
  zero current.

:func:`write_current_netcdf` writes a :class:`GridCurrent` (or a lon/lat grid) as CF NetCDF, used by the tests
and to produce example files.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import DataError
from oceanloc.geo.projection import LocalProjection
from oceanloc.models.currents import GridCurrent, Interpolation
from oceanloc.models.obstacles import OccupancyGrid

EASTWARD_NAMES = (
    "eastward_sea_water_velocity",
    "surface_eastward_sea_water_velocity",
    "eastward_sea_water_velocity_assuming_no_tide",
    "baroclinic_eastward_sea_water_velocity",
    "sea_surface_eastward_velocity",
)
NORTHWARD_NAMES = tuple(n.replace("eastward", "northward") for n in EASTWARD_NAMES)
EASTWARD_VARS = ("uo", "water_u", "u", "U", "ugos", "u_surf")
NORTHWARD_VARS = ("vo", "water_v", "v", "V", "vgos", "v_surf")
MEMBER_DIMS = ("member", "realization", "ensemble", "ensemble_member", "number", "ens")

_MPS_UNITS = {
    "m s-1",
    "m/s",
    "m s**-1",
    "m s^-1",
    "meter second-1",
    "meters second-1",
    "meter/second",
    "meters/second",
    "meter/sec",
    "m.s-1",
    "m sec-1",
    "meter s-1",
    "metre s-1",
    "metres/second",
    "ms-1",
}
_CMPS_UNITS = {"cm s-1", "cm/s", "cm s**-1", "cm s^-1", "centimeter second-1", "centimeters/second", "cm.s-1"}
_M_UNITS = {"m", "meter", "meters", "metre", "metres"}
_KM_UNITS = {"km", "kilometer", "kilometers", "kilometre", "kilometres"}


@dataclass(frozen=True, slots=True, kw_only=True)
class CurrentProduct:
    """A gridded current read from a file.

    Attributes
    ----------
    field : GridCurrent
        Velocity on a regular metric grid (``NaN`` on land); the members' mean for an ensemble.
    projection : LocalProjection or None
        The tangent plane used for longitude/latitude products (``None`` for projected ones).
    time_origin : str or None
        The first time slice (ISO 8601) that is time 0 of the field.
    description : str
        What was read: variables, grid, time and depth handling.
    members : tuple of GridCurrent
        The ensemble's members on the same grid (empty for a single forecast).
    layout : str
        ``"cf"`` (a regular CF grid: Copernicus Marine, HYCOM ...) or ``"roms"``.
    """

    field: GridCurrent
    projection: LocalProjection | None
    time_origin: str | None
    description: str
    members: tuple[GridCurrent, ...] = field(default=())
    layout: str = "cf"


def _import_xarray():
    try:
        import xarray as xr
    except ImportError:  # pragma: no cover - declared dependency
        raise DataError(
            "reading NetCDF currents needs xarray and netCDF4 (pip install xarray netCDF4)"
        ) from None
    return xr


def is_zarr_store(path: Path) -> bool:
    """A Zarr store: a directory with Zarr metadata (v2 ``.zgroup``/``.zattrs`` or v3 ``zarr.json``)."""
    return path.is_dir() and any((path / name).exists() for name in (".zgroup", ".zattrs", "zarr.json"))


def _consolidated(path: Path) -> bool:
    """Whether a Zarr store carries consolidated metadata (v2 ``.zmetadata``, or v3 ``zarr.json`` with a
    ``consolidated_metadata`` entry): read it then, else read the arrays' own metadata without a warning."""
    if (path / ".zmetadata").exists():
        return True
    meta = path / "zarr.json"
    try:
        import json

        return (
            meta.exists()
            and json.loads(meta.read_text(encoding="utf-8")).get("consolidated_metadata") is not None
        )
    except (OSError, ValueError, AttributeError):
        return False


def _open_dataset(path: Path):
    xr = _import_xarray()
    if is_zarr_store(path):
        try:
            import zarr  # noqa: F401
        except ImportError:  # pragma: no cover - declared dependency
            raise DataError(
                f"{path}: reading a Zarr store needs the zarr package (pip install zarr)"
            ) from None
        try:
            return xr.open_zarr(path, consolidated=_consolidated(path))
        except Exception as exc:
            raise DataError(f"{path}: cannot read as a Zarr store ({type(exc).__name__}: {exc})") from None
    if path.is_dir():
        raise DataError(f"{path}: a directory but not a Zarr store (no .zgroup, .zattrs or zarr.json)")
    if not path.is_file():
        raise DataError(f"{path}: current file not found")
    try:
        return xr.open_dataset(path, engine="netcdf4")
    except Exception as exc:
        raise DataError(f"{path}: cannot read as NetCDF ({type(exc).__name__}: {exc})") from None


def open_current_netcdf(path: str | Path, **kwargs) -> CurrentProduct:
    """:func:`open_current_product` (the name the scenario loader has used since NetCDF only)."""
    return open_current_product(path, **kwargs)


def open_current_product(
    path: str | Path,
    *,
    u_var: str | None = None,
    v_var: str | None = None,
    depth_index: int | None = None,
    depth_m: float | None = None,
    time_window: tuple[str, str] | None = None,
    origin_lonlat_deg: tuple[float, float] | None = None,
    interpolation: Interpolation = "linear",
) -> CurrentProduct:
    """Read a current product (see the module docstring).

    Parameters
    ----------
    path : str or Path
        NetCDF file or Zarr store.
    u_var, v_var : str, optional
        Velocity variable names; found by standard name or usual names when omitted.
    depth_index : int, optional
        Level of a depth axis.
    depth_m : float, optional
        Depth (metres, positive down) whose nearest level is read; the level nearest the surface when
        neither this nor ``depth_index`` is given.
    time_window : (start, end), optional
        ISO 8601 times: only the slices covering ``[start, end]`` are read (one more on each side where
        the product has them, so the field interpolates across the whole window).
    origin_lonlat_deg : (lon, lat), optional
        Origin of the local frame for longitude/latitude products; the grid centre when omitted.
    interpolation : {"linear", "cell"}
        Interpolation of the resulting :class:`GridCurrent`.

    Raises
    ------
    DataError
        Unreadable file, missing variables, wrong units, unusable coordinates, an unsupported grid, a
        level or window outside the product, no sea value.
    """
    p = Path(path)
    if depth_index is not None and depth_m is not None:
        raise DataError(f"{p}: give a depth index or a depth in metres, not both")
    ds = _open_dataset(p)
    with ds:
        from oceanloc.models.currents_roms import is_fvcom, is_roms, read_roms

        if is_fvcom(ds):
            raise DataError(
                f"{p}: an FVCOM subset (velocities on the triangles of an unstructured mesh, 'nele'/'nv') "
                "is not supported: interpolate it onto a regular longitude/latitude grid first"
            )
        if is_roms(ds):
            return read_roms(
                ds,
                p,
                u_var=u_var,
                v_var=v_var,
                depth_index=depth_index,
                depth_m=depth_m,
                time_window=time_window,
                origin_lonlat_deg=origin_lonlat_deg,
                interpolation=interpolation,
            )
        return _read_cf(
            ds, p, u_var, v_var, depth_index, depth_m, time_window, origin_lonlat_deg, interpolation
        )


def _read_cf(ds, p, u_var, v_var, depth_index, depth_m, time_window, origin_lonlat_deg, interpolation):
    u_da = _find_velocity(ds, p, u_var, EASTWARD_NAMES, EASTWARD_VARS, "eastward")
    v_da = _find_velocity(ds, p, v_var, NORTHWARD_NAMES, NORTHWARD_VARS, "northward")
    if u_da.dims != v_da.dims:
        raise DataError(f"{p}: {u_da.name} has dimensions {u_da.dims} but {v_da.name} has {v_da.dims}")
    u_scale = _velocity_scale(p, u_da)
    v_scale = _velocity_scale(p, v_da)
    dims = _classify_dims(ds, p, u_da)
    notes: list[str] = []
    if dims["z"] is not None:
        k, note = choose_level(ds, p, dims["z"], depth_index, depth_m)
        u_da = u_da.isel({dims["z"]: k})
        v_da = v_da.isel({dims["z"]: k})
        notes.append(note)
    elif depth_index is not None or depth_m is not None:
        notes.append("no depth axis: the only level read")
    tname = dims["t"]
    times, t_origin = None, None
    if tname is not None:
        keep, note = time_slices(ds, p, tname, time_window)
        if keep is not None:
            u_da = u_da.isel({tname: keep})
            v_da = v_da.isel({tname: keep})
            notes.append(note)
    elif time_window is not None:
        raise DataError(f"{p}: a time window was given but '{u_da.name}' has no time axis")
    order = [d for d in (dims["m"], tname, dims["y"], dims["x"]) if d is not None]
    u = np.asarray(u_da.transpose(*order).values, dtype=float) * u_scale
    v = np.asarray(v_da.transpose(*order).values, dtype=float) * v_scale
    if dims["m"] is None:
        u, v = u[None], v[None]
    if tname is None:
        u, v = u[:, None], v[:, None]
    else:
        times, t_origin = _time_seconds(u_da, p, tname)
    xc, yc, x_units, y_units = _horizontal(ds, p, dims)
    kind = dims["kind"]
    u_name, v_name = str(u_da.name), str(v_da.name)
    bad = ~(np.isfinite(u) & np.isfinite(v))
    u[bad] = np.nan
    v[bad] = np.nan
    if bad.all():
        raise DataError(f"{p}: {u_name}/{v_name} hold no finite value (all land or missing)")
    n_members = u.shape[0]
    nt = u.shape[1]
    flat_u = u.reshape(n_members * nt, *u.shape[2:])
    flat_v = v.reshape(n_members * nt, *v.shape[2:])
    try:
        if kind == "lonlat":
            x_m, y_m, flat_u, flat_v, projection = _regrid_lonlat(xc, yc, flat_u, flat_v, origin_lonlat_deg)
            notes.append(
                f"lon/lat grid resampled to {x_m[1] - x_m[0]:.0f} m about "
                f"({projection.lon0_deg:.4f}, {projection.lat0_deg:.4f})"
            )
        else:
            xs = _length_scale(x_units, p, dims["x"])
            ys = _length_scale(y_units, p, dims["y"])
            x_m, y_m, flat_u, flat_v = _regrid_xy(xc * xs, yc * ys, flat_u, flat_v)
            projection = None
    except DataError as exc:
        raise DataError(f"{p}: {exc}") from None
    u = flat_u.reshape(n_members, nt, *flat_u.shape[1:])
    v = flat_v.reshape(n_members, nt, *flat_v.shape[1:])
    desc = f"{p.name}: {u_name}/{v_name} on {len(x_m)} x {len(y_m)} nodes"
    if times is not None:
        desc += f", {len(times)} times from {t_origin}"
    return assemble_product(
        x_m, y_m, u, v, times, t_origin, projection, desc, notes, interpolation, layout="cf"
    )


def assemble_product(
    x_m, y_m, u, v, times, t_origin, projection, desc, notes, interpolation, *, layout: str
) -> CurrentProduct:
    """The product from ``(members, time, y, x)`` velocities on a regular metric grid: the members' mean
    as the field (land where any member has no value), each member on the same grid."""
    n_members = u.shape[0]
    land = np.any(~np.isfinite(u) | ~np.isfinite(v), axis=(0, 1))
    frac = float(np.mean(land))
    if frac > 0:
        notes.append(f"{100 * frac:.0f}% land/missing cells kept as NaN")
    members: tuple[GridCurrent, ...] = ()
    if n_members > 1:
        members = tuple(
            GridCurrent(x_m=x_m, y_m=y_m, u_mps=u[m], v_mps=v[m], time_s=times, interpolation=interpolation)
            for m in range(n_members)
        )
        notes.append(f"ensemble of {n_members} members (field: their mean)")
        mean_u = np.where(land, np.nan, np.mean(u, axis=0))
        mean_v = np.where(land, np.nan, np.mean(v, axis=0))
    else:
        mean_u, mean_v = u[0], v[0]
    field_ = GridCurrent(
        x_m=x_m, y_m=y_m, u_mps=mean_u, v_mps=mean_v, time_s=times, interpolation=interpolation
    )
    if notes:
        desc += " (" + "; ".join(notes) + ")"
    return CurrentProduct(
        field=field_,
        projection=projection,
        time_origin=t_origin,
        description=desc,
        members=members,
        layout=layout,
    )


def choose_level(
    ds, path: Path, zname: str, depth_index: int | None, depth_m: float | None
) -> tuple[int, str]:
    """The index of the level to read on depth axis ``zname`` and a note saying which (see
    :func:`open_current_product`); depths are positive down whatever the axis' ``positive`` attribute."""
    n = ds.sizes[zname]
    if zname in ds.variables:
        z = np.asarray(ds[zname].values, dtype=float)
        if str(ds[zname].attrs.get("positive", "down")).lower() == "up" or (z.size > 1 and np.all(z <= 0)):
            z = -z
    else:
        z = np.arange(n, dtype=float)
    if depth_index is not None:
        if not 0 <= depth_index < n:
            raise DataError(f"{path}: depth index {depth_index} outside 0..{n - 1} of '{zname}'")
        k = depth_index
    elif depth_m is not None:
        if zname not in ds.variables:
            raise DataError(f"{path}: depth axis '{zname}' has no coordinate values; give a depth index")
        if not (np.isfinite(depth_m) and depth_m >= 0):
            raise DataError(f"{path}: depth must be a non-negative number of metres, got {depth_m}")
        if depth_m > np.nanmax(z) + 0.5 * _spacing(z):
            raise DataError(
                f"{path}: depth {depth_m:g} m is below the deepest level of '{zname}' ({np.nanmax(z):g} m)"
            )
        k = int(np.nanargmin(np.abs(z - depth_m)))
    else:
        k = int(np.nanargmin(np.abs(z)))
    return k, f"level {k} of '{zname}' ({z[k]:g} m)"


def _spacing(z: FloatArray) -> float:
    return float(np.max(np.abs(np.diff(np.sort(z))))) if z.size > 1 else 0.0


def time_slices(ds, path: Path, tname: str, window: tuple[str, str] | None) -> tuple[np.ndarray | None, str]:
    """Indices of the time slices covering ``window`` (one more on each side where there is one), and a
    note; ``None`` (all slices) without a window."""
    if window is None:
        return None, ""
    values = ds[tname].values
    if not np.issubdtype(values.dtype, np.datetime64):
        raise DataError(f"{path}: a time window needs dates on '{tname}' (its units must say 'since ...')")
    try:
        lo, hi = (np.datetime64(str(w).strip().rstrip("Z"), "s") for w in window)
    except ValueError:
        raise DataError(f"{path}: time window must be two ISO 8601 times, got {window!r}") from None
    if not lo <= hi:
        raise DataError(f"{path}: time window starts after it ends ({window[0]} > {window[1]})")
    t = values.astype("datetime64[s]")
    first, last = np.datetime_as_string(t[0]), np.datetime_as_string(t[-1])
    if hi < t[0] or lo > t[-1]:
        raise DataError(
            f"{path}: time window {window[0]} .. {window[1]} is outside the product ({first} .. {last})"
        )
    i0 = max(int(np.searchsorted(t, lo, side="right")) - 1, 0)
    i1 = min(int(np.searchsorted(t, hi, side="left")), t.size - 1)
    keep = np.arange(i0, i1 + 1)
    if keep.size < 2 and t.size >= 2:
        keep = np.arange(max(i0 - 1, 0), min(i0 + 2, t.size))
    return keep, f"time window {window[0]} .. {window[1]}: {keep.size} of {t.size} slices"


def _horizontal(ds, p: Path, dims: dict):
    x_units = str(ds[dims["x"]].attrs.get("units", "")).strip() if dims["x"] in ds.variables else ""
    y_units = str(ds[dims["y"]].attrs.get("units", "")).strip() if dims["y"] in ds.variables else ""
    xc = np.asarray(ds[dims["x"]].values, dtype=float) if dims["x"] in ds.variables else None
    yc = np.asarray(ds[dims["y"]].values, dtype=float) if dims["y"] in ds.variables else None
    if xc is None or yc is None:
        raise DataError(f"{p}: horizontal dimensions {dims['y']}, {dims['x']} have no coordinate values")
    return xc, yc, x_units, y_units


def _find_velocity(
    ds, path: Path, name: str | None, standard: tuple[str, ...], usual: tuple[str, ...], which: str
):
    if name is not None:
        if name not in ds.data_vars:
            raise DataError(
                f"{path}: no variable '{name}' ({which} velocity); "
                f"variables: {', '.join(map(str, ds.data_vars))}"
            )
        return ds[name]
    for var in ds.data_vars.values():
        if str(var.attrs.get("standard_name", "")) in standard:
            return var
    for cand in usual:
        if cand in ds.data_vars:
            return ds[cand]
    raise DataError(
        f"{path}: no {which} velocity variable (standard_name {standard[0]} or one of {', '.join(usual)}); "
        f"variables: {', '.join(map(str, ds.data_vars)) or 'none'}"
    )


def _velocity_scale(path: Path, da) -> float:
    units = str(da.attrs.get("units", "")).strip()
    if not units:
        raise DataError(
            f"{path}: variable '{da.name}' has no units attribute; expected a velocity such as 'm s-1'"
        )
    if units in _MPS_UNITS:
        return 1.0
    if units in _CMPS_UNITS:
        return 0.01
    raise DataError(
        f"{path}: variable '{da.name}' has units '{units}', not a velocity (expected 'm s-1' or 'cm s-1')"
    )


def _length_scale(units: str, path: Path, name: str) -> float:
    if units in _M_UNITS:
        return 1.0
    if units in _KM_UNITS:
        return 1000.0
    raise DataError(f"{path}: coordinate '{name}' has units '{units}'; expected metres or kilometres")


def _classify_dims(ds, path: Path, da) -> dict:
    out: dict = {"x": None, "y": None, "t": None, "z": None, "m": None, "kind": None}
    for dim in da.dims:
        coord = ds[dim] if dim in ds.variables else None
        attrs = coord.attrs if coord is not None else {}
        sname = str(attrs.get("standard_name", "")).lower()
        units = str(attrs.get("units", "")).lower()
        axis = str(attrs.get("axis", "")).upper()
        lname = str(dim).lower()
        if (
            sname == "longitude"
            or units in ("degrees_east", "degree_east", "degrees_e")
            or lname in ("lon", "longitude", "nav_lon")
        ):
            out["x"], out["kind"] = dim, "lonlat"
        elif (
            sname == "latitude"
            or units in ("degrees_north", "degree_north", "degrees_n")
            or lname in ("lat", "latitude", "nav_lat")
        ):
            out["y"] = dim
        elif sname == "projection_x_coordinate" or (axis == "X") or lname == "x":
            out["x"], out["kind"] = dim, out["kind"] or "xy"
        elif sname == "projection_y_coordinate" or (axis == "Y") or lname == "y":
            out["y"] = dim
        elif sname == "time" or axis == "T" or lname in ("time", "t", "ocean_time"):
            out["t"] = dim
        elif sname == "realization" or lname in MEMBER_DIMS:
            out["m"] = dim
        elif (
            sname in ("depth", "altitude", "height")
            or axis == "Z"
            or lname in ("depth", "z", "level", "lev", "deptht", "s_rho")
        ):
            out["z"] = dim
        else:
            raise DataError(
                f"{path}: cannot tell what dimension '{dim}' of '{da.name}' is (not lon/lat/x/y/time/depth)"
            )
    if out["x"] is None or out["y"] is None:
        raise DataError(f"{path}: '{da.name}' needs longitude/latitude or x/y dimensions, has {da.dims}")
    return out


def _time_seconds(ds, path: Path, name: str) -> tuple[FloatArray, str]:
    """Seconds since the first slice of time axis ``name`` of ``ds`` (a dataset or a data array), and that
    first slice (ISO 8601)."""
    values = ds[name].values
    if np.issubdtype(values.dtype, np.datetime64):
        t = (values - values[0]) / np.timedelta64(1, "s")
        origin = np.datetime_as_string(values[0], unit="s")
    elif np.issubdtype(values.dtype, np.number):
        units = str(ds[name].attrs.get("units", "")).lower()
        per = {
            "s": 1.0,
            "sec": 1.0,
            "second": 1.0,
            "seconds": 1.0,
            "h": 3600.0,
            "hour": 3600.0,
            "hours": 3600.0,
            "d": 86400.0,
            "day": 86400.0,
            "days": 86400.0,
        }.get(units.split(" since ")[0].strip())
        if per is None:
            raise DataError(
                f"{path}: time '{name}' has units '{units}'; expected seconds, hours or days (since ...)"
            )
        t = (np.asarray(values, dtype=float) - float(values[0])) * per
        origin = f"{values[0]} {units}"
    else:
        raise DataError(f"{path}: time '{name}' is neither dates nor numbers")
    t = np.asarray(t, dtype=float)
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise DataError(f"{path}: time '{name}' is not strictly increasing")
    return t, str(origin)


def _sample_rectilinear(
    xc: FloatArray, yc: FloatArray, values: FloatArray, xq: FloatArray, yq: FloatArray
) -> FloatArray:
    """Bilinear sampling of ``values (nt, ny, nx)`` on increasing rectilinear axes at points ``(xq, yq)``.

    ``NaN`` where a surrounding node is ``NaN`` or the point lies outside the axes.
    """
    ix = np.clip(np.searchsorted(xc, xq, side="right") - 1, 0, xc.size - 2)
    iy = np.clip(np.searchsorted(yc, yq, side="right") - 1, 0, yc.size - 2)
    tx = (xq - xc[ix]) / (xc[ix + 1] - xc[ix])
    ty = (yq - yc[iy]) / (yc[iy + 1] - yc[iy])
    out = (values[:, iy, ix] * (1 - tx) + values[:, iy, ix + 1] * tx) * (1 - ty) + (
        values[:, iy + 1, ix] * (1 - tx) + values[:, iy + 1, ix + 1] * tx
    ) * ty
    outside = (tx < -1e-9) | (tx > 1 + 1e-9) | (ty < -1e-9) | (ty > 1 + 1e-9)
    out[:, outside] = np.nan
    return out


def _increasing(axis: FloatArray, u: FloatArray, v: FloatArray, dim: int, name: str):
    """Make ``axis`` increasing, flipping ``u`` and ``v`` along ``dim`` with it."""
    if axis.size < 2:
        raise DataError(f"the grid needs at least two nodes along {name}")
    step = np.diff(axis)
    if np.all(step < 0):
        return axis[::-1], np.flip(u, axis=dim), np.flip(v, axis=dim)
    if not np.all(step > 0):
        raise DataError(f"{name} is not monotonic")
    return axis, u, v


def _regrid_xy(xc: FloatArray, yc: FloatArray, u: FloatArray, v: FloatArray):
    xc, u, v = _increasing(xc, u, v, 2, "x")
    yc, u, v = _increasing(yc, u, v, 1, "y")
    dx = float(np.min(np.diff(xc)))
    dy = float(np.min(np.diff(yc)))
    if np.allclose(np.diff(xc), dx, rtol=1e-6) and np.allclose(np.diff(yc), dy, rtol=1e-6):
        return xc, yc, u, v
    xs = np.arange(xc[0], xc[-1] + 1e-9 * dx, dx)
    ys = np.arange(yc[0], yc[-1] + 1e-9 * dy, dy)
    gx, gy = np.meshgrid(xs, ys)
    su = _sample_rectilinear(xc, yc, u, gx.ravel(), gy.ravel()).reshape(u.shape[0], ys.size, xs.size)
    sv = _sample_rectilinear(xc, yc, v, gx.ravel(), gy.ravel()).reshape(v.shape[0], ys.size, xs.size)
    return xs, ys, su, sv


def _regrid_lonlat(
    lon: FloatArray, lat: FloatArray, u: FloatArray, v: FloatArray, origin: tuple[float, float] | None
):
    if np.any(lon > 180.0):
        wrapped = np.where(lon > 180.0, lon - 360.0, lon)
        if np.all(np.diff(wrapped) > 0):
            lon = wrapped
    lon, u, v = _increasing(lon, u, v, 2, "longitude")
    lat, u, v = _increasing(lat, u, v, 1, "latitude")
    lon0, lat0 = origin if origin is not None else (0.5 * (lon[0] + lon[-1]), 0.5 * (lat[0] + lat[-1]))
    proj = LocalProjection(lat0_deg=float(lat0), lon0_deg=float(lon0))
    # Extent: the largest metric rectangle inside the lon/lat box (its corners in the local plane).
    cx, cy = proj.to_local(
        np.array([lon[0], lon[-1], lon[0], lon[-1]]), np.array([lat[0], lat[0], lat[-1], lat[-1]])
    )
    x0, x1 = max(cx[0], cx[2]), min(cx[1], cx[3])
    y0, y1 = max(cy[0], cy[1]), min(cy[2], cy[3])
    ex, _ = proj.to_local(np.array([lon0, lon0 + np.min(np.diff(lon))]), np.array([lat0, lat0]))
    _, ey = proj.to_local(np.array([lon0, lon0]), np.array([lat0, lat0 + np.min(np.diff(lat))]))
    step = float(min(abs(ex[1] - ex[0]), abs(ey[1] - ey[0])))
    # A metre inside the box, so that rounding in the round trip never puts an edge node outside it.
    x0, x1, y0, y1 = x0 + 1.0, x1 - 1.0, y0 + 1.0, y1 - 1.0
    xs = np.arange(x0, x1 + 1e-9, step)
    ys = np.arange(y0, y1 + 1e-9, step)
    gx, gy = np.meshgrid(xs, ys)
    qlon, qlat = proj.to_lonlat(gx.ravel(), gy.ravel())
    su = _sample_rectilinear(lon, lat, u, qlon, qlat).reshape(u.shape[0], ys.size, xs.size)
    sv = _sample_rectilinear(lon, lat, v, qlon, qlat).reshape(v.shape[0], ys.size, xs.size)
    return xs, ys, su, sv, proj


def land_obstacles(field: GridCurrent) -> OccupancyGrid | None:
    """Land cells of a gridded current as an occupancy grid (a cell centred on each node), or ``None``."""
    land = field.land_mask()
    if not land.any():
        return None
    dx, dy = field.spacing_m
    if not np.isclose(dx, dy, rtol=1e-6):
        raise DataError("land masks need square grid cells")
    return OccupancyGrid(
        x0_m=float(field.x_m[0] - 0.5 * dx), y0_m=float(field.y_m[0] - 0.5 * dy), cell_m=dx, occupied=land
    )


def write_current_netcdf(
    path: str | Path,
    field: GridCurrent,
    *,
    projection: LocalProjection | None = None,
    time_origin: str = "2024-01-01T00:00:00",
) -> Path:
    """Write ``field`` as a CF-1.8 NetCDF file (``uo``/``vo`` in m s-1).

    With a ``projection`` the grid axes are written as longitude/latitude along the grid's central row and
    column (a rectilinear lon/lat grid, as Copernicus and HYCOM products are); otherwise as projected
    ``x``/``y`` in metres. ``NaN`` is written as the ``_FillValue``.
    """
    xr = _import_xarray()
    p = Path(path)
    u, v = field.u_mps, field.v_mps
    data_dims: tuple[str, ...]
    coords: dict = {}
    if projection is None:
        coords["x"] = (
            "x",
            field.x_m,
            {"standard_name": "projection_x_coordinate", "units": "m", "axis": "X"},
        )
        coords["y"] = (
            "y",
            field.y_m,
            {"standard_name": "projection_y_coordinate", "units": "m", "axis": "Y"},
        )
        data_dims = ("y", "x")
    else:
        lon, _ = projection.to_lonlat(field.x_m, np.zeros_like(field.x_m))
        _, lat = projection.to_lonlat(np.zeros_like(field.y_m), field.y_m)
        coords["longitude"] = ("longitude", lon, {"standard_name": "longitude", "units": "degrees_east"})
        coords["latitude"] = ("latitude", lat, {"standard_name": "latitude", "units": "degrees_north"})
        data_dims = ("latitude", "longitude")
    if field.time_s is not None:
        base = np.datetime64(time_origin, "s")
        coords["time"] = (
            "time",
            base + (field.time_s * 1e3).astype("timedelta64[ms]"),
            {"standard_name": "time"},
        )
        data_dims = ("time", *data_dims)
    else:
        u, v = u[0], v[0]
    attrs_u = {
        "standard_name": "eastward_sea_water_velocity",
        "units": "m s-1",
        "long_name": "eastward current",
    }
    attrs_v = {
        "standard_name": "northward_sea_water_velocity",
        "units": "m s-1",
        "long_name": "northward current",
    }
    ds = xr.Dataset(
        {"uo": (data_dims, u, attrs_u), "vo": (data_dims, v, attrs_v)},
        coords=coords,
        attrs={"Conventions": "CF-1.8", "source": "oceanloc"},
    )
    encoding = {name: {"_FillValue": np.float32(-9999.0), "dtype": "float32"} for name in ("uo", "vo")}
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(p, engine="netcdf4", encoding=encoding)
    except OSError as exc:
        raise DataError(f"{p}: cannot write NetCDF ({exc})") from None
    return p
