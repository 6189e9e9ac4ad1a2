import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from oceanloc.models.measurements import range_jacobian, range_m, simulate_ranges

finite = st.floats(-100, 100, allow_nan=False)


@settings(max_examples=100, deadline=None)
@given(arrays(float, (2, 3), elements=finite))
def test_range_jacobian_matches_central_differences(pts):
    target, sensor = pts
    if np.linalg.norm(target - sensor) < 1e-2:
        return
    eps = 1e-6
    fd = np.array(
        [
            (range_m(target + eps * e, sensor) - range_m(target - eps * e, sensor)) / (2 * eps)
            for e in np.eye(3)
        ]
    )
    np.testing.assert_allclose(range_jacobian(target, sensor), fd, atol=1e-7)


def test_range_jacobian_is_unit_line_of_sight_eq8():
    h = range_jacobian([17.0, 15.0, -6.0], [5.0, 5.0, 0.0])
    np.testing.assert_allclose(h, np.array([12.0, 10.0, -6.0]) / np.sqrt(280.0))
    assert np.linalg.norm(h) == 1.0 or abs(np.linalg.norm(h) - 1) < 1e-15


def test_range_jacobian_zero_at_coincident_points():
    np.testing.assert_array_equal(range_jacobian([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]), np.zeros(3))


def test_range_batches_broadcast():
    targets = np.zeros((4, 1, 3))
    sensors = np.arange(6, dtype=float).reshape(1, 2, 3)
    assert range_m(targets, sensors).shape == (4, 2)
    assert range_jacobian(targets, sensors).shape == (4, 2, 3)


def test_simulated_noise_has_requested_sigma():
    # 20000 draws: the sample std has relative standard error 1/sqrt(2*20000) = 0.5%; allow 3 SE.
    rng = np.random.default_rng(7)
    z = simulate_ranges(np.zeros((20000, 3)), np.array([3.0, 4.0, 0.0]), 0.12, rng)
    assert abs(z.mean() - 5.0) < 3 * 0.12 / np.sqrt(20000)
    assert abs(z.std() / 0.12 - 1) < 3 * 0.005


def test_per_run_generators_make_draws_batch_independent():
    from oceanloc._random import run_generators

    whole = simulate_ranges(np.zeros((5, 3)), np.ones(3), 1.0, run_generators(3, range(5)))
    part = simulate_ranges(np.zeros((2, 3)), np.ones(3), 1.0, run_generators(3, [3, 4]))
    np.testing.assert_array_equal(whole[3:], part)
