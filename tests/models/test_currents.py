import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oceanloc.errors import ConfigError, DataError
from oceanloc.models.currents import (
    DoubleGyreCurrent,
    GridCurrent,
    LinearCurrent,
    UniformCurrent,
    VortexCurrent,
    thesis_vortex_grid,
    vortex_velocity_xy,
)


def test_vortex_formula_at_hand_computed_points():
    # Unscaled (0.3, -0.3): u = -0.3 - 2(-0.3)(0.09) - 0.3 = -0.546, v = -0.3 + 0.3 = 0.
    u, v = vortex_velocity_xy(3000.0, -3000.0)
    assert u == pytest.approx(-0.546)
    assert v == pytest.approx(0.0, abs=1e-15)
    u, v = vortex_velocity_xy(-4000.0, 4000.0)  # the thesis' start: -(-0.4) - 2(0.4)(0.16) + 0.4
    assert (u, v) == pytest.approx((0.672, 0.0))


def _matlab_cell_finder(x, y):
    """The thesis' CellFinder, written as its loops are: lower-left node, index 21 when not found."""
    nodes = np.linspace(-5000.0, 5000.0, 21)
    col = row = 20
    for k in range(20):
        if nodes[k] <= x < nodes[k + 1]:
            col = k
            break
    for k in range(20):
        if nodes[k] <= y < nodes[k + 1]:
            row = k
            break
    return vortex_velocity_xy(nodes[col], nodes[row])


def test_cell_lookup_matches_thesis_cellfinder():
    field = thesis_vortex_grid("cell")
    rng = np.random.default_rng(0)
    pts = rng.uniform(-5000.0, 5000.0, size=(200, 2))
    pts = np.vstack([pts, [[5000.0, 5000.0], [-5000.0, 4999.9], [0.0, 0.0], [2500.0, -2500.0]]])
    got = field.velocity(pts)
    expected = np.array([_matlab_cell_finder(x, y) for x, y in pts])
    np.testing.assert_allclose(got, expected, atol=1e-15)


def test_cell_scalar_path_equals_array_path():
    field = thesis_vortex_grid("cell")
    rng = np.random.default_rng(1)
    for x, y in rng.uniform(-5200.0, 5200.0, size=(100, 2)):
        us, vs = field.velocity_xy(float(x), float(y))
        ua, va = field.velocity_xy(np.array([x]), np.array([y]))
        np.testing.assert_equal([us, vs], [ua[0], va[0]])


def test_grid_is_nan_outside_and_never_zero():
    for mode in ("cell", "linear"):
        field = thesis_vortex_grid(mode)
        u, v = field.velocity_xy(np.array([5000.1, -6000.0, 0.0]), np.array([0.0, 0.0, -5000.5]))
        assert np.all(np.isnan(u)) and np.all(np.isnan(v))
        assert math.isnan(field.velocity_xy(7000.0, 0.0)[0])


def test_bilinear_is_exact_for_a_linear_field_and_hits_nodes():
    x = np.linspace(0.0, 1000.0, 11)
    y = np.linspace(-500.0, 500.0, 6)
    gx, gy = np.meshgrid(x, y)
    field = GridCurrent(
        x_m=x, y_m=y, u_mps=0.001 * gx + 0.002 * gy, v_mps=-0.003 * gx + 0.1, interpolation="linear"
    )
    rng = np.random.default_rng(2)
    p = np.column_stack([rng.uniform(0, 1000, 50), rng.uniform(-500, 500, 50)])
    u, v = field.velocity_xy(p[:, 0], p[:, 1])
    np.testing.assert_allclose(u, 0.001 * p[:, 0] + 0.002 * p[:, 1], atol=1e-12)
    np.testing.assert_allclose(v, -0.003 * p[:, 0] + 0.1, atol=1e-12)
    u, _ = field.velocity_xy(gx.ravel(), gy.ravel())
    np.testing.assert_allclose(u, (0.001 * gx + 0.002 * gy).ravel(), atol=1e-15)


def test_land_nan_contaminates_linear_interpolation_but_not_far_cells():
    x = np.arange(5.0) * 100.0
    y = np.arange(4.0) * 100.0
    u = np.ones((4, 5))
    u[1, 2] = np.nan
    field = GridCurrent(x_m=x, y_m=y, u_mps=u, v_mps=np.zeros((4, 5)))
    assert np.isnan(field.velocity_xy(np.array([150.0]), np.array([50.0]))[0][0])  # a corner is land
    assert field.velocity_xy(np.array([350.0]), np.array([250.0]))[0][0] == pytest.approx(1.0)
    assert field.land_mask().sum() == 1


