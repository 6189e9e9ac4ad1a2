"""Forecast current products written in their real layouts, for the reader and command-line tests.

Every layout carries the same truth: a double gyre (two 10 km gyres, 0.4 m/s, its dividing line swinging
with a 6 h period) in the local frame about ORIGIN, weaker with depth (e-folding 50 m), with a square
island of land. The variable names, attributes, packing and fill values are those of the products:

- Copernicus Marine (the ``copernicusmarine`` toolbox's subsets): ``uo``/``vo`` float32 with NaN fill on
  ``(time, depth, latitude, longitude)``, time in hours since 1950, depth positive down; as NetCDF and as
  a Zarr store;
- HYCOM (GOFS 3.1 THREDDS subsets): ``water_u``/``water_v`` int16 packed with ``scale_factor = 0.001``,
  ``_FillValue = missing_value = -30000``, longitudes 0-360, time in hours since 2000;
- ROMS: ``u``/``v`` on the staggered C grid of a curvilinear grid turned by ``angle``, ``s_rho`` levels,
  ``mask_rho``, ``_FillValue = 1e37``, time ``ocean_time`` in seconds;
- FVCOM: ``u``/``v`` on the elements of a triangular mesh (refused by the reader);
- an ensemble: the Copernicus layout with a ``member`` dimension.
"""

from __future__ import annotations

import math

import numpy as np

from oceanloc.geo.projection import LocalProjection
from oceanloc.models.currents import DoubleGyreCurrent

ORIGIN = (-117.3, 32.6)  # lon, lat
PROJ = LocalProjection(lat0_deg=ORIGIN[1], lon0_deg=ORIGIN[0])
GYRE = DoubleGyreCurrent(
    length_m=10_000.0,
    amplitude_mps=0.4,
    epsilon=0.25,
    omega_rad_s=2 * math.pi / 21_600.0,
    origin_m=(-10_000.0, -5000.0),
)
ISLAND_M = (-1500.0, 500.0, 1000.0, 2500.0)  # x0, x1, y0, y1 in the local frame
DEPTHS_M = np.array([0.494025, 5.078224, 10.53566, 50.0])
START = np.datetime64("2024-03-01T00:00:00", "s")
HOURS = np.arange(31)


def truth(x_m, y_m, t_s, depth_m=0.0):
    """The current every layout holds (east, north in m/s); NaN on the island and outside the gyres."""
    u, v = GYRE.velocity_xy(np.asarray(x_m, float), np.asarray(y_m, float), np.asarray(t_s, float))
    k = np.exp(-np.asarray(depth_m, float) / 50.0)
    x0, x1, y0, y1 = ISLAND_M
    land = (
        (np.asarray(x_m) >= x0) & (np.asarray(x_m) <= x1) & (np.asarray(y_m) >= y0) & (np.asarray(y_m) <= y1)
    )
    return np.where(land, np.nan, u * k), np.where(land, np.nan, v * k)


def lonlat_axes(step_deg: float = 0.005):
    """Longitudes and latitudes covering the gyres (about 460 m by 555 m cells)."""
    lon_a, lat_a = PROJ.to_lonlat(np.array([-10_000.0, 10_000.0]), np.array([-5000.0, 5000.0]))
    lon = np.arange(lon_a[0] - 0.01, lon_a[1] + 0.01, step_deg)
    lat = np.arange(lat_a[0] - 0.01, lat_a[1] + 0.01, step_deg)
    return lon, lat


def _gridded(lon, lat, hours=HOURS, depths=DEPTHS_M):
    glon, glat = np.meshgrid(lon, lat)
    x, y = PROJ.to_local(glon, glat)
    u = np.empty((hours.size, depths.size, lat.size, lon.size))
    v = np.empty_like(u)
    for i, h in enumerate(hours):
        for k, d in enumerate(depths):
            u[i, k], v[i, k] = truth(x, y, 3600.0 * h, d)
    return u, v


