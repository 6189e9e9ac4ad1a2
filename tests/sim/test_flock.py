"""Flock simulation: drifting nodes, target tracks, measurements independent of batching."""

import numpy as np
import pytest

from oceanloc._random import run_generators
from oceanloc.config.flock import load_flock_scenario
from oceanloc.errors import ConfigError
from oceanloc.estimation.tracking import FlockSensorModel
from oceanloc.sim.flock import (
    epoch_times,
    ring_drift_nodes,
    scenario_nodes,
    scenario_truth,
    simulate_measurements,
    stop_and_go_target,
    straight_target,
    y_nodes,
)


def test_ring_nodes_drift_along_the_circle_at_the_given_speed():
    t = epoch_times(0.5, 100.0)
    nodes = ring_drift_nodes(t, 4, 200.0, 0.5, center_m=(10.0, -5.0))
    assert nodes.shape == (200, 4, 2)
    np.testing.assert_allclose(np.linalg.norm(nodes - [10.0, -5.0], axis=-1), 200.0)
    speed = np.linalg.norm(np.diff(nodes, axis=0), axis=-1) / 0.5
    np.testing.assert_allclose(speed, 0.5, rtol=1e-5)
    first = nodes[0, 0] - [10.0, -5.0]  # node 0 starts at 45 degrees; t_1 = 0.5 s later it moved 0.25 m
    assert np.arctan2(first[1], first[0]) == pytest.approx(np.pi / 4 + 0.25 / 200.0)


def test_y_nodes_and_straight_target():
    y = y_nodes(2.5)
    np.testing.assert_allclose(y[0], [0.0, 2.5], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(y, axis=1), 2.5)
    truth = straight_target(np.array([1.0, 2.0]), [1.0, 2.0], [10.0, 1.0])
    np.testing.assert_allclose(truth, [[11.0, 3.0, 10.0, 1.0, 0.0, 0.0], [21.0, 4.0, 10.0, 1.0, 0.0, 0.0]])


def test_stop_and_go_stays_in_its_box_stops_and_walks():
    t = epoch_times(0.05, 120.0)
    tracks = stop_and_go_target(
        t, [0.0, 0.0], np.random.default_rng(2), 3, half_width_m=2.0, speed_mps=0.4, mean_pause_s=5.0
    )
    assert tracks.shape == (3, t.size, 6)
    # Waypoints lie in the box; the smoothed velocity can carry the target past one by speed x smoothing.
    assert np.all(np.abs(tracks[..., :2]) <= 2.0 + 0.4 * 0.5)
    speed = np.linalg.norm(tracks[..., 2:4], axis=-1)
    assert np.all(speed <= 0.4 + 1e-9)
    assert np.mean(speed < 0.01) > 0.2 and np.mean(speed > 0.35) > 0.2  # both standing and walking
    # Velocity is the derivative of the position.
    np.testing.assert_allclose(np.diff(tracks[0, :, :2], axis=0) / 0.05, tracks[0, 1:, 2:4], atol=1e-9)


def test_measurements_do_not_depend_on_batching():
    sc = load_flock_scenario("dillard-filters")
    t = epoch_times(0.1, 5.0)
    nodes = scenario_nodes(sc, t)
    truth = scenario_truth(sc, t, np.random.default_rng(0), 1)
    model = FlockSensorModel.build("bearing", 4, 1e-3)
    all_runs = simulate_measurements(model, truth, nodes, 0.03, run_generators(7, range(5)))
    alone = simulate_measurements(model, truth, nodes, 0.03, run_generators(7, [3]))
    np.testing.assert_array_equal(all_runs[3], alone[0])
    assert np.all(np.abs(all_runs) <= np.pi)
    # The noise has the requested spread (SE of a sd estimate from 5 x 50 x 4 draws is ~3%; allow 4 SE).
    resid = (all_runs - model.measure(truth, nodes) + np.pi) % (2 * np.pi) - np.pi
    assert np.std(resid) == pytest.approx(0.03, rel=0.15)


def test_dropouts_and_lab_truth_shapes():
    sc = load_flock_scenario("dillard-lab-tdoa")
    t = epoch_times(sc.dt_s, 2.0)
    rngs = run_generators(1, range(3))
    truth = scenario_truth(sc, t, rngs, 3)
    assert truth.shape == (3, t.size, 6)
    np.testing.assert_allclose(truth[:, 0, :2], np.tile(sc.target.start_m, (3, 1)), atol=0.01)
    model = FlockSensorModel.build("tdoa", 3, 1e-3)
    z = simulate_measurements(model, truth, scenario_nodes(sc, t), 1e-3, rngs, dropout_probability=0.5)
    assert 0.4 < np.isnan(z).mean() < 0.6
    with pytest.raises(ConfigError, match="dt"):
        epoch_times(0.0, 1.0)


def test_shipped_example_recordings_are_the_synthesized_ones(tmp_path):
    from oceanloc.io.wav import example_recordings, read_wav
    from oceanloc.sim.flock import EXAMPLE_DELAY_S, write_example_recordings

    shipped = example_recordings()
    made = write_example_recordings(tmp_path)
    for ours, theirs in zip(made, shipped, strict=True):
        a, b = read_wav(ours), read_wav(theirs)
        assert a.sample_rate_hz == b.sample_rate_hz == 16000 and a.sample_format == "int16"
        np.testing.assert_allclose(a.samples, b.samples, atol=2.0**-15)  # within one LSB
    assert sum(p.stat().st_size for p in shipped) < 200_000
    assert EXAMPLE_DELAY_S == 1.2345e-3
