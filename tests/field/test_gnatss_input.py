"""GNATSS-format surveys through the field layer: the antenna + attitude + lever-arm path reproduces the
transducer positions GNATSS's files carry, and both methods recover the truth of the packaged example."""

import json

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.field.gnatss_input import gnatss_example_config, load_gnatss_input, localize_gnatss_input


@pytest.fixture(scope="module")
def example():
    folder = gnatss_example_config().parent
    truth = json.loads((folder / "truth.json").read_text())
    return folder, np.array(truth["transponders_enu_m"])


def test_antenna_attitude_lever_arm_give_the_transducer_positions(example):
    folder, _ = example
    cfg = folder / "config.yaml"
    via_antenna = load_gnatss_input(
        cfg, pxp_tt=folder / "pxp_tt", antenna=folder / "GPS_POS_FREED", attitude=folder / "RPH"
    ).pings
    via_positions = load_gnatss_input(
        cfg, pxp_tt=folder / "pxp_tt", positions=folder / "POS_FREED_TRANS_TWTT"
    ).pings
    assert via_antenna.n_replies == via_positions.n_replies == 600
    # the lever arm (0.30, -0.10, 1.20) m rotated by roll, pitch and heading; files carry 0.1 mm
    assert np.max(np.abs(via_antenna.transmit_xyz_m - via_positions.transmit_xyz_m)) < 2e-4
    assert np.max(np.abs(via_antenna.receive_xyz_m - via_positions.receive_xyz_m)) < 2e-4
    # GPS_POS_FREED carries sigmas only: the diagonal of the transducer covariance is kept
    d_a = np.diagonal(via_antenna.transmit_cov_m2, axis1=1, axis2=2)
    d_p = np.diagonal(via_positions.transmit_cov_m2, axis1=1, axis2=2)
    assert np.allclose(d_a, d_p, rtol=5e-3)  # sigmas written to 0.1 mm


def test_both_methods_recover_the_example(example):
    folder, truth = example
    data = load_gnatss_input(folder / "config.yaml")
    gn = localize_gnatss_input(data, method="gnatss")
    assert np.max(np.abs(gn.positions_enu_m - truth)) < 0.01  # GNATSS's method: 2 mm sigmas
    oc = localize_gnatss_input(data, method="oceanloc", solution="common_shift")
    # horizontally within 3 sigma; vertically the example's travel times are GNATSS's straight ray at the
    # harmonic-mean speed, from which oceanloc's ray tracing through the same profile puts it 1.3 cm
    # shallower (13 to 15 mm mean over the oracle's 36 straight-ray surveys): a model difference
    err = oc.positions_enu_m - truth
    assert np.all(np.abs(err[:, :2]) < 3.0 * oc.sigma_enu_m[:, :2])
    assert np.all((err[:, 2] > 0.005) & (err[:, 2] < 0.02)), err
    rec = oc.to_record()
    assert rec["pings"]["reason"].count("") == 600 - rec["replies_excluded"]


def test_the_record_epoch_is_the_surveys_utc_time(example):
    """GNATSS's times are J2000 seconds (2000-01-01 12:00:00): the oceanloc record's ``epoch_utc`` is the
    mean interrogation time of the used pings as UTC, inside the survey's span (not 20 years off, as
    with the La Jolla files' 2020 time base)."""
    import datetime as dt

    folder, _ = example
    data = load_gnatss_input(folder / "config.yaml")
    details = localize_gnatss_input(data, method="oceanloc", solution="common_shift").to_record()["details"]
    j2000 = dt.datetime(2000, 1, 1, 12, tzinfo=dt.UTC)
    epoch = dt.datetime.fromisoformat(details["epoch_utc"])
    assert abs((epoch - (j2000 + dt.timedelta(seconds=details["epoch_s"]))).total_seconds()) <= 0.5
    t = data.pings.t_transmit_s
    first, last = (j2000 + dt.timedelta(seconds=float(v)) for v in (t.min(), t.max()))
    assert first <= epoch <= last


def test_input_combinations_are_checked(example):
    folder, _ = example
    with pytest.raises(ConfigError, match="--antenna and --attitude go together"):
        load_gnatss_input(folder / "config.yaml", pxp_tt=folder / "pxp_tt", antenna=folder / "GPS_POS_FREED")
    with pytest.raises(ConfigError, match="--antenna and --attitude need --pxp-tt"):
        load_gnatss_input(folder / "config.yaml", antenna=folder / "GPS_POS_FREED", attitude=folder / "RPH")
