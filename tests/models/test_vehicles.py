import numpy as np
import pytest

from oceanloc.models.vehicles import rotation_z, unicycle_rollout, unicycle_step
from oceanloc.units import DEG


def test_step_uses_new_heading_eq1():
    poses = unicycle_step([0.0, 0.0, 0.0], 0.0, 90 * DEG, [3.0, 0.0, 0.0], 1.0)
    assert poses.yaw_rad == pytest.approx(np.pi / 2)
    np.testing.assert_allclose(poses.pos_enu_m, [0.0, 3.0, 0.0], atol=1e-12)


def test_step_matches_rotation_matrix_form():
    rng = np.random.default_rng(0)
    pos, yaw, rate = rng.normal(size=(5, 3)), rng.normal(size=5), rng.normal(size=5)
    v = np.array([3.0, 0.5, 0.0])
    poses = unicycle_step(pos, yaw, rate, v, 0.7)
    expected = pos + np.einsum("bij,j->bi", rotation_z(yaw + rate * 0.7), v) * 0.7
    np.testing.assert_allclose(poses.pos_enu_m, expected, atol=1e-12)


def test_rollout_equals_repeated_steps():
    rng = np.random.default_rng(1)
    rates = rng.uniform(-0.5, 0.5, size=(4, 3))
    pos0, yaw0 = rng.normal(size=(4, 3)), rng.normal(size=4)
    roll = unicycle_rollout(pos0, yaw0, rates, 3.0, 1.0)
    pos, yaw = pos0, yaw0
    for i in range(3):
        step = unicycle_step(pos, yaw, rates[:, i], [3.0, 0.0, 0.0], 1.0)
        pos, yaw = step.pos_enu_m, step.yaw_rad
        np.testing.assert_allclose(roll.pos_enu_m[:, i], pos, atol=1e-12)
        np.testing.assert_allclose(roll.yaw_rad[:, i], yaw, atol=1e-12)


def test_rotation_is_orthonormal():
    r = rotation_z(np.linspace(-3, 3, 7))
    np.testing.assert_allclose(r @ np.swapaxes(r, -1, -2), np.broadcast_to(np.eye(3), r.shape), atol=1e-12)
