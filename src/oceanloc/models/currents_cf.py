"""Gridded surface currents from CF-convention NetCDF files (Copernicus Marine, HYCOM, ROMS subsets).

:func:`open_current_netcdf` reads eastward and northward velocity through xarray and returns a
:class:`~oceanloc.models.currents.GridCurrent` on a regular metric grid, ready for drift integration:

- velocity variables are found by CF ``standard_name`` (``eastward_sea_water_velocity``,
  ``surface_eastward_sea_water_velocity``, ... and their northward twins) or by the usual names (``uo/vo``,
  ``water_u/water_v``, ``u/v``), or named explicitly;
- units must be velocities (``m s-1``, ``m/s``, ``cm s-1`` ...); anything else, or no units, is an error
  naming the file and the variable;
- horizontal coordinates are longitude/latitude (degrees) or projected ``x/y`` (m or km); longitude and
  latitude grids are resampled once onto a regular grid in a local tangent plane
  (:class:`~oceanloc.geo.projection.LocalProjection`) with the same resolution;
- an optional time axis becomes seconds since its first slice; a depth axis is reduced to the level
  nearest the surface (or a chosen index);
- land and missing cells (``_FillValue``, ``NaN``) stay ``NaN``: drift stops there and
  :func:`land_obstacles` turns them into an occupancy grid for the planner. A file without one sea value is
  an error. Nothing ever becomes a silent zero current.

:func:`write_current_netcdf` writes a :class:`GridCurrent` (or a lon/lat grid) as CF NetCDF, used by the tests
and to produce example files.
"""

from __future__ import annotations

from dataclasses import dataclass
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

