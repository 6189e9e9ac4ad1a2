import numpy as np
import pymap3d
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oceanloc.errors import DataError
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic, geodetic_to_enu, origin_from_first_fix

ORIGIN = EnuOrigin(lat_deg=32.705, lon_deg=-117.236, h_m=-1.478)


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-5000, 5000),
    st.floats(-5000, 5000),
    st.floats(-200, 200),
)
def test_enu_geodetic_round_trip_is_sub_millimetre(e, n, u):
    geo = enu_to_geodetic([e, n, u], ORIGIN)
    back = geodetic_to_enu(geo[0], geo[1], geo[2], ORIGIN)
    np.testing.assert_allclose(back, [e, n, u], atol=1e-6)


def test_matches_pymap3d_and_small_offsets_match_local_scale():
    # 1e-4 deg of latitude near 32.7 N is 11.09 m north (meridian arc); pymap3d is the oracle.
    enu = geodetic_to_enu(ORIGIN.lat_deg + 1e-4, ORIGIN.lon_deg, ORIGIN.h_m, ORIGIN)
    ref = pymap3d.geodetic2enu(ORIGIN.lat_deg + 1e-4, ORIGIN.lon_deg, ORIGIN.h_m, *vars_of(ORIGIN))
    np.testing.assert_allclose(enu, ref, atol=1e-9)
    assert abs(enu[1] - 11.09) < 0.01 and abs(enu[0]) < 1e-6


def vars_of(o):
    return o.lat_deg, o.lon_deg, o.h_m


def test_batch_shapes_and_first_fix_origin():
    lat = ORIGIN.lat_deg + np.linspace(0, 1e-3, 5)
    lon = np.full(5, ORIGIN.lon_deg)
    h = np.zeros(5)
    origin = origin_from_first_fix(lat, lon, h)
    enu = geodetic_to_enu(lat, lon, h, origin)
    assert enu.shape == (5, 3)
    np.testing.assert_allclose(enu[0], 0.0, atol=1e-9)


def test_bad_origin_is_a_data_error():
    with pytest.raises(DataError, match="latitude"):
        EnuOrigin(lat_deg=95.0, lon_deg=0.0, h_m=0.0)
    with pytest.raises(DataError, match="no fixes"):
        origin_from_first_fix([], [], [])
