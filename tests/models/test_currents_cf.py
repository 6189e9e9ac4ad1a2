import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.geo.projection import LocalProjection
from oceanloc.models.currents import DoubleGyreCurrent, GridCurrent
from oceanloc.models.currents_cf import land_obstacles, open_current_netcdf, write_current_netcdf

xr = pytest.importorskip("xarray")

GYRE = DoubleGyreCurrent(length_m=5000.0, amplitude_mps=0.5, epsilon=0.2, omega_rad_s=2 * np.pi / 86_400)


def _gyre_grid(times=(0.0, 3600.0, 7200.0)):
    x = np.linspace(0.0, 10_000.0, 41)
    y = np.linspace(0.0, 5000.0, 21)
    gx, gy = np.meshgrid(x, y)
    u = np.stack([GYRE.velocity_xy(gx, gy, t)[0] for t in times])
    v = np.stack([GYRE.velocity_xy(gx, gy, t)[1] for t in times])
    return x, y, u, v, np.asarray(times)


def test_double_gyre_round_trip_on_a_projected_grid(tmp_path):
    x, y, u, v, t = _gyre_grid()
    u[:, 10, 20] = np.nan  # one land node
    v[:, 10, 20] = np.nan
    path = write_current_netcdf(tmp_path / "gyre.nc", GridCurrent(x_m=x, y_m=y, u_mps=u, v_mps=v, time_s=t))
    product = open_current_netcdf(path)
    f = product.field
    np.testing.assert_allclose(f.x_m, x)
    np.testing.assert_allclose(f.time_s, t)
    # Written as float32: relative rounding 6e-8 of 0.5 m/s.
    np.testing.assert_allclose(f.u_mps, u, atol=1e-7)
    assert np.isnan(f.u_mps[0, 10, 20]) and f.land_mask().sum() == 1
    assert "uo/vo" in product.description and product.projection is None
    # Between nodes and slices the field interpolates the analytic gyre: bilinear error h^2/8 |u''| with
    # h = 250 m, |u''| <= A (pi/L)^2 = 2e-7 -> 1.6e-3 m/s, plus time interpolation of the same order.
    rng = np.random.default_rng(0)
    px, py, pt = rng.uniform(500, 9500, 100), rng.uniform(2600, 4500, 100), rng.uniform(0, 7200, 100)
    got = f.velocity_xy(px, py, pt)[0]
    exact = GYRE.velocity_xy(px, py, pt)[0]
    assert np.max(np.abs(got - exact)) < 4e-3
    grid = land_obstacles(f)
    assert grid is not None and grid.occupied.sum() == 1


def test_lonlat_product_is_resampled_to_metres(tmp_path):
    x, y, u, v, _ = _gyre_grid(times=(0.0,))
    proj = LocalProjection(lat0_deg=32.7, lon0_deg=-117.2)
    path = write_current_netcdf(
        tmp_path / "ll.nc", GridCurrent(x_m=x - 5000, y_m=y - 2500, u_mps=u, v_mps=v), projection=proj
    )
    product = open_current_netcdf(path, origin_lonlat_deg=(-117.2, 32.7))
    f = product.field
    assert product.projection is not None
    assert "resampled" in product.description
    # Same frame (the writer places rows/columns along the axes through the origin): the resampled field
    # reproduces the gyre within interpolation error (see the projected test) plus the tangent-plane offset.
    px, py = np.array([-2000.0, 0.0, 2400.0]), np.array([500.0, -1000.0, 1500.0])
    got = f.velocity_xy(px, py)
    exact = GYRE.velocity_xy(px + 5000, py + 2500)
    np.testing.assert_allclose(got[0], exact[0], atol=5e-3)
    np.testing.assert_allclose(got[1], exact[1], atol=5e-3)


def _dataset(**overrides):
    x = np.arange(4) * 100.0
    y = np.arange(3) * 100.0
    attrs_u = {"standard_name": "eastward_sea_water_velocity", "units": "m s-1"}
    attrs_v = {"standard_name": "northward_sea_water_velocity", "units": "m s-1"}
    attrs_u.update(overrides.pop("u_attrs", {}))
    data = {
        "uo": (("y", "x"), overrides.pop("u", np.ones((3, 4))), attrs_u),
        "vo": (("y", "x"), np.zeros((3, 4)), attrs_v),
    }
    coords = {"x": ("x", x, {"units": "m", "axis": "X"}), "y": ("y", y, {"units": "m", "axis": "Y"})}
    return xr.Dataset(data, coords=coords)


def test_missing_velocity_variable_is_named(tmp_path):
    ds = _dataset().drop_vars("vo")
    ds.to_netcdf(tmp_path / "a.nc", engine="netcdf4")
    with pytest.raises(DataError, match=r"a\.nc: no northward velocity variable .*variables: uo"):
        open_current_netcdf(tmp_path / "a.nc")


def test_wrong_or_missing_units_are_errors(tmp_path):
    _dataset(u_attrs={"units": "degC"}).to_netcdf(tmp_path / "b.nc", engine="netcdf4")
    with pytest.raises(DataError, match="'uo' has units 'degC', not a velocity"):
        open_current_netcdf(tmp_path / "b.nc")
    ds = _dataset()
    del ds["uo"].attrs["units"]
    ds.to_netcdf(tmp_path / "c.nc", engine="netcdf4")
    with pytest.raises(DataError, match="no units attribute"):
        open_current_netcdf(tmp_path / "c.nc")


def test_centimetres_per_second_are_converted(tmp_path):
    _dataset(u_attrs={"units": "cm s-1"}, u=np.full((3, 4), 50.0)).to_netcdf(
        tmp_path / "d.nc", engine="netcdf4"
    )
    assert open_current_netcdf(tmp_path / "d.nc").field.u_mps.max() == pytest.approx(0.5)


def test_all_land_and_garbage_files_are_errors(tmp_path):
    _dataset(u=np.full((3, 4), np.nan)).to_netcdf(tmp_path / "e.nc", engine="netcdf4")
    with pytest.raises(DataError, match="no finite value"):
        open_current_netcdf(tmp_path / "e.nc")
    (tmp_path / "f.nc").write_bytes(b"this is not a netcdf file")
    with pytest.raises(DataError, match=r"f\.nc: cannot read as NetCDF"):
        open_current_netcdf(tmp_path / "f.nc")
    with pytest.raises(DataError, match="not found"):
        open_current_netcdf(tmp_path / "missing.nc")


def test_unknown_dimension_is_named(tmp_path):
    ds = _dataset().rename({"x": "foo"})
    ds["foo"].attrs = {"units": "m"}
    ds.to_netcdf(tmp_path / "g.nc", engine="netcdf4")
    with pytest.raises(DataError, match="dimension 'foo'"):
        open_current_netcdf(tmp_path / "g.nc")
