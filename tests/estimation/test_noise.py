import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.estimation.noise import running_range_noise, stationary_mask, total_range_sigma_m


def test_running_estimates_match_numpy_and_converge():
    # 250 stationary ranges as in the papers: sigma_hat has relative SE 1/sqrt(2*249) = 4.5%; allow 3 SE.
    rng = np.random.default_rng(30)
    r = 9.02 + 0.113 * rng.standard_normal(250)
    est = running_range_noise(r)
    np.testing.assert_allclose(est.range_m[-1], r.mean(), rtol=1e-12)
    np.testing.assert_allclose(
        est.sigma_m[1:], [np.std(r[: i + 1], ddof=1) for i in range(1, 250)], rtol=1e-9
    )
    assert abs(est.final_sigma_m / 0.113 - 1) < 3 * 0.045
    assert np.isnan(est.sigma_m[0])


def test_total_sigma_is_the_journal_value_and_bad_input_errors():
    assert total_range_sigma_m(0.113, 1.0) == pytest.approx(1.006, abs=5e-4)
    with pytest.raises(DataError):
        running_range_noise([1.0])
    with pytest.raises(DataError, match="NaN"):
        running_range_noise([1.0, np.nan, 2.0])


def test_stationary_mask_finds_the_still_segment():
    t = np.arange(600.0)
    pos = np.zeros((600, 3))
    pos[300:, 0] = np.arange(300) * 1.0  # moving at 1 m/s after 300 s
    still = stationary_mask(t, pos + 0.3 * np.random.default_rng(0).standard_normal((600, 3)))
    assert still[:280].all() and not still[320:].any()
