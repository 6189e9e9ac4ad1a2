"""Sound speed (thesis eq. II.1 against TEOS-10), travel time <-> range, straight-ray corrections."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oceanloc.errors import ConfigError, DataError
from oceanloc.models.acoustics import (
    gradient_path_jacobian,
    gradient_path_m2,
    harmonic_mean_sound_speed_mps,
    range_from_travel_time_m,
    refraction_shortening_jacobian,
    refraction_shortening_m,
    sound_speed_medwin_mps,
    sound_speed_teos10_mps,
    trace_layered_ray,
    travel_time_from_range_s,
)


def test_eq_ii1_reference_value():
    # Hand evaluation of (II.1) at T = 10 degC, S = 35, z = 100 m:
    # 1449.2 + 46 - 5.5 + 0.29 + 0 + 1.6 = 1491.59 m/s.
    assert sound_speed_medwin_mps(10.0, 35.0, 100.0) == pytest.approx(1491.59, abs=1e-9)


def test_eq_ii1_increases_with_temperature_salinity_depth():
    base = sound_speed_medwin_mps(12.0, 34.0, 30.0)
    assert sound_speed_medwin_mps(13.0, 34.0, 30.0) > base
    assert sound_speed_medwin_mps(12.0, 35.0, 30.0) > base
    assert sound_speed_medwin_mps(12.0, 34.0, 40.0) > base


def test_eq_ii1_agrees_with_teos10_in_the_mixed_layer():
    # Medwin's fit is quoted to about 0.2 m/s against the full equations over 0-35 degC, 0-1000 m.
    t, s, z = np.meshgrid(np.linspace(2, 30, 8), np.linspace(32, 37, 4), np.linspace(0, 200, 5))
    diff = sound_speed_medwin_mps(t, s, z) - sound_speed_teos10_mps(t, s, z, 36.8, -122.0)
    assert np.max(np.abs(diff)) < 1.0
    assert abs(np.mean(diff)) < 0.3


def test_travel_time_round_trip_batched():
    r = np.array([[10.0, 1500.0], [52.7, 0.0]])
    c = np.array([1499.3, 1504.7])
    t = travel_time_from_range_s(r, c)
    np.testing.assert_allclose(range_from_travel_time_m(t, c), r, rtol=1e-15)
    np.testing.assert_allclose(travel_time_from_range_s(r, c, two_way=True), 2 * t)
    np.testing.assert_allclose(range_from_travel_time_m(2 * t, c, two_way=True), r, rtol=1e-15)
    assert range_from_travel_time_m(0.1, 1500.0) == pytest.approx(150.0)


@pytest.mark.parametrize("c", [0.0, -1500.0, np.nan])
def test_bad_sound_speed(c):
    with pytest.raises(ConfigError, match="sound speed"):
        range_from_travel_time_m(1.0, c)


def test_harmonic_mean_of_linear_profile():
    # c(z) = c0 + g z: integral dz / c = ln(c(z2)/c(z1)) / g exactly; trapezoids on a fine grid converge.
    z = np.linspace(0.0, 100.0, 2001)
    c = 1480.0 + 0.2 * z
    exact = 100.0 * 0.2 / np.log(1500.0 / 1480.0)
    assert harmonic_mean_sound_speed_mps(z, c) == pytest.approx(exact, rel=1e-9)
    # A sub-layer and a layer extending past the profile (held constant below).
    assert harmonic_mean_sound_speed_mps(z, c, 0.0, 50.0) == pytest.approx(
        50.0 * 0.2 / np.log(1490.0 / 1480.0), rel=1e-9
    )
    assert harmonic_mean_sound_speed_mps([0.0, 10.0], [1500.0, 1500.0], 0.0, 30.0) == pytest.approx(1500.0)


def test_bad_profiles():
    with pytest.raises(DataError, match="increasing"):
        harmonic_mean_sound_speed_mps([0.0, 5.0, 5.0], [1500.0, 1500.0, 1501.0])
    with pytest.raises(ConfigError, match="deeper"):
        harmonic_mean_sound_speed_mps([0.0, 5.0], [1500.0, 1500.0], 5.0, 1.0)


@pytest.mark.parametrize(
    "profile",
    [
        lambda z: 1515.0 - 20.0 * z / 53.0,  # linear
        lambda z: 1500.0 + 15.0 / (1.0 + np.exp((z - 20.0) / 4.0)),  # thermocline at 20 m
        lambda z: np.where(z < 10.0, 1512.0, 1512.0 - 0.4 * (z - 10.0)),  # mixed layer over a gradient
    ],
)
def test_refraction_shortening_matches_a_layered_ray_trace(profile):
    # The straight ray at the harmonic-mean speed is exact to first order (Fermat); the second-order
    # shortening of the equivalent path is kappa L tan^2 with kappa = Var_z(c) / (2 c^2) within 10 %,
    # whatever the profile's shape, up to tan(incidence) = 5.
    depth = 53.0
    edges = np.linspace(0.0, depth, 2001)
    mid = 0.5 * (edges[1:] + edges[:-1])
    c = profile(mid)
    c_h = depth / np.sum(np.diff(edges) / c)
    tan = np.array([0.5, 1.0, 2.0, 3.0, 4.0, 5.0])
    t_s, reach_m = trace_layered_ray(c, np.diff(edges), tan)
    np.testing.assert_allclose(reach_m, tan * depth, rtol=1e-9)
    target = np.zeros((tan.size, 3))
    sensor = np.stack([tan * depth, np.zeros_like(tan), np.full_like(tan, depth)], axis=1)
    shortening = c_h * t_s - np.linalg.norm(sensor, axis=1)
    kappa = np.var(c) / (2.0 * np.mean(c) ** 2)
    np.testing.assert_allclose(-shortening, kappa * refraction_shortening_m(target, sensor), rtol=0.1)


@settings(max_examples=50, deadline=None)
@given(st.floats(-300, 300), st.floats(-300, 300), st.floats(20, 80), st.floats(-5, 5), st.floats(-5, 5))
def test_refraction_and_gradient_jacobians_match_central_differences(e, n, up, te, tn):
    target = np.array([te, tn, 0.0])
    sensor = np.array([e, n, up])
    h = 1e-5
    for fn, jac in (
        (refraction_shortening_m, refraction_shortening_jacobian),
        (gradient_path_m2, gradient_path_jacobian),
    ):
        fd = np.stack(
            [(fn(target + h * d, sensor) - fn(target - h * d, sensor)) / (2 * h) for d in np.eye(3)], axis=-1
        )
        np.testing.assert_allclose(jac(target, sensor), fd, rtol=1e-5, atol=1e-6)


def test_gradient_factor_is_half_the_offset_times_the_slant_range():
    sensor = np.array([30.0, 40.0, 120.0])  # L = 130
    np.testing.assert_allclose(gradient_path_m2(np.zeros(3), sensor), [0.5 * 130 * 30, 0.5 * 130 * 40])


def test_ray_trace_rejects_mismatched_layers():
    with pytest.raises(ConfigError, match="one positive thickness"):
        trace_layered_ray([1500.0, 1501.0], [10.0], [1.0])
