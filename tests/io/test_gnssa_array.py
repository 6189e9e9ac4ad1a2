"""Array survey type and builders (:mod:`oceanloc.io.gnssa_array`); ECEF conversions (:mod:`.geo.ecef`)."""

import dataclasses

import numpy as np
import pytest

from oceanloc.errors import ConfigError, DataError
from oceanloc.geo.ecef import ecef_covariance_to_enu_m2, ecef_to_enu_m, enu_rotation, enu_to_ecef_m
from oceanloc.geo.enu import EnuOrigin
from oceanloc.io.gnssa import lajolla_paths, read_gnssa
from oceanloc.io.gnssa_array import (
    AntennaTrack,
    array_survey_from_gnssa,
    array_survey_from_track,
    array_survey_from_transducers,
)
from oceanloc.models.attitude import rotation_enu_from_body, transducer_jacobians


def _track(sigma_att=(0.0, 0.0, 0.0)):
    t = np.arange(0.0, 100.0, 1.0)
    pos = np.stack([2.0 * t, np.zeros_like(t), np.full_like(t, 1.5)], axis=1)
    cov = np.broadcast_to(np.diag([4e-4, 4e-4, 1e-3]), (t.size, 3, 3)).copy()
    att = np.stack([3.0 * np.sin(t / 3.0), np.zeros_like(t), np.full_like(t, 90.0)], axis=1)
    return AntennaTrack(
        t_s=t,
        position_enu_m=pos,
        covariance_enu_m2=cov,
        attitude_deg=att,
        attitude_sigma_deg=np.array(sigma_att),
    )


def test_track_survey_puts_the_transducer_through_the_lever_arm_at_transmit_and_receive():
    track = _track()
    lever = np.array([1.0, 0.5, 2.0])
    survey = array_survey_from_track(
        name="s",
        track=track,
        t_transmit_s=np.array([10.0, 20.0]),
        reply_ping=np.array([0, 0, 1]),
        reply_transponder=np.array([0, 1, 1]),
        twtt_s=np.array([2.5, 3.0, 2.7]),
        turnaround_s=np.array([0.1, 0.2]),
        transponder_ids=("A", "B"),
        lever_arm_body_m=lever,
    )
    np.testing.assert_allclose(survey.t_receive_s, [12.5, 13.0, 22.7])
    pos, _, att = track.at(np.array([12.5]))
    expected = pos[0] + rotation_enu_from_body(*att[0]) @ lever
    np.testing.assert_allclose(survey.receive_enu_m()[0], expected)
    # heading 90: forward is east, starboard south, down down
    tx = survey.transmit_enu_m()
    r = rotation_enu_from_body(*track.at(np.array([10.0]))[2][0])
    np.testing.assert_allclose(tx[0], [20.0, 0.0, 1.5] + r @ lever)
    assert survey.replies_per_transponder.tolist() == [1, 2]
    # another lever arm on demand (the solver's calibration)
    np.testing.assert_allclose(survey.transmit_enu_m(np.zeros(3))[0], [20.0, 0.0, 1.5])


def test_attitude_sigma_is_propagated_into_the_position_covariance():
    lever = np.array([0.0, 3.0, 0.0])
    common = dict(
        name="s",
        t_transmit_s=np.array([10.0]),
        reply_ping=np.array([0]),
        reply_transponder=np.array([0]),
        twtt_s=np.array([2.0]),
        turnaround_s=np.array([0.0]),
        transponder_ids=("A",),
        lever_arm_body_m=lever,
    )
    exact = array_survey_from_track(track=_track(), **common)
    noisy = array_survey_from_track(track=_track((0.5, 0.5, 1.0)), **common)
    _, _, att = _track().at(np.array([10.0]))
    _, d_att = transducer_jacobians(att[:, 0], att[:, 1], att[:, 2], lever)
    added = d_att[0] @ np.diag([0.25, 0.25, 1.0]) @ d_att[0].T
    np.testing.assert_allclose(noisy.transmit_antenna_cov_m2[0] - exact.transmit_antenna_cov_m2[0], added)
    # a 3 m starboard arm and 1 deg of heading: about 5 cm along track
    assert np.sqrt(added[1, 1] + added[0, 0]) == pytest.approx(3.0 * np.radians(1.0), rel=0.2)


