from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from oceanloc.errors import ConfigError
from oceanloc.field.repeatability import survey_spread
from oceanloc.geo.plate_motion import SECONDS_PER_YEAR, SiteVelocity, given_site_velocity

YEAR = SECONDS_PER_YEAR


def _surveys(pos, sig, epochs):
    return [
        SimpleNamespace(position_enu_m=np.asarray(p, float), sigma_enu_m=np.asarray(sig, float), epoch_s=t)
        for p, t in zip(pos, epochs, strict=True)
    ]


def test_spread_chi_square_and_its_bounds():
    # Three surveys at E = -1, 0, +1 cm with 1 cm sigmas: chi-square 2 on 2 dof, inside (0.05, 7.38).
    pos = np.array([[-0.01, 0.0, 0.0], [0.0, 0.0, 0.0], [0.01, 0.0, 0.0]])
    results = _surveys(pos, [0.01, 0.02, 0.03], [0.0, 0.0, 0.0])
    s = survey_spread(results)
    np.testing.assert_allclose(s.std_enu_m, [0.01, 0.0, 0.0], atol=1e-15)
    assert s.chi2_enu[0] == pytest.approx(2.0)
    np.testing.assert_allclose(s.chi2_bounds, stats.chi2.ppf([0.025, 0.975], 2))
    assert s.sigmas_explain_spread.tolist() == [True, False, False]  # zero spread is below the range
    assert s.fitted_velocity_enu_mps is None  # the epochs span no time
    with pytest.raises(ConfigError, match="at least two surveys"):
        survey_spread(results[:1])


def test_a_moving_site_is_compared_at_one_epoch():
    # A site moving 40 mm/yr west and 25 mm/yr north, surveyed exactly at four epochs over a year: as
    # surveyed the spread is the motion; moved by the velocity it vanishes, and the fit recovers it.
    v = np.array([-0.040, 0.025, 0.0]) / YEAR
    epochs = np.array([0.0, 0.1, 0.4, 1.0]) * YEAR
    pos = np.array([0.01, -0.02, 0.0]) + v * epochs[:, None]
    results = _surveys(pos, [0.01, 0.01, 0.02], epochs)
    raw = survey_spread(results)
    assert raw.std_enu_m[0] == pytest.approx(0.040 * np.std(epochs / YEAR, ddof=1))
    moved = survey_spread(results, given_site_velocity((-40.0, 25.0)), reference_epoch_s=0.0)
    np.testing.assert_allclose(moved.std_enu_m, 0.0, atol=1e-12)
    np.testing.assert_allclose(moved.positions_enu_m, np.tile([0.01, -0.02, 0.0], (4, 1)), atol=1e-12)
    assert moved.reference_epoch_s == 0.0 and raw.reference_epoch_s == pytest.approx(0.375 * YEAR)
    np.testing.assert_allclose(raw.fitted_velocity_enu_mps, v, atol=1e-15)
    # slope sigma of equal-weight least squares: sigma / sqrt(sum (t - mean t)^2)
    spread_t = np.sqrt(np.sum((epochs - epochs.mean()) ** 2))
    np.testing.assert_allclose(raw.fitted_velocity_sigma_enu_mps, np.array([0.01, 0.01, 0.02]) / spread_t)


def test_velocity_uncertainty_adds_in_quadrature():
    # 3 mm/yr of velocity uncertainty, 2 years from the reference epoch: 6 mm with the 8 mm sigma -> 10 mm.
    vel = SiteVelocity(
        velocity_enu_mps=np.zeros(3), sigma_enu_mps=np.array([3e-3, 0.0, 0.0]) / YEAR, source="test"
    )
    results = _surveys(np.zeros((2, 3)), [0.008, 0.008, 0.008], [-2.0 * YEAR, 2.0 * YEAR])
    s = survey_spread(results, vel, reference_epoch_s=0.0)
    np.testing.assert_allclose(s.sigma_enu_m[:, 0], 0.010)
    np.testing.assert_allclose(s.sigma_enu_m[:, 1], 0.008)