def test_time_interpolation_is_linear_and_nan_outside_the_span():
    x = np.array([0.0, 1.0])
    y = np.array([0.0, 1.0])
    u = np.stack([np.zeros((2, 2)), np.ones((2, 2)) * 2.0])
    field = GridCurrent(x_m=x, y_m=y, u_mps=u, v_mps=np.zeros_like(u), time_s=np.array([0.0, 100.0]))
    assert field.velocity_xy(np.array([0.5]), np.array([0.5]), 25.0)[0][0] == pytest.approx(0.5)
    assert np.isnan(field.velocity_xy(np.array([0.5]), np.array([0.5]), 101.0)[0][0])
    per_point = field.velocity_xy(np.array([0.5, 0.5]), np.array([0.5, 0.5]), np.array([0.0, 50.0]))[0]
    np.testing.assert_allclose(per_point, [0.0, 1.0])


def test_grid_validation_errors():
    with pytest.raises(DataError, match="evenly spaced"):
        GridCurrent(
            x_m=np.array([0.0, 1.0, 3.0]),
            y_m=np.array([0.0, 1.0]),
            u_mps=np.zeros((2, 3)),
            v_mps=np.zeros((2, 3)),
        )
    with pytest.raises(DataError, match="shape"):
        GridCurrent(
            x_m=np.array([0.0, 1.0]), y_m=np.array([0.0, 1.0]), u_mps=np.zeros((3, 2)), v_mps=np.zeros((3, 2))
        )
    with pytest.raises(ConfigError, match="interpolation"):
        GridCurrent(
            x_m=np.array([0.0, 1.0]),
            y_m=np.array([0.0, 1.0]),
            u_mps=np.zeros((2, 2)),
            v_mps=np.zeros((2, 2)),
            interpolation="cubic",
        )


def test_double_gyre_is_divergence_free_and_matches_its_stream_function():
    dg = DoubleGyreCurrent(length_m=1000.0, amplitude_mps=0.3, epsilon=0.25, omega_rad_s=0.001)
    rng = np.random.default_rng(3)
    x = rng.uniform(10, 1990, 200)
    y = rng.uniform(10, 990, 200)
    t = 700.0
    h = 1e-3
    du = (dg.velocity_xy(x + h, y, t)[0] - dg.velocity_xy(x - h, y, t)[0]) / (2 * h)
    dv = (dg.velocity_xy(x, y + h, t)[1] - dg.velocity_xy(x, y - h, t)[1]) / (2 * h)
    # Central differences of a smooth field: truncation ~h^2 * |f'''| ~ 1e-12; rounding ~eps/h ~ 1e-13.
    np.testing.assert_allclose(du + dv, 0.0, atol=1e-9)

    def psi(px, py):
        a = 0.25 * np.sin(0.001 * t)
        s = px / 1000.0
        f = a * s * s + (1 - 2 * a) * s
        return 0.3 * 1000.0 / np.pi * np.sin(np.pi * f) * np.sin(np.pi * py / 1000.0)

    u_fd = -(psi(x, y + h) - psi(x, y - h)) / (2 * h)
    v_fd = (psi(x + h, y) - psi(x - h, y)) / (2 * h)
    u, v = dg.velocity_xy(x, y, t)
    np.testing.assert_allclose(u, u_fd, atol=1e-8)
    np.testing.assert_allclose(v, v_fd, atol=1e-8)
    assert np.isnan(dg.velocity_xy(-1.0, 5.0)[0])


@settings(max_examples=40, deadline=None)
@given(st.floats(-4999, 4999), st.floats(-4999, 4999))
def test_analytic_and_bilinear_vortex_agree_to_interpolation_error(x, y):
    # Bilinear interpolation error <= h^2/8 * max|second derivative|; u has d2u/dx2 = -4y/s^3 so with
    # h = 500 m and |y| <= 5 km the bound is 500^2/8 * 4 * 0.5 / 1e4^2 = 6.25e-4 m/s.
    exact = VortexCurrent().velocity_xy(x, y)
    interp = thesis_vortex_grid("linear").velocity_xy(np.array([x]), np.array([y]))
    assert abs(interp[0][0] - exact[0]) <= 6.3e-4
    assert abs(interp[1][0] - exact[1]) <= 1e-12


def test_uniform_and_linear_fields():
    assert UniformCurrent(velocity_mps=(0.1, -0.2)).velocity([[0, 0], [5, 5]]).tolist() == [
        [0.1, -0.2],
        [0.1, -0.2],
    ]
    lin = LinearCurrent(matrix_per_s=((0.0, -1.0), (1.0, 0.0)), offset_mps=(0.5, 0.0))
    np.testing.assert_allclose(lin.velocity([[1.0, 2.0]]), [[-1.5, 1.0]])