_MPS_UNITS = {
    "m s-1",
    "m/s",
    "m s**-1",
    "m s^-1",
    "meter second-1",
    "meters second-1",
    "meter/second",
    "meters/second",
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
        Velocity on a regular metric grid (``NaN`` on land).
    projection : LocalProjection or None
        The tangent plane used for longitude/latitude products (``None`` for projected ones).
    time_origin : str or None
        The first time slice (ISO 8601) that is time 0 of the field.
    description : str
        What was read: variables, grid, time and depth handling.
    """

    field: GridCurrent
    projection: LocalProjection | None
    time_origin: str | None
    description: str


def _import_xarray():
    try:
        import xarray as xr
    except ImportError:  # pragma: no cover - declared dependency
        raise DataError(
            "reading NetCDF currents needs xarray and netCDF4 (pip install xarray netCDF4)"
        ) from None
    return xr


def open_current_netcdf(
    path: str | Path,
    *,
    u_var: str | None = None,
    v_var: str | None = None,
    depth_index: int | None = None,
    origin_lonlat_deg: tuple[float, float] | None = None,
    interpolation: Interpolation = "linear",
) -> CurrentProduct:
    """Read a CF NetCDF current product (see the module docstring).

    Parameters
    ----------
    path : str or Path
        NetCDF file.
    u_var, v_var : str, optional
        Velocity variable names; found by standard name or usual names when omitted.
    depth_index : int, optional
        Level of a depth axis; the level nearest the surface when omitted.
    origin_lonlat_deg : (lon, lat), optional
        Origin of the local frame for longitude/latitude products; the grid centre when omitted.
    interpolation : {"linear", "cell"}
        Interpolation of the resulting :class:`GridCurrent`.

    Raises
    ------
    DataError
        Unreadable file, missing variables, wrong units, unusable coordinates, no sea value.
    """
    xr = _import_xarray()
    p = Path(path)
    if not p.is_file():
        raise DataError(f"{p}: current file not found")
    try:
        ds = xr.open_dataset(p, engine="netcdf4")
    except Exception as exc:
        raise DataError(f"{p}: cannot read as NetCDF ({type(exc).__name__}: {exc})") from None
    with ds:
        u_da = _find_velocity(ds, p, u_var, EASTWARD_NAMES, EASTWARD_VARS, "eastward")
        v_da = _find_velocity(ds, p, v_var, NORTHWARD_NAMES, NORTHWARD_VARS, "northward")
        if u_da.dims != v_da.dims:
            raise DataError(f"{p}: {u_da.name} has dimensions {u_da.dims} but {v_da.name} has {v_da.dims}")
        u_scale = _velocity_scale(p, u_da)
        v_scale = _velocity_scale(p, v_da)
        dims = _classify_dims(ds, p, u_da)
        notes: list[str] = []
        if dims["z"] is not None:
            zname = dims["z"]
            zvals = (
                np.asarray(ds[zname].values, dtype=float)
                if zname in ds.variables
                else np.arange(ds.sizes[zname])
            )
            k = int(np.argmin(np.abs(zvals))) if depth_index is None else depth_index
            if not 0 <= k < ds.sizes[zname]:
                raise DataError(f"{p}: depth index {k} outside 0..{ds.sizes[zname] - 1} of '{zname}'")
            u_da = u_da.isel({zname: k})
            v_da = v_da.isel({zname: k})
            notes.append(f"level {k} of '{zname}' ({zvals[k]:g})")
        tname = dims["t"]
        order = [d for d in (tname, dims["y"], dims["x"]) if d is not None]
        u = np.asarray(u_da.transpose(*order).values, dtype=float) * u_scale
        v = np.asarray(v_da.transpose(*order).values, dtype=float) * v_scale
        if tname is None:
            u, v = u[None], v[None]
            times, t_origin = None, None
        else:
            times, t_origin = _time_seconds(ds, p, tname)
        x_units = str(ds[dims["x"]].attrs.get("units", "")).strip() if dims["x"] in ds.variables else ""
        y_units = str(ds[dims["y"]].attrs.get("units", "")).strip() if dims["y"] in ds.variables else ""
        xc = np.asarray(ds[dims["x"]].values, dtype=float) if dims["x"] in ds.variables else None
        yc = np.asarray(ds[dims["y"]].values, dtype=float) if dims["y"] in ds.variables else None
        if xc is None or yc is None:
            raise DataError(f"{p}: horizontal dimensions {dims['y']}, {dims['x']} have no coordinate values")
        kind = dims["kind"]
        u_name, v_name = str(u_da.name), str(v_da.name)
    bad = ~(np.isfinite(u) & np.isfinite(v))
    u[bad] = np.nan
    v[bad] = np.nan
    if bad.all():
        raise DataError(f"{p}: {u_name}/{v_name} hold no finite value (all land or missing)")
    try:
        regridded = _regrid_lonlat(xc, yc, u, v, origin_lonlat_deg) if kind == "lonlat" else None
    except DataError as exc:
        raise DataError(f"{p}: {exc}") from None
    if regridded is not None:
        x_m, y_m, u, v, projection = regridded
        notes.append(
            f"lon/lat grid resampled to {x_m[1] - x_m[0]:.0f} m about "
            f"({projection.lon0_deg:.4f}, {projection.lat0_deg:.4f})"
        )
    else:
        xs = _length_scale(x_units, p, dims["x"])
        ys = _length_scale(y_units, p, dims["y"])
        try:
            x_m, y_m, u, v = _regrid_xy(xc * xs, yc * ys, u, v)
        except DataError as exc:
            raise DataError(f"{p}: {exc}") from None
        projection = None
    land = float(np.mean(np.any(~np.isfinite(u), axis=0)))
    if land > 0:
        notes.append(f"{100 * land:.0f}% land/missing cells kept as NaN")
    field = GridCurrent(x_m=x_m, y_m=y_m, u_mps=u, v_mps=v, time_s=times, interpolation=interpolation)
    desc = f"{p.name}: {u_name}/{v_name} on {len(x_m)} x {len(y_m)} nodes"
    if times is not None:
        desc += f", {len(times)} times from {t_origin}"
    if notes:
        desc += " (" + "; ".join(notes) + ")"
    return CurrentProduct(field=field, projection=projection, time_origin=t_origin, description=desc)


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
    out: dict = {"x": None, "y": None, "t": None, "z": None, "kind": None}
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
        elif sname == "time" or axis == "T" or lname in ("time", "t"):
            out["t"] = dim
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
