"""Filter runner: NEES/NIS consistency against chi-square, missing measurements, HDOP over time."""

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.estimation.tracking import FlockSensorModel, run_filter
from oceanloc.planning.dop import hdop
from tests.estimation.flock_cases import SENSORS, consistent_bearing_problem

RUNS, EPOCHS = 400, 40


@pytest.mark.parametrize(("kind", "sigma"), [("bearing", 0.005), ("range", 2.0), ("tdoa", 2e-3)])
@pytest.mark.parametrize("filt", ["ekf", "ukf"])
def test_nees_and_nis_match_chi_square(kind, sigma, filt):
    # Truth drawn from the filter's model (high SNR, good geometry): a consistent filter has
    # E[NEES] = n = 4 and E[NIS] = m. Tolerances are 3 Monte Carlo standard errors:
    # NEES at the last epoch over 400 runs, SE = sqrt(2 n / 400) = 0.14;
    # NIS over 400 runs x 40 epochs (white in time for a consistent filter), SE = sqrt(2 m / 16000).
    motion, model, init, truth, z = consistent_bearing_problem(RUNS, EPOCHS, seed=3, kind=kind, sigma=sigma)
    res = run_filter(filt, init, motion, model, z, np.broadcast_to(SENSORS, (EPOCHS, 4, 2)))
    err = truth[:, -1] - res.estimates[:, -1]
    nees = np.einsum("bi,bij,bj->b", err, np.linalg.inv(res.covariances[:, -1]), err)
    assert abs(nees.mean() - 4) < 3 * np.sqrt(8 / RUNS)
    m = model.dim
    assert abs(res.nis.mean() - m) < 3 * np.sqrt(2 * m / (RUNS * EPOCHS))
    assert not res.repaired.any()


def test_dropouts_keep_consistency_and_count_dof():
    motion, model, init, _truth, z = consistent_bearing_problem(RUNS, EPOCHS, seed=7)
    rng = np.random.default_rng(0)
    z = np.where(rng.random(z.shape) < 0.3, np.nan, z)  # each node misses 30% of epochs
    res = run_filter("ukf", init, motion, model, z, np.broadcast_to(SENSORS, (EPOCHS, 4, 2)))
    np.testing.assert_array_equal(res.nis_dof, np.isfinite(z).sum(-1))
    # E[NIS] = E[dof]; SE from chi-square variances 2 dof summed over all epochs.
    assert abs(res.nis.sum() - res.nis_dof.sum()) < 3 * np.sqrt(2 * res.nis_dof.sum())
    assert np.all(np.isfinite(res.estimates))
    assert np.all(res.innovations[~np.isfinite(z)] == 0)


def test_hdop_over_time_matches_planning_dop():
    motion, model, init, _truth, z = consistent_bearing_problem(5, 10, seed=1)
    z[2, 4, 1] = np.nan
    res = run_filter("ekf", init, motion, model, z, np.broadcast_to(SENSORS, (10, 4, 2)))
    ref = hdop(SENSORS, res.estimates[..., :2], "bearing", 0.005)
    mask = np.ones(res.hdop_m.shape, bool)
    mask[2, 4] = False
    np.testing.assert_allclose(res.hdop_m[mask], ref[mask], rtol=1e-12)
    assert res.hdop_m[2, 4] == pytest.approx(
        hdop(SENSORS[[0, 2, 3]], res.estimates[2, 4, :2], "bearing", 0.005)
    )


def test_per_track_moving_sensors_and_shape_errors():
    motion, model, init, _truth, z = consistent_bearing_problem(3, 6, seed=2)
    sensors = np.broadcast_to(SENSORS, (3, 6, 4, 2)) + np.arange(6)[None, :, None, None]
    a = run_filter("ukf", init, motion, model, z, sensors, record_covariances=False)
    b = run_filter("ukf", init[1], motion, model, z[1:2], sensors[1], record_covariances=False)
    np.testing.assert_allclose(a.estimates[1], b.estimates[0], rtol=1e-12)
    assert a.covariances is None
    with pytest.raises(ConfigError, match="measurements"):
        run_filter("ekf", init, motion, model, z[:, :, :3], sensors)
    with pytest.raises(ConfigError, match="sensor positions"):
        run_filter("ekf", init, motion, model, z, sensors[:, :, :3])
    with pytest.raises(ConfigError, match="filter"):
        run_filter("pf", init, motion, model, z, sensors)


def test_sensor_model_validation():
    with pytest.raises(ConfigError, match="sigma"):
        FlockSensorModel.build("bearing", 3, 0.0)
    with pytest.raises(ConfigError, match="kind"):
        FlockSensorModel.build("doppler", 3, 1.0)
    tdoa = FlockSensorModel.build("tdoa", 3, 1e-3, pairs="reference")
    assert tdoa.dim == 2 and tdoa.angle_mask is None
    assert FlockSensorModel.build("bearing", 3, 0.01).angle_mask.all()
