import numpy as np
import pymap3d
import pytest

from oceanloc.errors import ConfigError
from oceanloc.geo.plate_motion import (
    ITRF2014_POLES_MAS_YR,
    MAS_PER_YEAR_RAD_S,
    SECONDS_PER_YEAR,
    given_site_velocity,
    plate_site_velocity,
    plate_velocity_enu_mps,
)

LA_JOLLA = (32.8668445, -117.2701205)


@pytest.mark.parametrize("plate", sorted(ITRF2014_POLES_MAS_YR))
@pytest.mark.parametrize(("lat", "lon"), [LA_JOLLA, (-20.0, 170.0), (60.0, -40.0)])
def test_plate_velocity_matches_the_spherical_closed_form(plate, lat, lon):
    # On a sphere at geocentric (phi, lambda): v_E = R omega.n and v_N = -R omega.e, with e and n the
    # local east and north unit vectors; our ellipsoidal normal tilts by < 0.2 deg from the radius, so
    # the two agree to 0.5 % of the speed.
    w = np.array(ITRF2014_POLES_MAS_YR[plate]) * MAS_PER_YEAR_RAD_S
    r = np.array(pymap3d.geodetic2ecef(lat, lon, 0.0))
    phi, lam, radius = np.arcsin(r[2] / np.linalg.norm(r)), np.arctan2(r[1], r[0]), np.linalg.norm(r)
    east = np.array([-np.sin(lam), np.cos(lam), 0.0])
    north = np.array([-np.sin(phi) * np.cos(lam), -np.sin(phi) * np.sin(lam), np.cos(phi)])
    expected = radius * np.array([w @ north, -(w @ east)])
    got = plate_velocity_enu_mps(lat, lon, plate)
    assert got[2] == 0.0
    np.testing.assert_allclose(got[:2], expected, atol=5e-3 * np.linalg.norm(expected))


def test_pacific_plate_at_la_jolla():
    # ITRF2014 Pacific plate at the La Jolla transponder: 44.0 mm/yr west, 26.0 mm/yr north (51 mm/yr
    # towards N59W); the GNSS-A surveys from July 2021 to March 2022 span 0.66 yr, 3.4 cm of motion.
    v = plate_site_velocity(*LA_JOLLA, "PCFC")
    np.testing.assert_allclose(v.velocity_enu_mm_yr, [-44.0, 26.0, 0.0], atol=0.1)
    assert v.sigma_enu_mps[0] * SECONDS_PER_YEAR * 1e3 == pytest.approx(5.0)
    assert v.source == "ITRF2014 PCFC"


def test_bad_plates_and_velocities_are_refused():
    with pytest.raises(ConfigError, match="unknown plate 'XXXX'; known: PCFC, NOAM"):
        plate_velocity_enu_mps(0.0, 0.0, "XXXX")
    with pytest.raises(ConfigError, match="2 or 3 finite numbers"):
        given_site_velocity((1.0,))
    with pytest.raises(ConfigError, match="2 or 3 finite numbers"):
        given_site_velocity((1.0, float("nan")))
    np.testing.assert_allclose(given_site_velocity((-40.0, 20.0)).velocity_enu_mm_yr, [-40.0, 20.0, 0.0])


@pytest.mark.parametrize(
    ("lat", "lon", "plate"),
    [
        (32.8668445, -117.2701205, "PCFC"),  # La Jolla offshore: west of the Imperial/San Andreas system
        (34.05, -118.25, "PCFC"),  # Los Angeles, west of the San Andreas big bend
        (37.77, -122.42, "NOAM"),  # San Francisco, east of the San Andreas
        (32.7, -114.6, "NOAM"),  # Yuma, east of the Salton Trough
        (19.7, -155.5, "PCFC"),  # Hawaii
        (30.0, 160.0, "PCFC"),  # west of the antimeridian
        (35.0, -70.0, "NOAM"),  # western North Atlantic
        (35.0, -20.0, None),  # east of the Mid-Atlantic Ridge: a plate the model does not know
        (0.0, 0.0, None),
    ],
)
def test_plate_at_finds_the_plate_of_the_site(lat, lon, plate):
    from oceanloc.geo.plate_motion import plate_at

    assert plate_at(lat, lon) == plate
    assert plate_at(lat, lon + 360.0) == plate  # longitudes east of 180 wrap
