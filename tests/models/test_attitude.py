"""Attitude, lever arm and track interpolation (:mod:`oceanloc.models.attitude`)."""

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.models.attitude import (
    interpolate_track,
    rotation_enu_from_body,
    transducer_enu_m,
    transducer_jacobians,
)


def test_rotation_follows_the_forward_starboard_down_convention():
    # heading 90 deg: the bow points east, starboard south; down is down
    r = rotation_enu_from_body(0.0, 0.0, 90.0)
    np.testing.assert_allclose(r @ [1, 0, 0], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(r @ [0, 1, 0], [0, -1, 0], atol=1e-12)
    np.testing.assert_allclose(r @ [0, 0, 1], [0, 0, -1], atol=1e-12)
    # roll 10 deg starboard down, heading north: the starboard axis dips below the horizon
    np.testing.assert_allclose(
        rotation_enu_from_body(10.0, 0.0, 0.0) @ [0, 1, 0],
        [np.cos(np.radians(10)), 0, -np.sin(np.radians(10))],
    )
    # pitch 5 deg bow up, heading north: the bow rises
    np.testing.assert_allclose(
        rotation_enu_from_body(0.0, 5.0, 0.0) @ [1, 0, 0], [0, np.cos(np.radians(5)), np.sin(np.radians(5))]
    )
    rs = rotation_enu_from_body([1.0, -3.0], [2.0, 4.0], [350.0, 10.0])
    np.testing.assert_allclose(
        rs @ np.swapaxes(rs, -1, -2), np.broadcast_to(np.eye(3), (2, 3, 3)), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(rs), 1.0)


def test_transducer_jacobians_match_central_differences():
    rng = np.random.default_rng(0)
    att = rng.uniform(-15.0, 15.0, (20, 3))
    att[:, 2] = rng.uniform(0.0, 360.0, 20)
    lever = np.array([1.2, -0.4, 2.3])
    antenna = rng.normal(size=(20, 3))
    d_lever, d_att = transducer_jacobians(att[:, 0], att[:, 1], att[:, 2], lever)

    def pos(a, l_):
        return transducer_enu_m(antenna, rotation_enu_from_body(a[:, 0], a[:, 1], a[:, 2]), l_)

    for k in range(3):
        step = np.zeros(3)
        step[k] = 1e-6
        fd = (pos(att + step, lever) - pos(att - step, lever)) / 2e-6  # per degree
        np.testing.assert_allclose(d_att[:, :, k], fd, atol=1e-8)
        fd_l = (pos(att, lever + step) - pos(att, lever - step)) / 2e-6
        np.testing.assert_allclose(d_lever[:, :, k], fd_l, atol=1e-8)


def test_track_interpolation_is_linear_and_takes_heading_the_short_way():
    t = np.array([0.0, 10.0])
    pos = np.array([[0.0, 0.0, 1.0], [10.0, -20.0, 3.0]])
    cov = np.stack([np.eye(3) * 1e-4, np.eye(3) * 3e-4])
    att = np.array([[1.0, -2.0, 359.0], [3.0, 2.0, 3.0]])
    p, c, a = interpolate_track(t, np.array([2.5, 5.0]), pos, cov, att)
    np.testing.assert_allclose(p[1], [5.0, -10.0, 2.0])
    np.testing.assert_allclose(c[0], np.eye(3) * 1.5e-4)
    np.testing.assert_allclose(a[:, 2], [0.0, 1.0], atol=1e-9)  # 359 -> 3 through 0, not through 180
    np.testing.assert_allclose(a[1, :2], [2.0, 0.0])
    with pytest.raises(DataError, match="outside the antenna track"):
        interpolate_track(t, np.array([10.5]), pos, cov, att)
    with pytest.raises(DataError, match="strictly increasing"):
        interpolate_track(np.array([0.0, 0.0]), np.array([0.0]), pos, cov, att)
