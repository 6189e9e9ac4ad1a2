"""Repeatability of the array centre across surveys (:mod:`oceanloc.field.gnssa_surveys`)."""

import dataclasses

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.estimation.gnssa_array import GnssaArrayOptions, localize_gnssa_array
from oceanloc.field.gnssa_surveys import process_gnssa_array_surveys
from oceanloc.field.repeatability import survey_spread
from oceanloc.geo.plate_motion import SECONDS_PER_YEAR, plate_site_velocity
from oceanloc.io.gnssa import lajolla_paths, published_sound_speed_mps, read_gnssa
from oceanloc.io.gnssa_array import array_survey_from_gnssa
from oceanloc.sim.gnssa_array import simulate_gnssa_array

TRIANGLE = np.array([[500.0, 0.0, -2000.0], [-250.0, 433.0, -2010.0], [-250.0, -433.0, -1990.0]])


def test_la_jolla_surveys_through_the_array_path_keep_their_repeatability():
    """The five La Jolla files as one-transponder arrays, with the array solver's defaults (published
    speed as the prior, knots every 15 min, gradient, noise components, jackknife, survey-wide GNSS
    when the residuals are serially correlated, the model selection): std E 1.6, N 2.5, U 3.3 cm
    (targets E 2.5, N 3.5, U 6 cm; without the selection E 1.4, N 2.7, U 3.1 cm), and the sigmas explain
    it on every axis (chi-square on 4 dof inside 0.48-11.1). The selection keeps the knots on every
    survey and the gradient on three; the common-mode term stays on all five (four with correlated
    residuals, one with too few replies to tell)."""
    results = [
        localize_gnssa_array(
            array_survey_from_gnssa(read_gnssa(p)),
            GnssaArrayOptions(sound_speed_mps=published_sound_speed_mps(p)),
        )
        for p in lajolla_paths()
    ]
    origin = read_gnssa(lajolla_paths()[0]).origin
    velocity = plate_site_velocity(origin.lat_deg, origin.lon_deg, "PCFC")
    spread = survey_spread([r.centre for r in results], velocity)
    np.testing.assert_array_less(spread.std_enu_m, [0.025, 0.035, 0.06])
    assert spread.sigmas_explain_spread.tolist() == [True, True, True]
    np.testing.assert_allclose(spread.chi2_enu, [4.1, 7.8, 6.9], atol=0.2)
    kept = [{t.name: t.kept for t in r.model_tests} for r in results]
    assert all(k["sound_speed_variation"] and k["gnss_serial_correlation"] for k in kept)
    assert sum(k["gradient"] for k in kept) == 3
    gross = [e for r in results for e in r.exclusions if e.reason.startswith("gross")]
    assert [e.line for e in gross] == [57]


def test_array_centre_moves_with_the_site_and_the_surveys_measure_its_velocity():
    velocity_mps = np.array([-0.044, 0.026, 0.0]) / SECONDS_PER_YEAR  # the Pacific plate at La Jolla
    surveys = []
    for k, years in enumerate((0.0, 0.5, 1.0)):
        rng = np.random.default_rng(40 + k)
        dt = years * SECONDS_PER_YEAR
        survey, truth = simulate_gnssa_array(rng, positions_enu_m=TRIANGLE + velocity_mps * dt, n_pings=300)
        surveys.append(
            dataclasses.replace(
                survey, t_transmit_s=survey.t_transmit_s + dt, t_receive_s=survey.t_receive_s + dt
            )
        )
    out = process_gnssa_array_surveys(
        surveys, GnssaArrayOptions(), profiles=[truth.profile], site_velocity="-44,26"
    )
    assert out.spread is not None and out.as_surveyed is not None
    # moved to one epoch, the centres agree within their sigmas; as surveyed they are 5 cm apart
    assert out.spread.sigmas_explain_spread.all()
    assert out.as_surveyed.std_enu_m[0] > 0.015
    assert out.spread.fitted_velocity_enu_mps is not None
    fitted = out.spread.fitted_velocity_enu_mps * SECONDS_PER_YEAR
    sigma = out.spread.fitted_velocity_sigma_enu_mps * SECONDS_PER_YEAR
    assert np.all(np.abs(fitted[:2] - [-0.044, 0.026]) < 4.0 * sigma[:2])
    record = out.to_record()
    assert record["centre_spread"]["n_surveys"] == 3 and len(record["surveys"]) == 3


def test_surveys_of_different_arrays_are_refused():
    rng = np.random.default_rng(1)
    a, _ = simulate_gnssa_array(rng, positions_enu_m=TRIANGLE, n_pings=40)
    b = dataclasses.replace(a, transponder_ids=("X", "Y", "Z"))
    with pytest.raises(ConfigError, match="name different transponders"):
        process_gnssa_array_surveys([a, b], GnssaArrayOptions())
    with pytest.raises(ConfigError, match="one sound-speed profile, one per survey"):
        process_gnssa_array_surveys([a, a, a], GnssaArrayOptions(), profiles=[None, None])
