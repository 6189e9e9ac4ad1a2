"""HDOP (AquaQuad thesis eqs. IV.6, IV.9, IV.10, IV.12, IV.13)."""

import numpy as np
import pytest

from oceanloc.planning.dop import hdop, position_jacobian


def _ring(n, radius, phase=0.0):
    a = phase + 2 * np.pi * np.arange(n) / n
    return radius * np.stack([np.cos(a), np.sin(a)], axis=-1)


@pytest.mark.parametrize("n", [3, 4, 8])
def test_even_ring_closed_forms(n):
    # Evenly spaced nodes: H^T H = (n / 2) I for ranges, (n / (2 r^2)) I for bearings.
    assert hdop(_ring(n, 250.0), np.zeros(2), "range", 0.5) == pytest.approx(2 * 0.5 / np.sqrt(n))
    assert hdop(_ring(n, 250.0), np.zeros(2), "bearing", 0.01) == pytest.approx(2 * 250 * 0.01 / np.sqrt(n))


def test_two_node_closed_forms_eq_iv10_iv12():
    rng = np.random.default_rng(0)
    for _ in range(20):
        r1, r2 = rng.uniform(10, 1000, 2)
        t1, t2 = rng.uniform(-np.pi, np.pi, 2)
        nodes = np.array([[r1 * np.cos(t1), r1 * np.sin(t1)], [r2 * np.cos(t2), r2 * np.sin(t2)]])
        s = abs(np.sin(t1 - t2))
        assert hdop(nodes, [0, 0], "bearing", 0.02) == pytest.approx(0.02 * np.hypot(r1, r2) / s, rel=1e-9)
        assert hdop(nodes, [0, 0], "range", 3.0) == pytest.approx(3.0 * np.sqrt(2) / s, rel=1e-9)


@pytest.mark.parametrize("kind", ["bearing", "range", "tdoa"])
def test_matches_dense_linear_algebra_batched(kind):
    rng = np.random.default_rng(3)
    nodes = rng.uniform(-500, 500, (200, 5, 2))
    target = rng.uniform(-100, 100, (200, 2))
    sigma = rng.uniform(0.5, 2.0, (200, 10 if kind == "tdoa" else 5))
    got = hdop(nodes, target, kind, sigma, sound_speed_mps=1490.0)
    H = position_jacobian(nodes, target, kind, sound_speed_mps=1490.0)
    info = np.einsum("bmi,bm,bmj->bij", H, sigma**-2, H)
    ref = np.sqrt(np.trace(np.linalg.inv(info), axis1=1, axis2=2))
    np.testing.assert_allclose(got, ref, rtol=1e-9)


def test_singular_geometries_are_infinite():
    line = np.array([[100.0, 0.0], [200.0, 0.0], [-300.0, 0.0]])
    assert np.isinf(hdop(line, [0.0, 0.0], "bearing"))
    assert np.isinf(hdop(line, [0.0, 0.0], "range"))
    # TDOA, Fig. 32: a third node on the line of bearing of node 1 leaves one independent row.
    nodes = np.array([[100.0, 0.0], [0.0, 100.0], [300.0, 0.0]])
    assert np.isinf(hdop(nodes, [0.0, 0.0], "tdoa"))
    nodes[2] = [0.0, -300.0]
    assert np.isfinite(hdop(nodes, [0.0, 0.0], "tdoa"))


def test_missing_node_by_infinite_sigma():
    nodes = _ring(4, 100.0)
    sigma = np.array([1.0, 1.0, 1.0, np.inf])
    assert hdop(nodes, [0, 0], "range", sigma) == pytest.approx(hdop(nodes[:3], [0, 0], "range", 1.0))


def test_broadcast_grid_of_candidate_positions():
    fixed = np.array([[100.0, 0.0], [0.0, 100.0]])
    xs = np.linspace(-200, 200, 7)
    cand = np.stack(np.meshgrid(xs, xs, indexing="ij"), axis=-1)  # (7, 7, 2)
    nodes = np.concatenate([np.broadcast_to(fixed, (7, 7, 2, 2)), cand[:, :, None]], axis=2)
    grid = hdop(nodes, np.zeros(2), "bearing")
    assert grid.shape == (7, 7)
    assert grid[2, 5] == pytest.approx(hdop(nodes[2, 5], np.zeros(2), "bearing"))


def test_unknown_kind():
    with pytest.raises(ValueError, match="bearing, range, tdoa"):
        hdop(_ring(3, 1.0), [0, 0], "doppler")
