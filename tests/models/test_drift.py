import numpy as np
import pytest
from scipy.linalg import expm

from oceanloc.errors import ConfigError
from oceanloc.models.currents import (
    GridCurrent,
    LinearCurrent,
    UniformCurrent,
    thesis_vortex_grid,
    vortex_velocity_xy,
)
from oceanloc.models.drift import (
    STOP_BLOCKED,
    STOP_COMPLETED,
    STOP_NO_CURRENT,
    euler_step,
    integrate,
    rk4_step,
)

A = np.array([[-0.2, -1.0], [1.0, -0.1]]) * 1e-3  # a damped rotation, 1/s
B = np.array([0.05, -0.02])  # m/s


def _exact(p0, t):
    """x(t) = e^{At} x0 + A^{-1} (e^{At} - I) b."""
    e = expm(A * t)
    return e @ p0 + np.linalg.solve(A, (e - np.eye(2)) @ B)


def _final_error(method, dt, t_end=6000.0):
    field = LinearCurrent(matrix_per_s=tuple(map(tuple, A)), offset_mps=tuple(B))
    p0 = np.array([[1000.0, -500.0]])
    track = integrate(field, p0, dt_s=dt, n_steps=round(t_end / dt), method=method)
    return np.linalg.norm(track.final_m[0] - _exact(p0[0], t_end))


def test_uniform_current_is_exact_for_both_integrators():
    field = UniformCurrent(velocity_mps=(0.3, -0.1))
    for method in ("euler", "rk4"):
        tr = integrate(field, [[0.0, 0.0], [10.0, 5.0]], dt_s=60.0, n_steps=10, method=method)
        np.testing.assert_allclose(tr.final_m, [[180.0, -60.0], [190.0, -55.0]], atol=1e-9)


def test_rk4_converges_at_fourth_order_on_an_exact_linear_solution():
    e1, e2 = _final_error("rk4", 200.0), _final_error("rk4", 100.0)
    # Global error C dt^4: halving dt divides it by 2^4 = 16 (higher-order terms move the ratio by ~1%).
    assert 14.0 < e1 / e2 < 18.0
    # Local error ~ (|A| dt)^5 / 5! |x| = 0.1^5 / 120 * 1100 m = 9e-5 m; 60 steps accumulate ~5.5e-3 m.
    assert e2 < 5.5e-3


def test_euler_converges_at_first_order_on_an_exact_linear_solution():
    e1, e2 = _final_error("euler", 20.0), _final_error("euler", 10.0)
    assert 1.9 < e1 / e2 < 2.1
    assert e2 < 20.0


def test_rk4_keeps_a_rotation_on_its_circle():
    field = LinearCurrent(matrix_per_s=((0.0, -1e-3), (1e-3, 0.0)))
    tr = integrate(field, [[1000.0, 0.0]], dt_s=60.0, n_steps=105, method="rk4")  # one revolution: 6283 s
    radius = np.linalg.norm(tr.positions_m[0], axis=1)
    # RK4's amplification on a rotation: |R(i th)|^2 = 1 - th^6 / 72 + th^8 / 576 with th = w dt = 0.06.
    th = 0.06
    gain = np.sqrt(1 - th**6 / 72 + th**8 / 576)
    np.testing.assert_allclose(radius, 1000.0 * gain ** np.arange(106), rtol=1e-12)


def test_steps_work_on_floats_and_arrays_alike():
    field = thesis_vortex_grid("linear")
    for step in (euler_step, rk4_step):
        xs, ys = step(field, 1234.0, -987.0, 0.0, 60.0)
        xa, ya = step(field, np.array([1234.0]), np.array([-987.0]), 0.0, 60.0)
        assert (xs, ys) == pytest.approx((xa[0], ya[0]), abs=1e-12)


def test_euler_on_the_cell_field_is_the_thesis_dead_reckoning():
    field = thesis_vortex_grid("cell")
    x, y = -4000.0, 4000.0
    expected = [(x, y)]
    nodes = np.linspace(-5000.0, 5000.0, 21)
    for _ in range(50):
        col = int(np.searchsorted(nodes, x, side="right") - 1)
        row = int(np.searchsorted(nodes, y, side="right") - 1)
        u, v = vortex_velocity_xy(nodes[col], nodes[row])
        x, y = x + 60.0 * u, y + 60.0 * v
        expected.append((x, y))
    tr = integrate(field, [[-4000.0, 4000.0]], dt_s=60.0, n_steps=50, method="euler")
    np.testing.assert_allclose(tr.positions_m[0], expected, atol=1e-9)


def test_particles_stop_where_the_current_is_undefined_or_blocked():
    x = np.array([0.0, 100.0, 200.0])
    y = np.array([0.0, 100.0])
    field = GridCurrent(x_m=x, y_m=y, u_mps=np.full((2, 3), 1.0), v_mps=np.zeros((2, 3)))
    tr = integrate(
        field,
        [[50.0, 50.0], [10.0, 50.0]],
        dt_s=30.0,
        n_steps=10,
        method="euler",
        is_free=lambda px, py: px < 100.0,
    )
    assert tr.stop_reason.tolist() == [STOP_BLOCKED, STOP_BLOCKED]
    assert tr.final_m[:, 0].tolist() == [80.0, 70.0]
    assert not tr.alive[0, -1]
    tr = integrate(field, [[50.0, 50.0]], dt_s=30.0, n_steps=10, method="euler")
    assert tr.stop_reason[0] == STOP_NO_CURRENT
    assert tr.final_m[0, 0] == 200.0  # last position where the current was defined
    assert integrate(field, [[0.0, 0.0]], dt_s=1.0, n_steps=3).stop_reason[0] == STOP_COMPLETED


def test_integrate_rejects_bad_steps():
    with pytest.raises(ConfigError):
        integrate(UniformCurrent(), [[0.0, 0.0]], dt_s=0.0, n_steps=3)
    with pytest.raises(ConfigError, match="integrator"):
        integrate(UniformCurrent(), [[0.0, 0.0]], dt_s=1.0, n_steps=3, method="midpoint")