def copernicus_dataset(members: int = 0):
    import xarray as xr

    lon, lat = lonlat_axes()
    u, v = _gridded(lon, lat)
    dims = ("time", "depth", "latitude", "longitude")
    attrs_u = {
        "standard_name": "eastward_sea_water_velocity",
        "long_name": "Eastward velocity",
        "units": "m s-1",
        "valid_min": np.float32(-5.0),
        "valid_max": np.float32(5.0),
    }
    attrs_v = {**attrs_u, "standard_name": "northward_sea_water_velocity", "long_name": "Northward velocity"}
    if members:
        scale = 1.0 + 0.1 * (np.arange(members) - (members - 1) / 2.0)
        u = u[None] * scale[:, None, None, None, None]
        v = v[None] * scale[:, None, None, None, None]
        dims = ("member", *dims)
    data = {"uo": (dims, u.astype(np.float32), attrs_u), "vo": (dims, v.astype(np.float32), attrs_v)}
    coords = {
        "time": (
            "time",
            START + HOURS * np.timedelta64(3600, "s"),
            {"standard_name": "time", "axis": "T", "long_name": "Time"},
        ),
        "depth": (
            "depth",
            DEPTHS_M.astype(np.float32),
            {"standard_name": "depth", "units": "m", "positive": "down", "axis": "Z", "long_name": "Depth"},
        ),
        "latitude": (
            "latitude",
            lat.astype(np.float32),
            {"standard_name": "latitude", "units": "degrees_north", "axis": "Y"},
        ),
        "longitude": (
            "longitude",
            lon.astype(np.float32),
            {"standard_name": "longitude", "units": "degrees_east", "axis": "X"},
        ),
    }
    if members:
        coords["member"] = ("member", np.arange(members), {"standard_name": "realization"})
    ds = xr.Dataset(
        data,
        coords=coords,
        attrs={"Conventions": "CF-1.0", "source": "MERCATOR GLO12", "copernicusmarine_version": "2.0.0"},
    )
    encoding = {name: {"_FillValue": np.float32(np.nan), "dtype": "float32"} for name in ("uo", "vo")}
    encoding["time"] = {"units": "hours since 1950-01-01", "calendar": "gregorian", "dtype": "float64"}
    return ds, encoding


def write_copernicus_netcdf(path, members: int = 0):
    ds, encoding = copernicus_dataset(members)
    ds.to_netcdf(path, engine="netcdf4", encoding=encoding)
    return path


def write_copernicus_zarr(path):
    ds, encoding = copernicus_dataset()
    ds.to_zarr(path, encoding=encoding, mode="w", consolidated=False)
    return path


def write_hycom_netcdf(path):
    import xarray as xr

    lon, lat = lonlat_axes(0.04 / 5)
    depths = np.array([0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0])
    hours = HOURS[::3]
    u, v = _gridded(lon, lat, hours, depths)
    dims = ("time", "depth", "lat", "lon")
    attrs = {
        "long_name": "Eastward Water Velocity",
        "standard_name": "eastward_sea_water_velocity",
        "units": "m/s",
        "NAVO_code": 17,
    }
    ds = xr.Dataset(
        {
            "water_u": (dims, u, attrs),
            "water_v": (
                dims,
                v,
                {
                    **attrs,
                    "long_name": "Northward Water Velocity",
                    "standard_name": "northward_sea_water_velocity",
                    "NAVO_code": 18,
                },
            ),
        },
        coords={
            "time": (
                "time",
                START + hours * np.timedelta64(3600, "s"),
                {"long_name": "Valid Time", "axis": "T"},
            ),
            "depth": (
                "depth",
                depths,
                {
                    "long_name": "Depth",
                    "standard_name": "depth",
                    "units": "m",
                    "positive": "down",
                    "axis": "Z",
                },
            ),
            "lat": (
                "lat",
                lat,
                {"long_name": "Latitude", "standard_name": "latitude", "units": "degrees_north", "axis": "Y"},
            ),
            "lon": (
                "lon",
                lon % 360.0,
                {
                    "long_name": "Longitude",
                    "standard_name": "longitude",
                    "units": "degrees_east",
                    "axis": "X",
                },
            ),
        },
        attrs={
            "Conventions": "CF-1.0",
            "source": "HYCOM archive file",
            "institution": "Naval Oceanographic Office",
        },
    )
    packed = {
        "dtype": "int16",
        "scale_factor": 0.001,
        "add_offset": 0.0,
        "_FillValue": np.int16(-30000),
        "missing_value": np.int16(-30000),
    }
    encoding = {
        "water_u": packed,
        "water_v": packed,
        "time": {"units": "hours since 2000-01-01 00:00:00", "calendar": "gregorian", "dtype": "float64"},
    }
    ds.to_netcdf(path, engine="netcdf4", encoding=encoding)
    return path


ROMS_ANGLE = math.radians(30.0)