def test_la_jolla_survey_becomes_a_one_transponder_array():
    base = read_gnssa(lajolla_paths()[0])
    survey = array_survey_from_gnssa(base)
    assert survey.n_transponders == 1 and survey.n_replies == base.n_pings == survey.n_pings
    np.testing.assert_allclose(survey.receive_enu_m(), base.receive_enu_m)
    np.testing.assert_allclose(
        np.sqrt(np.diagonal(survey.transmit_antenna_cov_m2, axis1=1, axis2=2)), base.sigma_transmit_enu_m
    )
    assert survey.origin == base.origin and survey.line.tolist() == base.line.tolist()


def test_inconsistent_surveys_are_refused():
    n = 3
    kw = dict(
        name="s",
        t_transmit_s=np.arange(n, dtype=float),
        transmit_enu_m=np.zeros((n, 3)),
        transmit_cov_m2=np.broadcast_to(np.eye(3) * 1e-4, (n, 3, 3)),
        reply_ping=np.arange(n),
        reply_transponder=np.zeros(n, dtype=int),
        twtt_s=np.full(n, 2.0),
        receive_enu_m=np.zeros((n, 3)),
        receive_cov_m2=np.broadcast_to(np.eye(3) * 1e-4, (n, 3, 3)),
        turnaround_s=np.zeros(1),
        transponder_ids=("A",),
    )
    survey = array_survey_from_transducers(**kw)
    assert survey.n_pings == 3
    with pytest.raises(ConfigError, match=r"receive_antenna_enu_m has shape \(2, 3\), expected \(3, 3\)"):
        array_survey_from_transducers(**{**kw, "receive_enu_m": np.zeros((2, 3))})
    with pytest.raises(ConfigError, match="indexes a transponder that does not exist"):
        array_survey_from_transducers(**{**kw, "reply_transponder": np.array([0, 1, 0])})
    with pytest.raises(DataError, match=r"reply 1 has TWTT -1.0 s outside \(0, 60\) s"):
        array_survey_from_transducers(**{**kw, "twtt_s": np.array([2.0, -1.0, 2.0])})
    with pytest.raises(DataError, match="outside the antenna track"):
        array_survey_from_track(
            name="s",
            track=_track(),
            t_transmit_s=np.array([98.0]),
            reply_ping=np.array([0]),
            reply_transponder=np.array([0]),
            twtt_s=np.array([5.0]),
            turnaround_s=np.zeros(1),
            transponder_ids=("A",),
            lever_arm_body_m=np.zeros(3),
        )
    assert dataclasses.replace(survey, name="t").name == "t"


def test_ecef_positions_and_covariances_rotate_to_enu():
    origin = EnuOrigin(lat_deg=32.87, lon_deg=-117.27, h_m=-30.0)
    enu = np.array([[100.0, -50.0, -2000.0], [0.0, 0.0, 0.0]])
    xyz = enu_to_ecef_m(enu, origin)
    np.testing.assert_allclose(ecef_to_enu_m(xyz, origin), enu, atol=1e-6)
    r = enu_rotation(origin)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    # the rotation maps a small ECEF displacement to the ENU one
    d = np.array([0.3, -0.2, 0.1])
    np.testing.assert_allclose(ecef_to_enu_m(xyz[1] + d, origin), r @ d, atol=1e-6)
    cov = np.diag([1e-4, 4e-4, 9e-4])
    enu_cov = ecef_covariance_to_enu_m2(cov, origin)
    np.testing.assert_allclose(enu_cov, r @ cov @ r.T)
    assert np.trace(enu_cov) == pytest.approx(np.trace(cov))


def test_enu_rotations_batched_are_the_origins_one_by_one():
    """``enu_rotation_at`` over a batch of points (poles and the antimeridian included) equals
    ``enu_rotation`` at each, and maps small ECEF displacements to pymap3d's ENU ones."""
    from oceanloc.geo.ecef import enu_rotation_at

    lat = np.array([[89.9, -45.0, 0.0], [32.87, 60.0, -89.9]])
    lon = np.array([[0.0, 179.9, -180.0], [-117.27, 350.0, 10.0]])
    rot = enu_rotation_at(lat, lon)
    assert rot.shape == (2, 3, 3, 3)
    d = np.array([0.3, -0.2, 0.1])
    for idx in np.ndindex(lat.shape):
        origin = EnuOrigin(lat_deg=float(lat[idx]), lon_deg=float(lon[idx]), h_m=0.0)
        np.testing.assert_allclose(rot[idx], enu_rotation(origin), atol=1e-15)
        xyz = enu_to_ecef_m(np.zeros(3), origin)
        np.testing.assert_allclose(ecef_to_enu_m(xyz + d, origin), rot[idx] @ d, atol=1e-6)
