import numpy as np
import pytest
from scipy import optimize

from oceanloc.errors import ConfigError
from oceanloc.planning.box_search import BoxSearchOptions, grid_maximum, maximize_in_box


def _multimodal(x, rows):
    # Two peaks in [-1, 1]^2; the global one (value 1) is the narrower, at (0.6, -0.5).
    a = np.exp(-((x[..., 0] - 0.6) ** 2 + (x[..., 1] + 0.5) ** 2) / 0.02)
    b = 0.8 * np.exp(-((x[..., 0] + 0.4) ** 2 + (x[..., 1] - 0.3) ** 2) / 0.3)
    return a + b


def test_finds_global_peak_not_the_broad_local_one():
    best = maximize_in_box(_multimodal, [-1, -1], [1, 1], 3)
    ref = optimize.minimize(lambda x: -_multimodal(x[None, None], None)[0, 0], [0.6, -0.5], tol=1e-14)
    np.testing.assert_allclose(best.x, [ref.x] * 3, atol=1e-6)
    # The search stops once its local model promises less than value_tol (1e-10, relative) more.
    assert np.all(best.value >= -ref.fun * (1 - 1e-10))


def test_optimum_on_a_bound_and_on_a_corner():
    def ramp(x, rows):  # maximized at x0 = 1 (bound), x1 = 0.25 (interior)
        return x[..., 0] - (x[..., 1] - 0.25) ** 2

    best = maximize_in_box(ramp, [-1, -1], [1, 1], 1)
    np.testing.assert_allclose(best.x[0], [1.0, 0.25], atol=1e-7)
    corner = maximize_in_box(lambda x, r: x.sum(-1), [0, 0, 0], [1, 2, 3], 1)
    np.testing.assert_allclose(corner.x[0], [1, 2, 3], atol=1e-12)


# The search stops on value: within value_tol = 1e-10 (relative, at least absolute) of a maximum of
# curvature c, the point is within sqrt(2e-10 / c); for unit curvature 1.4e-5.
X_TOL_UNIT_CURVATURE = np.sqrt(2e-10)


def test_a_bound_the_objective_rises_away_from_is_not_returned():
    # The maximum is 1e-3 inside the lower bound: the bound is the best grid point, and a stencil of half
    # a grid step sees it as a maximum with zero gradient (x = c + r sin(u) is stationary there); finer
    # stencils find the way in. Returning the bound would cost 1e-6.
    best = maximize_in_box(lambda x, r: -((x[..., 0] + 0.999) ** 2), [-1.0], [1.0], 1)
    assert best.value[0] >= -1e-10
    assert best.x[0, 0] == pytest.approx(-0.999, abs=X_TOL_UNIT_CURVATURE)


def test_periodic_dimension_wraps():
    best = maximize_in_box(lambda x, r: np.cos(x[..., 0] - 3.1), [-np.pi], [np.pi], 1, periodic=[True])
    assert best.x[0, 0] == pytest.approx(3.1, abs=X_TOL_UNIT_CURVATURE)
    assert best.value[0] >= 1.0 - 1e-10


def test_problems_in_a_batch_are_independent():
    def shifted(x, rows):
        return -((x[..., 0] - 0.1 * rows[:, None]) ** 2)

    best = maximize_in_box(shifted, [-1], [1], 5)
    np.testing.assert_allclose(best.x[:, 0], 0.1 * np.arange(5), atol=X_TOL_UNIT_CURVATURE / np.sqrt(2))
    assert np.all(best.value >= -1e-10)


def test_beats_or_matches_fine_grid():
    grid = grid_maximum(_multimodal, [-1, -1], [1, 1], 1, 801)
    best = maximize_in_box(_multimodal, [-1, -1], [1, 1], 1, options=BoxSearchOptions(grid_points=7))
    assert best.value[0] >= grid.value[0] - 1e-12


def test_invalid_box_is_a_config_error():
    with pytest.raises(ConfigError, match="invalid box"):
        maximize_in_box(_multimodal, [0, 0], [1, -1], 1)
