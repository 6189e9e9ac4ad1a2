"""Filter runner: NEES/NIS consistency against chi-square, missing measurements, HDOP over time."""

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.estimation.gaussian import Gaussian
from oceanloc.estimation.tracking import FlockSensorModel, run_filter
from oceanloc.models.motion import constant_velocity
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


def _near_node_pass(bias_s: float):
    """TDOA tracking of a target passing 2.5 m from node 0 of a 4-node square (+-100 m) at 1 m/s.

    While the target is within 2.6 m of node 0 (15 epochs of 0.1 s) node 0's arrival is late by
    ``bias_s`` (the direct path and the surface reflection merge at close range), so every pair with
    node 0 is off by ``bias_s`` (10 ms = 15 m, 100 sigma).
    """
    nodes = np.array([[100.0, 0.0], [0.0, 100.0], [-100.0, 0.0], [0.0, -100.0]])
    dt, t_count, runs, sig = 0.1, 600, 20, 1e-4
    motion = constant_velocity(dt, 0.01)
    t = dt * np.arange(1, t_count + 1)
    start, v = np.array([102.5, -30.0]), np.array([0.0, 1.0])
    truth = np.concatenate([start + v * t[:, None], np.broadcast_to(v, (t_count, 2))], axis=1)
    model = FlockSensorModel.build("tdoa", 4, sig)
    rng = np.random.default_rng(1)
    z = model.measure(truth, nodes) + sig * rng.standard_normal((runs, t_count, model.dim))
    near = np.linalg.norm(truth[:, :2] - nodes[0], axis=-1) < 2.6
    z[:, near] += bias_s * ((model.pairs[:, 0] == 0).astype(float) - (model.pairs[:, 1] == 0))
    mean0 = np.r_[start + np.array([1.0, -1.0]), v]
    init = Gaussian.from_single(mean0, np.diag([2.0, 2.0, 0.2, 0.2]) ** 2, runs)
    return motion, model, init, truth, z, np.broadcast_to(nodes, (t_count, 4, 2)), near


@pytest.mark.parametrize("filt", ["ekf", "ukf"])
def test_nis_gate_keeps_a_near_node_pass_bounded(filt):
    motion, model, init, truth, z, nodes, near = _near_node_pass(1e-2)
    assert near.sum() == 15
    # Without the gate the 100-sigma innovations are accepted: the track is pulled > 30 m away while
    # its own sigma stays ~0.1 m, and the streak of NIS beyond the 0.999 quantile flags the divergence.
    raw = run_filter(filt, init, motion, model, z, nodes, gate_probability=None)
    err = np.linalg.norm(raw.estimates[..., :2] - truth[:, :2], axis=-1)
    sd = np.sqrt(raw.covariances[..., 0, 0] + raw.covariances[..., 1, 1])
    assert err.max() > 30.0 and sd.flat[err.argmax()] < 0.2
    assert raw.nis.max() > 1e4 and raw.diverged.all() and not raw.gated.any()
    # With the gate the 15 bad epochs are rejected and the track coasts through them: its error stays
    # below 1 m, the bound from 3 times its largest posterior position sigma (0.33 m: the 0.2 m/s velocity
    # prior tightened by the track, times the 1.5 s coast, on top of the ~0.05 m sigma before it).
    gated = run_filter(filt, init, motion, model, z, nodes)
    err = np.linalg.norm(gated.estimates[..., :2] - truth[:, :2], axis=-1)
    sd = np.sqrt(gated.covariances[..., 0, 0] + gated.covariances[..., 1, 1])
    assert err.max() < 1.0 and err.max() < 3 * sd.max()
    assert np.all(gated.gated[:, near]) and not gated.diverged.any()
    # Plus the 0.1 % a consistent filter loses elsewhere: 585 epochs x 0.001 = 0.6 per run, <= 3 each.
    assert np.all((gated.gated_count >= 15) & (gated.gated_count <= 18))


def test_gate_reopens_after_a_streak_and_flags_the_divergence():
    # A prior 5 m off on the wrong side of the track (0.5 m sigma claimed): a gate alone rejects the right
    # measurements for good; after divergence_epochs epochs the track is flagged and re-acquires.
    motion, model, init, truth, z, nodes, _near = _near_node_pass(0.0)
    bad = Gaussian(mean=init.mean + np.array([-5.0, 0.0, 0.0, 0.0]), cov=init.cov / 16)
    res = run_filter("ekf", bad, motion, model, z, nodes, divergence_epochs=5)
    np.testing.assert_array_equal(res.diverged_epoch, 0)
    assert res.gated_count.max() <= 5 * 3  # the gate reopened
    err = np.linalg.norm(res.estimates[:, -1, :2] - truth[-1, :2], axis=-1)
    assert err.max() < 0.5  # re-acquired: 0.02 .. 0.17 m at the end, not 5 m
    coast = run_filter("ekf", bad, motion, model, z, nodes, divergence_epochs=10**6)
    # Without the reopening the gate locks the track out until Q has grown its covariance over the error.
    assert coast.gated_count.min() > 3 * res.gated_count.max()


def test_consistent_filter_is_rarely_gated_and_never_diverges():
    # E[gated share] = 1 - 0.999 for a consistent filter; 3 SE of a binomial over 16000 epochs = 0.00075.
    motion, model, init, _truth, z = consistent_bearing_problem(RUNS, EPOCHS, seed=3)
    res = run_filter("ekf", init, motion, model, z, np.broadcast_to(SENSORS, (EPOCHS, 4, 2)))
    assert abs(res.gated.mean() - 1e-3) < 3 * np.sqrt(1e-3 * 0.999 / (RUNS * EPOCHS))
    assert not res.diverged.any()
    with pytest.raises(ConfigError, match="gate probability"):
        run_filter("ekf", init, motion, model, z, SENSORS[None].repeat(EPOCHS, 0), gate_probability=1.0)
