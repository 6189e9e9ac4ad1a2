"""Bearing, horizontal range and TDOA models (AquaQuad thesis eqs. II.3, II.4, II.7) and their Jacobians."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oceanloc.models.measurements import (
    bearing_jacobian,
    bearing_rad,
    horizontal_range_jacobian,
    horizontal_range_m,
    sensor_pairs,
    tdoa_jacobian,
    tdoa_s,
    wrap_angle_rad,
)

SENSORS = np.array([[500.0, 0.0], [0.0, 500.0], [-500.0, 0.0], [0.0, -500.0]])


def _numeric_jacobian(fun, x, step, wrap=False):
    cols = []
    for k in range(x.shape[-1]):
        e = np.zeros(x.shape[-1])
        e[k] = step
        diff = fun(x + e) - fun(x - e)
        cols.append((wrap_angle_rad(diff) if wrap else diff) / (2 * step))
    return np.stack(cols, axis=-1)


def test_wrap_angle_range_is_half_open_at_minus_pi():
    a = np.array([np.pi, -np.pi, 3 * np.pi, -3 * np.pi, 0.5, 2 * np.pi + 0.5, -0.5])
    w = wrap_angle_rad(a)
    np.testing.assert_allclose(w, [np.pi, np.pi, np.pi, np.pi, 0.5, 0.5, -0.5], atol=1e-12)
    assert np.all((w > -np.pi) & (w <= np.pi))


def test_bearing_is_four_quadrant():
    sensor = np.zeros((1, 2))
    targets = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    np.testing.assert_allclose(
        bearing_rad(targets, sensor)[:, 0], np.array([1, 3, -3, -1]) * np.pi / 4, atol=1e-15
    )


@pytest.mark.parametrize(
    "position",
    [
        [120.0, -35.0],  # generic
        [0.3, 1e-3],  # 0.3 m from the sensor at the origin of the shifted frame: large curvature
        [-800.0, 1e-9],  # on the branch cut behind sensor 0: bearings near +-pi
    ],
)
def test_jacobians_match_central_differences_on_six_state(position):
    x = np.array([*position, 3.0, -1.0, 0.1, 0.2])
    sensors = SENSORS if position[0] != 0.3 else np.zeros((1, 2))
    pairs = sensor_pairs(len(sensors)) if len(sensors) > 1 else None
    # The step is 1e-6 of the closest range: truncation error ~ (step / r)^2 relative, far below 1e-6.
    step = 1e-6 * max(horizontal_range_m(x, sensors).min(), 1e-3)
    np.testing.assert_allclose(
        bearing_jacobian(x, sensors),
        _numeric_jacobian(lambda s: bearing_rad(s, sensors), x, step, wrap=True),
        rtol=1e-6,
        atol=1e-9 / step,
    )
    np.testing.assert_allclose(
        horizontal_range_jacobian(x, sensors),
        _numeric_jacobian(lambda s: horizontal_range_m(s, sensors), x, step),
        rtol=1e-6,
        atol=1e-8,
    )
    if pairs is not None:
        np.testing.assert_allclose(
            tdoa_jacobian(x, sensors, pairs, 1480.0),
            _numeric_jacobian(lambda s: tdoa_s(s, sensors, pairs, 1480.0), x, step),
            rtol=1e-6,
            atol=1e-12,
        )


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-2000, 2000),
    st.floats(-2000, 2000),
    st.floats(-2000, 2000),
    st.floats(-2000, 2000),
)
def test_bearing_jacobian_property(x, y, sx, sy):
    r = np.hypot(x - sx, y - sy)
    if r < 1e-2:
        return
    sensors = np.array([[sx, sy]])
    target = np.array([x, y])
    step = 1e-5 * r
    num = _numeric_jacobian(lambda s: bearing_rad(s, sensors), target, step, wrap=True)
    np.testing.assert_allclose(bearing_jacobian(target, sensors), num, rtol=1e-5, atol=1e-7 / r)


def test_zero_range_rows_carry_no_information():
    x = np.array([500.0, 0.0, 1.0, 1.0])
    assert np.all(bearing_jacobian(x, SENSORS)[0] == 0.0)
    assert np.all(horizontal_range_jacobian(x, SENSORS)[0] == 0.0)


def test_batch_broadcasting_over_runs_and_sigma_points():
    rng = np.random.default_rng(1)
    states = rng.normal(scale=300.0, size=(5, 13, 6))  # runs x sigma points x state
    sensors = rng.normal(scale=600.0, size=(5, 4, 2))  # a flock per run
    out = bearing_rad(states, sensors[:, None])
    jac = bearing_jacobian(states, sensors[:, None])
    assert out.shape == (5, 13, 4) and jac.shape == (5, 13, 4, 6)
    np.testing.assert_allclose(out[3, 7], bearing_rad(states[3, 7], sensors[3]))
    np.testing.assert_allclose(jac[2, 4], bearing_jacobian(states[2, 4], sensors[2]))


def test_tdoa_sign_and_pairs():
    # Target near sensor 1: the signal reaches 1 before 0, so tau_01 = tau_0 - tau_1 > 0.
    sensors = np.array([[0.0, 0.0], [100.0, 0.0], [50.0, 80.0]])
    target = np.array([90.0, 5.0])
    pairs = sensor_pairs(3)
    np.testing.assert_array_equal(pairs, [[0, 1], [0, 2], [1, 2]])
    np.testing.assert_array_equal(sensor_pairs(3, "reference"), [[0, 1], [0, 2]])
    tau = tdoa_s(target, sensors, pairs, 1500.0)
    r = horizontal_range_m(target, sensors)
    assert tau[0] > 0
    np.testing.assert_allclose(tau, [(r[0] - r[1]) / 1500, (r[0] - r[2]) / 1500, (r[1] - r[2]) / 1500])


@pytest.mark.parametrize("bad", [[[0, 0]], [[0, 3]], [[-1, 1]], [0, 1]])
def test_bad_pairs_are_rejected(bad):
    with pytest.raises(ValueError, match="pairs"):
        tdoa_s(np.zeros(2), SENSORS[:3], bad)
