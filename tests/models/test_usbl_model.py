"""USBL direction and calibrated-range models: Jacobians against central differences, conventions, wrap."""

import numpy as np
import pytest

from oceanloc.models.usbl import (
    apparent_beacon_enu_m,
    direction_residual_rad,
    heading_from_yaw,
    rotation_zyx,
    rotation_zyx_derivatives,
    usbl_direction_jacobian,
    usbl_direction_rad,
    usbl_range_jacobian,
    usbl_range_m,
)
from oceanloc.units import DEG


def _case(seed: int, batch: int = 16):
    rng = np.random.default_rng(seed)
    beacon = rng.normal(0.0, 30.0, (batch, 3))
    beacon[:, 2] = -rng.uniform(5.0, 80.0, batch)
    antenna = rng.normal(0.0, 10.0, (batch, 3))
    antenna[:, 2] = rng.normal(0.0, 0.3, batch)
    attitude = rng.normal(0.0, 0.1, (batch, 3))
    attitude[:, 2] = rng.uniform(-np.pi, np.pi, batch)
    lever = rng.normal(0.0, 1.0, (batch, 3))
    mis = rng.normal(0.0, 0.05, (batch, 3))
    return [beacon, antenna, attitude, lever, mis]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_direction_jacobians_match_central_differences(seed):
    args = _case(seed)
    jac = usbl_direction_jacobian(*args)
    eps = 1e-6
    for i, name in enumerate(["beacon", "antenna", "attitude", "lever_arm", "misalignment"]):
        fd = np.zeros((args[0].shape[0], 2, 3))
        for k in range(3):
            up = [a.copy() for a in args]
            dn = [a.copy() for a in args]
            up[i][:, k] += eps
            dn[i][:, k] -= eps
            fd[:, :, k] = direction_residual_rad(usbl_direction_rad(*up), usbl_direction_rad(*dn)) / (2 * eps)
        np.testing.assert_allclose(getattr(jac, name), fd, atol=1e-8, err_msg=name)
    np.testing.assert_allclose(jac.angles, usbl_direction_rad(*args))


def test_direction_jacobian_without_pose_and_with_a_given_rotation_is_the_same():
    from oceanloc.models.usbl import vessel_rotation

    args = _case(5)
    full = usbl_direction_jacobian(*args)
    fast = usbl_direction_jacobian(*args, pose=False, rotation=vessel_rotation(args[2]))
    for name in ("angles", "beacon", "misalignment", "lever_arm"):
        np.testing.assert_allclose(getattr(fast, name), getattr(full, name), rtol=1e-12, atol=1e-15)
    assert fast.antenna.size == 0 and fast.attitude.size == 0


@pytest.mark.parametrize("seed", [3, 4])
def test_range_jacobians_match_central_differences(seed):
    beacon, antenna, attitude, lever, _ = _case(seed)
    cal = (1.004, 3e-4, 0.12)
    jac = usbl_range_jacobian(beacon, antenna, attitude, lever, *cal)
    eps = 1e-6
    args = [beacon, antenna, attitude, lever]
    for i, name in enumerate(["beacon", "antenna", "attitude", "lever_arm"]):
        fd = np.zeros((beacon.shape[0], 3))
        for k in range(3):
            up = [a.copy() for a in args]
            dn = [a.copy() for a in args]
            up[i][:, k] += eps
            dn[i][:, k] -= eps
            fd[:, k] = (usbl_range_m(*up, *cal) - usbl_range_m(*dn, *cal)) / (2 * eps)
        np.testing.assert_allclose(getattr(jac, name), fd, atol=2e-8, err_msg=name)
    for j, name in enumerate(["scale", "delay", "bias"]):
        step = [1e-6, 1e-8, 1e-6][j]
        up, dn = list(cal), list(cal)
        up[j] += step
        dn[j] -= step
        fd = (usbl_range_m(*args, *up) - usbl_range_m(*args, *dn)) / (2 * step)
        np.testing.assert_allclose(getattr(jac, name), fd, rtol=1e-6, err_msg=name)


def test_rotation_derivatives_match_central_differences():
    angles = np.array([0.3, -0.2, 2.5])
    d = rotation_zyx_derivatives(*angles)
    for i in range(3):
        e = np.zeros(3)
        e[i] = 1e-7
        fd = (rotation_zyx(*(angles + e)) - rotation_zyx(*(angles - e))) / 2e-7
        np.testing.assert_allclose(d[i], fd, atol=1e-8)


def test_conventions_of_a_level_head_aligned_with_north():
    # Head on the bow, vessel level and heading north: the azimuth is the bearing clockwise from north
    # and a beacon below has a negative elevation (SeaTrac's USBL_AZIMUTH and USBL_ELEVATION).
    zero = np.zeros(3)
    az, el = usbl_direction_rad([10.0, 10.0, -10.0 * np.sqrt(2)], zero, zero, zero, zero)
    assert az == pytest.approx(45 * DEG)
    assert el == pytest.approx(-45 * DEG)
    # heading east: the beacon to the east is dead ahead
    az, _ = usbl_direction_rad([10.0, 0.0, -5.0], zero, [0.0, 0.0, 90 * DEG], zero, zero)
    assert az == pytest.approx(0.0, abs=1e-12)
    # a head yawed 2 degrees to starboard sees a beacon on the bow 2 degrees to port
    az, _ = usbl_direction_rad([10.0, 0.0, -5.0], zero, [0.0, 0.0, 90 * DEG], zero, [0.0, 0.0, 2 * DEG])
    assert az == pytest.approx(-2 * DEG)
    # rolled starboard down, the head's face points to port: a beacon straight below appears to
    # starboard, 1 degree off the head's vertical
    az, el = usbl_direction_rad([0.0, 0.0, -20.0], zero, zero, zero, [1 * DEG, 0.0, 0.0])
    assert az == pytest.approx(90 * DEG)
    assert el == pytest.approx(-89 * DEG)


def test_the_seatrac_simulator_convention_is_the_model_with_no_misalignment():
    d = np.array([7.0, -3.0, -25.0])
    expected_az = np.arctan2(d[0], d[1])
    expected_el = np.arctan2(d[2], np.hypot(d[0], d[1]))
    zero = np.zeros(3)
    np.testing.assert_allclose(usbl_direction_rad(d, zero, zero, zero, zero), [expected_az, expected_el])


def test_azimuth_residual_is_wrapped_on_the_circle():
    res = direction_residual_rad([359.9 * DEG, -30 * DEG], [-0.2 * DEG, -30.5 * DEG])
    np.testing.assert_allclose(res, [0.1 * DEG, 0.5 * DEG], atol=1e-12)


def test_apparent_position_inverts_the_model():
    beacon, antenna, attitude, lever, mis = _case(9)
    cal = (0.998, -2e-4, 0.05)
    r = usbl_range_m(beacon, antenna, attitude, lever, *cal)
    d = usbl_direction_rad(beacon, antenna, attitude, lever, mis)
    np.testing.assert_allclose(
        apparent_beacon_enu_m(r, d, antenna, attitude, lever, mis, *cal), beacon, atol=1e-9
    )


def test_heading_from_yaw():
    np.testing.assert_allclose(heading_from_yaw([0.0, 0.5 * np.pi, np.pi]), [0.5 * np.pi, 0.0, -0.5 * np.pi])
