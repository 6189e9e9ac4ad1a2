import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.estimation.consistency import confidence_ellipse, ellipse_scale, sample_ellipse


def test_scale_is_appendix_b_value():
    assert ellipse_scale(0.95) == pytest.approx(2.4477, abs=1e-4)


def test_axes_and_angle_of_a_rotated_covariance():
    rot = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    cov = rot @ np.diag([9.0, 1.0]) @ rot.T
    ell = confidence_ellipse([1.0, 2.0], cov)
    assert ell.semi_major_m == pytest.approx(3.0 * 2.4477, rel=1e-4)
    assert ell.semi_minor_m == pytest.approx(2.4477, rel=1e-4)
    assert ell.angle_rad == pytest.approx(0.3)
    pts = ell.points(50)
    d = pts - [1.0, 2.0]
    np.testing.assert_allclose(np.einsum("ni,ij,nj->n", d, np.linalg.inv(cov), d), ellipse_scale(0.95) ** 2)


def test_coverage_of_gaussian_samples():
    # 20000 samples: the fraction inside has standard error sqrt(0.95*0.05/20000) = 0.0015; allow 3 SE.
    rng = np.random.default_rng(0)
    cov = np.array([[4.0, 1.5], [1.5, 2.0]])
    pts = rng.multivariate_normal([0, 0], cov, 20000)
    inside = np.einsum("ni,ij,nj->n", pts, np.linalg.inv(cov), pts) <= ellipse_scale(0.95) ** 2
    assert abs(inside.mean() - 0.95) < 3 * np.sqrt(0.95 * 0.05 / 20000)
    fit = sample_ellipse(pts)
    assert fit.semi_major_m == pytest.approx(confidence_ellipse([0, 0], cov).semi_major_m, rel=0.03)


def test_bad_inputs():
    with pytest.raises(ConfigError, match="confidence"):
        ellipse_scale(1.5)
    with pytest.raises(ConfigError, match="at least 3 points"):
        sample_ellipse(np.zeros((2, 2)))
