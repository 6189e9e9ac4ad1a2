from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from oceanloc.errors import ConfigError
from oceanloc.evaluation.repeatability import survey_spread


def test_spread_chi_square_and_its_bounds():
    # Three surveys at E = -1, 0, +1 cm with 1 cm sigmas: chi-square 2 on 2 dof, inside (0.05, 7.38).
    pos = np.array([[-0.01, 0.0, 0.0], [0.0, 0.0, 0.0], [0.01, 0.0, 0.0]])
    results = [SimpleNamespace(position_enu_m=p, sigma_enu_m=np.array([0.01, 0.02, 0.03])) for p in pos]
    s = survey_spread(results)
    np.testing.assert_allclose(s.std_enu_m, [0.01, 0.0, 0.0], atol=1e-15)
    assert s.chi2_enu[0] == pytest.approx(2.0)
    np.testing.assert_allclose(s.chi2_bounds, stats.chi2.ppf([0.025, 0.975], 2))
    assert s.sigmas_explain_spread.tolist() == [True, False, False]  # zero spread is below the range
    with pytest.raises(ConfigError, match="at least two surveys"):
        survey_spread(results[:1])
