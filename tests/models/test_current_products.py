"""Forecast products in their real layouts (issue 26, section 2): Copernicus Marine NetCDF and Zarr, HYCOM,
ROMS on its own grid, an ensemble; FVCOM refused clearly; depth level and time window; land as obstacles."""

from __future__ import annotations

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.models.currents_cf import land_obstacles, open_current_product
from tests.models import product_layouts as lay

pytest.importorskip("xarray")

# Reading resamples lon/lat cells (at most 555 m) onto a metric grid, which the field then interpolates:
# bilinear error h^2/8 |u''| twice, with |u''| <= A (pi/L)^2 (1 + 2 eps)^2 = 9e-8 m^-1 s^-1 (the swinging
# divide stretches the gyre by up to 1 + 2 eps) -> 2 x 3.5e-3 m/s, plus float32 and the 1e-3 m/s packing.
TOL = 8e-3


def _check_against_truth(product, depth_m=0.0, t_s=(0.0, 10_800.0, 21_600.0)):
    """At time slices of every layout (every 3 h): between slices the field interpolates in time too."""
    f = product.field
    rng = np.random.default_rng(1)
    x = rng.uniform(-8000.0, 8000.0, 300)
    y = rng.uniform(-4000.0, 4000.0, 300)
    for t in t_s:
        got_u, got_v = f.velocity_xy(x, y, np.full(x.size, t))
        tu, tv = lay.truth(x, y, t, depth_m)
        sea = np.isfinite(got_u) & np.isfinite(tu)
        assert sea.mean() > 0.8
        assert np.max(np.abs(got_u[sea] - tu[sea])) < TOL
        assert np.max(np.abs(got_v[sea] - tv[sea])) < TOL
        # Land in the product is land (NaN) in the field: never a current on the island.
        x0, x1, y0, y1 = lay.ISLAND_M
        inside = (x > x0 + 600) & (x < x1 - 600) & (y > y0 + 600) & (y < y1 - 600)
        assert not np.isfinite(got_u[inside]).any()


@pytest.mark.parametrize("layout", ["copernicus-netcdf", "copernicus-zarr", "hycom"])
def test_regular_products_read_to_the_truth_with_land_as_obstacles(tmp_path, layout):
    if layout == "copernicus-zarr":
        pytest.importorskip("zarr")
        path = lay.write_copernicus_zarr(tmp_path / "cmems.zarr")
    elif layout == "copernicus-netcdf":
        path = lay.write_copernicus_netcdf(tmp_path / "cmems.nc")
    else:
        path = lay.write_hycom_netcdf(tmp_path / "hycom.nc")
    product = open_current_product(path, origin_lonlat_deg=lay.ORIGIN)
    assert product.time_origin.startswith("2024-03-01T00:00:00")
    assert product.projection is not None and product.layout == "cf" and not product.members
    names = "water_u/water_v" if layout == "hycom" else "uo/vo"
    assert names in product.description and "level 0" in product.description
    _check_against_truth(product)
    grid = land_obstacles(product.field)
    assert grid is not None
    x0, x1, y0, y1 = lay.ISLAND_M
    assert grid.is_occupied_xy(np.array([0.5 * (x0 + x1)]), np.array([0.5 * (y0 + y1)]))[0]
    assert not grid.is_occupied_xy(np.array([5000.0]), np.array([-2000.0]))[0]


def test_depth_in_metres_picks_the_nearest_level(tmp_path):
    path = lay.write_copernicus_netcdf(tmp_path / "cmems.nc")
    product = open_current_product(path, origin_lonlat_deg=lay.ORIGIN, depth_m=9.0)
    assert "level 2 of 'depth' (10.5357 m)" in product.description
    _check_against_truth(product, depth_m=float(lay.DEPTHS_M[2]), t_s=(0.0,))
    with pytest.raises(DataError, match=r"depth 900 m is below the deepest level of 'depth' \(50 m\)"):
        open_current_product(path, depth_m=900.0)
    with pytest.raises(DataError, match="not both"):
        open_current_product(path, depth_m=5.0, depth_index=1)
    hycom = open_current_product(lay.write_hycom_netcdf(tmp_path / "h.nc"), depth_m=20.0)
    assert "(20 m)" in hycom.description