def write_roms(path):
    """A 12 x 22 km ROMS grid turned 30 degrees from east (xi) at 400 m, 4 s-levels, hourly for 30 h."""
    import xarray as xr

    h = 400.0
    nxi, neta = 56, 31
    xi = (np.arange(nxi) - (nxi - 1) / 2) * h
    eta = (np.arange(neta) - (neta - 1) / 2) * h
    gxi, geta = np.meshgrid(xi, eta)
    c, s = math.cos(ROMS_ANGLE), math.sin(ROMS_ANGLE)
    x = gxi * c - geta * s
    y = gxi * s + geta * c
    lon, lat = PROJ.to_lonlat(x, y)
    s_rho = np.array([-0.875, -0.625, -0.375, -0.125])
    hours = HOURS
    nt = hours.size
    u_rho = np.empty((nt, s_rho.size, neta, nxi))
    v_rho = np.empty_like(u_rho)
    for i, hr in enumerate(hours):
        ue, vn = truth(x, y, 3600.0 * hr)
        for k in range(s_rho.size):
            u_rho[i, k] = ue * c + vn * s  # along xi
            v_rho[i, k] = -ue * s + vn * c  # along eta
    mask = np.isfinite(u_rho[0, 0]).astype(float)
    u = 0.5 * (u_rho[..., :-1] + u_rho[..., 1:])
    v = 0.5 * (v_rho[..., :-1, :] + v_rho[..., 1:, :])
    u = np.where(np.isfinite(u), u, 1e37)
    v = np.where(np.isfinite(v), v, 1e37)
    ms = {"units": "meter second-1", "time": "ocean_time"}
    ds = xr.Dataset(
        {
            "u": (
                ("ocean_time", "s_rho", "eta_u", "xi_u"),
                u,
                {
                    **ms,
                    "long_name": "u-momentum component",
                    "coordinates": "lon_u lat_u s_rho ocean_time",
                    "field": "u-velocity, scalar, series",
                },
            ),
            "v": (
                ("ocean_time", "s_rho", "eta_v", "xi_v"),
                v,
                {
                    **ms,
                    "long_name": "v-momentum component",
                    "coordinates": "lon_v lat_v s_rho ocean_time",
                    "field": "v-velocity, scalar, series",
                },
            ),
            "mask_rho": (
                ("eta_rho", "xi_rho"),
                mask,
                {"long_name": "mask on RHO-points", "flag_values": [0.0, 1.0]},
            ),
            "angle": (
                ("eta_rho", "xi_rho"),
                np.full((neta, nxi), ROMS_ANGLE),
                {"long_name": "angle between XI-axis and EAST", "units": "radians"},
            ),
            "h": (
                ("eta_rho", "xi_rho"),
                np.full((neta, nxi), 200.0),
                {"long_name": "bathymetry at RHO-points", "units": "meter"},
            ),
            "lon_rho": (
                ("eta_rho", "xi_rho"),
                lon,
                {
                    "long_name": "longitude of RHO-points",
                    "units": "degree_east",
                    "standard_name": "longitude",
                },
            ),
            "lat_rho": (
                ("eta_rho", "xi_rho"),
                lat,
                {"long_name": "latitude of RHO-points", "units": "degree_north", "standard_name": "latitude"},
            ),
        },
        coords={
            "ocean_time": (
                "ocean_time",
                START + hours * np.timedelta64(3600, "s"),
                {"long_name": "time since initialization"},
            ),
            "s_rho": (
                "s_rho",
                s_rho,
                {
                    "long_name": "S-coordinate at RHO-points",
                    "positive": "up",
                    "standard_name": "ocean_s_coordinate_g2",
                },
            ),
        },
        attrs={"type": "ROMS/TOMS history file", "Conventions": "CF-1.4, SGRID"},
    )
    enc = {name: {"_FillValue": 1e37} for name in ("u", "v")}
    enc["ocean_time"] = {"units": "seconds since 2024-03-01 00:00:00", "calendar": "gregorian"}
    ds.to_netcdf(path, engine="netcdf4", encoding=enc)
    return path


def write_fvcom(path):
    import xarray as xr

    n = 40
    rng = np.random.default_rng(0)
    lonc = ORIGIN[0] + rng.uniform(-0.05, 0.05, n)
    latc = ORIGIN[1] + rng.uniform(-0.05, 0.05, n)
    ds = xr.Dataset(
        {
            "u": (
                ("time", "siglay", "nele"),
                np.zeros((2, 3, n), np.float32),
                {"long_name": "Eastward Water Velocity", "units": "meters s-1"},
            ),
            "v": (
                ("time", "siglay", "nele"),
                np.zeros((2, 3, n), np.float32),
                {"long_name": "Northward Water Velocity", "units": "meters s-1"},
            ),
            "nv": (
                ("three", "nele"),
                rng.integers(1, 20, (3, n)).astype(np.int32),
                {"long_name": "nodes surrounding element"},
            ),
            "lonc": ("nele", lonc, {"long_name": "zonal longitude", "units": "degrees_east"}),
            "latc": ("nele", latc, {"long_name": "zonal latitude", "units": "degrees_north"}),
        },
        coords={"time": ("time", np.array([0.0, 1.0]), {"units": "days since 1858-11-17 00:00:00"})},
        attrs={"source": "FVCOM_4.3"},
    )
    ds.to_netcdf(path, engine="netcdf4")
    return path
