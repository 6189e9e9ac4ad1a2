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


def test_map_grid_matches_pointwise_hdop_and_netcdf_round_trip(tmp_path):
    import xarray as xr

    from oceanloc.planning.dop import hdop_map

    fixed = np.array([[100.0, 0.0], [0.0, 100.0]])
    m = hdop_map(fixed, [0.0, 0.0], "tdoa", x_range_m=(-200, 200), y_range_m=(-100, 150), resolution_m=50)
    np.testing.assert_allclose(m.x_m, np.arange(-200, 201, 50))
    np.testing.assert_allclose(m.y_m, np.arange(-100, 151, 50))
    i, j = 3, 1  # y = 50, x = -150
    ref = hdop(np.vstack([fixed, [[-150.0, 50.0]]]), [0.0, 0.0], "tdoa")
    assert m.hdop[i, j] == pytest.approx(ref)
    # The moving node on node 1's line of bearing beyond it (x > 0, y = 0) is singular (Fig. 32).
    assert np.isinf(m.hdop[2, 7]) and m.y_m[2] == 0 and m.x_m[7] == 150
    path = tmp_path / "map.nc"
    m.to_dataset().to_netcdf(path, engine="netcdf4")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        np.testing.assert_allclose(ds["hdop"].values[i, j], ref)
        assert np.isnan(ds["hdop"].values[2, 7])
        assert ds.attrs["measurement"] == "tdoa"


def test_map_rejects_bad_grids():
    from oceanloc.errors import ConfigError
    from oceanloc.planning.dop import hdop_map

    with pytest.raises(ConfigError, match="resolution"):
        hdop_map([[1.0, 0.0]], [0, 0], "range", x_range_m=(0, 1), y_range_m=(0, 1), resolution_m=0)
    with pytest.raises(ConfigError, match="x range"):
        hdop_map([[1.0, 0.0]], [0, 0], "range", x_range_m=(1, 0), y_range_m=(0, 1), resolution_m=0.1)


def test_placement_matches_exhaustive_search_on_small_problems():
    # Three bearing nodes and one TDOA node added to two fixed ones: an exhaustive grid over ranges and
    # bearings (node 1 fixed at bearing 0 by symmetry for the free problem) cannot beat the optimizer.
    from oceanloc.planning.dop import optimize_placement

    rng = np.random.default_rng(0)
    res = optimize_placement(3, "bearing", min_standoff_m=20, max_standoff_m=200, rng=rng, starts=6)
    r = np.linspace(20, 200, 7)
    a = np.radians(np.arange(0, 360, 10))
    r1, r2, r3, a2, a3 = np.meshgrid(r, r, r, a, a, indexing="ij", sparse=False)
    nodes = np.stack(
        [
            np.stack([r1, np.zeros_like(r1)], -1),
            np.stack([r2 * np.cos(a2), r2 * np.sin(a2)], -1),
            np.stack([r3 * np.cos(a3), r3 * np.sin(a3)], -1),
        ],
        axis=-2,
    )
    exhaustive = hdop(nodes, np.zeros(2), "bearing").min()
    assert res.hdop <= exhaustive * (1 + 1e-9)
    assert res.hdop == pytest.approx(2 * 20 / np.sqrt(3), rel=1e-6)  # the even ring at the minimum stand-off
    assert np.all(np.linalg.norm(res.nodes_m, axis=1) >= 20 - 1e-9)

    fixed = np.array([[100.0, 0.0], [0.0, 150.0]])
    one = optimize_placement(
        1, "tdoa", fixed_nodes_m=fixed, min_standoff_m=50, max_standoff_m=300, rng=rng, starts=4
    )
    ang = np.radians(np.arange(0, 360, 0.5))
    cand = np.stack([50 * np.cos(ang), 50 * np.sin(ang)], -1)
    grid = hdop(
        np.concatenate([np.broadcast_to(fixed, (ang.size, 2, 2)), cand[:, None]], axis=1), [0, 0], "tdoa"
    )
    assert one.hdop <= grid.min() * (1 + 1e-9)
    assert one.gap >= -1e-12


def test_placement_reports_ring_gap_and_validates():
    from oceanloc.errors import ConfigError
    from oceanloc.planning.dop import optimize_placement

    rng = np.random.default_rng(1)
    res = optimize_placement(
        2,
        "bearing",
        fixed_nodes_m=[[100.0, 0.0], [0.0, 150.0]],
        min_standoff_m=50,
        max_standoff_m=500,
        rng=rng,
        starts=4,
    )
    assert res.gap > 0.1  # with two nodes already in place the symmetric ring is clearly suboptimal
    assert res.start_hdop.shape == (4,) and res.start_nodes_m.shape == (4, 2, 2)
    with pytest.raises(ConfigError, match="stand-off"):
        optimize_placement(3, "range", min_standoff_m=10, max_standoff_m=5, rng=rng)
    with pytest.raises(ConfigError, match="at least 3"):
        optimize_placement(2, "tdoa", min_standoff_m=1, max_standoff_m=5, rng=rng)


def test_placement_bearings_are_clockwise_from_north():
    from oceanloc.planning.dop import optimize_placement

    res = optimize_placement(
        4,
        "range",
        target_m=(5.0, -5.0),
        min_standoff_m=10,
        max_standoff_m=10,
        starts=1,
        rng=np.random.default_rng(1),
    )
    ranges, bearings = res.ranges_bearings()
    np.testing.assert_allclose(ranges, 10.0)
    d = res.nodes_m - res.target_m
    np.testing.assert_allclose(d[:, 0], ranges * np.sin(bearings), atol=1e-9)  # east = r sin(bearing)
    np.testing.assert_allclose(d[:, 1], ranges * np.cos(bearings), atol=1e-9)  # north = r cos(bearing)
    record = res.to_record()
    assert all(0 <= b < 360 for b in record["node_bearing_deg"])
    assert record["bearing_convention"].startswith("degrees clockwise from north")