def test_time_window_reads_the_slices_covering_it(tmp_path):
    path = lay.write_copernicus_netcdf(tmp_path / "cmems.nc")
    product = open_current_product(
        path, origin_lonlat_deg=lay.ORIGIN, time_window=("2024-03-01T06:30:00", "2024-03-01T12:00:00Z")
    )
    # 06:00 .. 12:00: seven hourly slices; time 0 is the first slice read.
    assert product.time_origin.startswith("2024-03-01T06:00:00")
    assert product.field.time_s.tolist() == [3600.0 * k for k in range(7)]
    assert "7 of 31 slices" in product.description
    got = product.field.velocity_xy(np.array([3000.0]), np.array([-2000.0]), np.array([3600.0]))[0]
    assert got[0] == pytest.approx(lay.truth(3000.0, -2000.0, 7 * 3600.0)[0], abs=TOL)
    with pytest.raises(
        DataError, match=r"outside the product \(2024-03-01T00:00:00 \.\. 2024-03-02T06:00:00\)"
    ):
        open_current_product(path, time_window=("2024-04-01T00:00:00", "2024-04-02T00:00:00"))
    with pytest.raises(DataError, match="starts after it ends"):
        open_current_product(path, time_window=("2024-03-01T12:00:00", "2024-03-01T06:00:00"))


def test_roms_on_its_rotated_curvilinear_grid(tmp_path):
    path = lay.write_roms(tmp_path / "roms_his.nc")
    product = open_current_product(path, origin_lonlat_deg=lay.ORIGIN)
    assert product.layout == "roms" and "level 3 of 's_rho' (the surface)" in product.description
    assert "ROMS curvilinear grid interpolated to 400 m" in product.description
    # The grid is turned 30 degrees: only a rotation back to east/north recovers the truth.
    f = product.field
    rng = np.random.default_rng(2)
    x, y = rng.uniform(-4000.0, 4000.0, 200), rng.uniform(-3000.0, 3000.0, 200)
    for t in (0.0, 7200.0):
        gu, gv = f.velocity_xy(x, y, np.full(x.size, t))
        tu, tv = lay.truth(x, y, t)
        sea = np.isfinite(gu) & np.isfinite(tu)
        # The island (6 % of the box) grows by the staggering and the two interpolations near its coast.
        assert sea.mean() > 0.7
        # Three linear steps at 400 m (staggered averaging, the triangles, the field's bilinear cells), each
        # h^2/8 |u''| = 1.8e-3 m/s with |u''| <= 9e-8 (see TOL).
        assert np.max(np.abs(gu[sea] - tu[sea])) < 5.4e-3
        assert np.max(np.abs(gv[sea] - tv[sea])) < 5.4e-3
    assert land_obstacles(f) is not None
    with pytest.raises(DataError, match="ROMS s-coordinate levels have no fixed depth"):
        open_current_product(path, depth_m=10.0)


def test_fvcom_is_refused_naming_what_is_unsupported(tmp_path):
    path = lay.write_fvcom(tmp_path / "fvcom.nc")
    with pytest.raises(DataError, match=r"fvcom\.nc: an FVCOM subset .* unstructured mesh.* not supported"):
        open_current_product(path)


def test_ensemble_members_and_their_mean(tmp_path):
    path = lay.write_copernicus_netcdf(tmp_path / "ens.nc", members=5)
    product = open_current_product(path, origin_lonlat_deg=lay.ORIGIN)
    assert len(product.members) == 5 and "ensemble of 5 members" in product.description
    x, y = np.array([3000.0]), np.array([-2000.0])
    speeds = [m.velocity_xy(x, y, 0.0)[0][0] for m in product.members]
    truth = lay.truth(3000.0, -2000.0, 0.0)[0]
    np.testing.assert_allclose(speeds, truth * np.array([0.8, 0.9, 1.0, 1.1, 1.2]), atol=TOL)
    assert product.field.velocity_xy(x, y, 0.0)[0][0] == pytest.approx(truth, abs=TOL)


def test_a_directory_that_is_not_a_zarr_store(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(DataError, match="a directory but not a Zarr store"):
        open_current_product(tmp_path / "empty")
