import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection


@settings(max_examples=25, deadline=None)
@given(st.floats(-60, 60), st.floats(-179, 179), st.floats(-20_000, 20_000), st.floats(-20_000, 20_000))
def test_round_trip(lat0, lon0, x, y):
    p = LocalProjection(lat0_deg=lat0, lon0_deg=lon0)
    lon, lat = p.to_lonlat(x, y)
    x2, y2 = p.to_local(lon, lat)
    assert float(x2) == pytest.approx(x, abs=1e-6)
    assert float(y2) == pytest.approx(y, abs=1e-6)


def test_small_offsets_match_the_local_radii_of_curvature():
    lat0 = 32.7
    p = LocalProjection(lat0_deg=lat0, lon0_deg=-117.2)
    a, e2 = 6378137.0, 6.69437999014e-3
    s = np.sin(np.radians(lat0))
    n_radius = a / np.sqrt(1 - e2 * s * s)
    m_radius = a * (1 - e2) / (1 - e2 * s * s) ** 1.5
    x, y = p.to_local(-117.2 + 0.001, lat0 + 0.001)
    # First order in the offsets; the second-order terms are ~1e-5 of 100 m here.
    assert float(x) == pytest.approx(np.radians(0.001) * n_radius * np.cos(np.radians(lat0)), rel=1e-4)
    assert float(y) == pytest.approx(np.radians(0.001) * m_radius, rel=1e-4)


def test_longitudes_wrap_near_the_origin():
    p = LocalProjection(lat0_deg=0.0, lon0_deg=179.9)
    x, _ = p.to_local(-179.9, 0.0)  # 0.2 degrees east across the antimeridian
    assert float(x) == pytest.approx(22_264, rel=1e-3)
    with pytest.raises(ConfigError):
        LocalProjection(lat0_deg=95.0, lon0_deg=0.0)
