"""Sound-speed profiles and ray-traced travel times (:mod:`oceanloc.models.sound_profile`)."""

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.models.acoustics import harmonic_mean_sound_speed_mps, sound_speed_teos10_mps, trace_layered_ray
from oceanloc.models.sound_profile import SoundSpeedProfile, bending_table, ray_travel_time_s
from oceanloc.sim.gnssa_array import example_profile


def _clipped_layers(profile, top, bottom):
    b, c = profile.layer_bounds_m, profile.layer_speed_mps
    dz = np.clip(np.minimum(bottom, b[1:]) - np.maximum(top, b[:-1]), 0.0, None)
    return c[dz > 0], dz[dz > 0]


def test_ray_times_match_the_layered_snell_tracer():
    profile = example_profile(3000.0)
    top, bottom = 3.0, 2800.0
    x = np.array([0.0, 500.0, 2800.0, 5600.0])
    t, p, _ = ray_travel_time_s(profile, np.full(4, top), np.full(4, bottom), x)
    c, dz = _clipped_layers(profile, top, bottom)
    t_ref, reach = trace_layered_ray(c, dz, x / (bottom - top))
    np.testing.assert_allclose(reach, x, atol=1e-6)
    np.testing.assert_allclose(t, t_ref, rtol=0.0, atol=1e-10)
    assert p[0] == pytest.approx(0.0, abs=1e-12) and np.all(np.diff(p) > 0)


def test_ray_time_derivatives_are_the_ray_parameter_and_the_vertical_slowness():
    profile = example_profile(2000.0)
    top, bottom, x = np.array([2.0]), np.array([1800.0]), np.array([1500.0])
    _, p, eta = ray_travel_time_s(profile, top, bottom, x)
    h = 1e-3
    dt_dx = (
        ray_travel_time_s(profile, top, bottom, x + h)[0] - ray_travel_time_s(profile, top, bottom, x - h)[0]
    ) / (2 * h)
    dt_dz = (
        ray_travel_time_s(profile, top, bottom + h, x)[0] - ray_travel_time_s(profile, top, bottom - h, x)[0]
    ) / (2 * h)
    np.testing.assert_allclose(dt_dx, p, rtol=1e-6)
    np.testing.assert_allclose(dt_dz, eta, rtol=1e-5)


def test_bending_table_is_within_its_stated_tolerance():
    """3e-8 s one way (0.05 mm) with the default grid, offsets up to two depths, three transducer depths."""
    profile = example_profile(2200.0)
    table = bending_table(profile, 2000.0, (1.0, 6.0), 4000.0)
    rng = np.random.default_rng(0)
    x = rng.uniform(0.0, 4000.0, 500)
    top = rng.uniform(1.0, 6.0, 500)
    exact, _, _ = ray_travel_time_s(profile, top, np.full(500, 2000.0), x)
    straight = np.hypot(x, 2000.0 - top) * profile.harmonic_slowness_spm(top, 2000.0)
    bending = exact - straight
    assert np.max(np.abs(table.correction_s(top, x) - bending)) < 3e-8
    # the bending is real: tens of microseconds (several cm of path) at the far end
    assert np.min(bending) < -2e-5 and np.max(bending) <= 1e-12


def test_harmonic_mean_is_exact_for_the_linear_profile_and_close_to_the_trapezoidal_one():
    z = np.array([0.0, 100.0, 1000.0])
    c = np.array([1520.0, 1500.0, 1490.0])
    profile = SoundSpeedProfile(depth_m=z, speed_mps=c)
    # exact integral of dz / c for c linear: ln(c2/c1) / slope
    exact = 100.0 / (np.log(1500.0 / 1520.0) / -0.2)
    assert profile.harmonic_mean_mps(0.0, 100.0) == pytest.approx(exact, rel=1e-12)
    # the trapezoidal rule of acoustics.harmonic_mean_sound_speed_mps is off by its integration error
    # (0.014 m/s over the 900 m segment)
    assert profile.harmonic_mean_mps(0.0, 1000.0) == pytest.approx(
        harmonic_mean_sound_speed_mps(z, c), abs=0.02
    )
    # beyond the cast the end speeds hold
    assert profile.harmonic_mean_mps(1000.0, 1200.0) == pytest.approx(1490.0)
    assert profile.harmonic_mean_mps(-5.0, 0.0) == pytest.approx(1520.0)


def test_ctd_cast_through_teos10_by_depth_or_pressure():
    depth = np.array([0.0, 50.0, 200.0, 1000.0, 2000.0])
    temp = np.array([18.0, 15.0, 10.0, 4.0, 2.5])
    sal = np.array([33.5, 33.6, 34.0, 34.4, 34.6])
    by_depth = SoundSpeedProfile.from_ctd(temp, sal, depth_m=depth, latitude_deg=32.8, longitude_deg=-117.3)
    np.testing.assert_allclose(
        by_depth.speed_mps, sound_speed_teos10_mps(temp, sal, depth, 32.8, -117.3), rtol=0, atol=1e-9
    )
    import gsw

    pressure = gsw.p_from_z(-depth, 32.8)
    by_p = SoundSpeedProfile.from_ctd(
        temp, sal, pressure_dbar=pressure, latitude_deg=32.8, longitude_deg=-117.3
    )
    np.testing.assert_allclose(by_p.depth_m, depth, atol=1e-6)
    np.testing.assert_allclose(by_p.speed_mps, by_depth.speed_mps, atol=1e-6)


def test_bad_profiles_are_refused_with_the_reason():
    with pytest.raises(DataError, match="increase strictly"):
        SoundSpeedProfile(depth_m=np.array([0.0, 10.0, 10.0]), speed_mps=np.full(3, 1500.0))
    with pytest.raises(DataError, match=r"outside \[1300, 1700\] m/s \(units\?\)"):
        SoundSpeedProfile(depth_m=np.array([0.0, 10.0]), speed_mps=np.array([1500.0, 4.9]))
    with pytest.raises(DataError, match="two or more"):
        SoundSpeedProfile(depth_m=np.array([0.0]), speed_mps=np.array([1500.0]))
