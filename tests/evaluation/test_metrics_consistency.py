import numpy as np
import pytest

from oceanloc.evaluation.metrics import epoch_consistency


def test_consistent_nees_has_mean_dof_and_five_percent_above_q95():
    # 4000 chi2(3) draws per epoch: the mean's SE is sqrt(6/4000) = 0.039 (4 SE: 0.155); the share above
    # the 95 % quantile has SE sqrt(0.05 * 0.95 / 4000) = 0.0034 (4 SE: 0.014).
    draws = np.random.default_rng(3).chisquare(3, size=(4000, 5))
    cons = epoch_consistency(draws, 3)
    assert cons.quantile == pytest.approx(7.8147, abs=1e-4)
    np.testing.assert_allclose(cons.mean_nees, 3.0, atol=0.155)
    np.testing.assert_allclose(cons.fraction_above, 0.05, atol=0.014)
    lo, hi = cons.mean_band
    assert hi - lo == pytest.approx(6 * np.sqrt(6 / 4000))


def test_overconfident_nees_shows_up_by_epoch():
    draws = np.random.default_rng(4).chisquare(3, size=(1000, 3)) * np.array([1.0, 4.0, 1.0])
    cons = epoch_consistency(draws, 3)
    assert cons.fraction_above[1] > 0.5 > cons.fraction_above[0]
    assert cons.to_record()["fraction_above_quantile"][1] == pytest.approx(cons.fraction_above[1])
