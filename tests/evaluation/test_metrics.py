import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.estimation.consistency import chi_square_check, nees
from oceanloc.evaluation.metrics import log_det_stats, rmsee


def test_rmsee_eq45():
    err = np.array([[[3.0, 4.0, 0.0]], [[0.0, 0.0, 0.0]]])  # two runs, one transponder
    assert rmsee(err) == pytest.approx([np.sqrt(12.5)])


def test_nees_is_block_diagonal_sum():
    e = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    info = np.stack([np.eye(3) * 2.0, np.eye(3) * 3.0])
    assert nees(e, info) == pytest.approx(2.0 + 12.0)


def test_chi_square_check_accepts_chi_square_and_rejects_scaled():
    # Seeded: 1000 chi2(12) draws sit inside the 3-SE band; 1.3x scaled draws fall outside it.
    rng = np.random.default_rng(3)
    good = chi_square_check(rng.chisquare(12, 1000), 12)
    assert good.mean_within_band and good.p_value > 0.01
    bad = chi_square_check(1.3 * rng.chisquare(12, 1000), 12)
    assert not bad.mean_within_band and bad.p_value < 1e-6
    assert good.mean_band == pytest.approx((12 - 3 * np.sqrt(24 / 1000), 12 + 3 * np.sqrt(24 / 1000)))
    with pytest.raises(ConfigError):
        chi_square_check([1.0], 3)


def test_log_det_stats():
    s = log_det_stats(np.array([[1.0, 2.0], [3.0, 6.0]]))
    np.testing.assert_allclose(s.mean, [2.0, 4.0])
    np.testing.assert_allclose(s.std, [np.sqrt(2.0), np.sqrt(8.0)])
    np.testing.assert_allclose(s.standard_error, s.std / np.sqrt(2))
