import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oceanloc.models.energy import EnergyBudget
from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.nearest import GrowingNearest
from oceanloc.planning.drift_rrt.objective import HdopTerm, ThesisCost, bearing_hdop


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 400), st.integers(1, 8), st.integers(0, 2**31 - 1))
def test_growing_nearest_equals_brute_force(n, k, seed):
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-100, 100, size=(n, 2))
    index = GrowingNearest(capacity=4, rebuild_every=16)  # grows its storage and rebuilds often
    for i, (x, y) in enumerate(pts):
        index.add(float(x), float(y))
        if i % 37 == 0 or i == n - 1:
            q = rng.uniform(-100, 100, 2)
            d, _idx = index.query(float(q[0]), float(q[1]), k, exclude=i)
            brute = np.linalg.norm(pts[: i + 1] - q, axis=1)
            brute[i] = np.inf
            order = np.argsort(brute, kind="stable")[: min(k, i)]
            np.testing.assert_allclose(d, brute[order])


def test_bearing_hdop_matches_the_matrix_formula():
    rng = np.random.default_rng(0)
    nodes = rng.uniform(-5000, 5000, size=(20, 4, 2))
    target = rng.uniform(-1000, 1000, size=(20, 2))
    got = bearing_hdop(nodes, target)
    for b in range(20):
        d = target[b] - nodes[b]
        r2 = np.sum(d * d, axis=1)
        h = np.column_stack([-d[:, 1] / r2, d[:, 0] / r2])
        assert got[b] == pytest.approx(np.sqrt(np.trace(np.linalg.inv(h.T @ h))), rel=1e-9)
    collinear = np.array([[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]])
    assert np.isinf(bearing_hdop(collinear, np.array([[5.0, 0.0]])))[0]


def test_hdop_term_takes_an_injected_function():
    calls = []

    def fake(nodes, target):
        calls.append((nodes.shape, target.shape))
        return nodes[..., 0, 0]

    term = HdopTerm(others_m=[[1.0, 2.0], [3.0, 4.0]], target_m=[0.0, 0.0], hdop_fn=fake)
    out = term(np.array([[10.0, 0.0], [20.0, 0.0], [30.0, 0.0]]))
    assert out.tolist() == [10.0, 20.0, 30.0]
    assert calls == [((3, 3, 2), (3, 2))]


def test_thesis_cost_terms():
    c = ThesisCost()
    # Table 3 gains; a drift step at the goal with zero HDOP earns -K4 dt = -0.3.
    assert float(c.drift_cost(c.position_cost(0.0, 0.0))) == pytest.approx(-0.005 * 60)
    assert float(c.position_cost(9000.0, c.distance_max_m)) == pytest.approx(0.045)
    assert float(c.hop_cost(0.5)) == pytest.approx(0.475)


def _zigzag():
    pts = np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [20.0, 30.0], [60.0, 30.0], [70.0, 30.0]])
    flight = np.array([False, False, True, True, False])
    times = np.array([0.0, 60.0, 120.0, 123.0, 127.0, 187.0])
    return DriftPath(points_m=pts, times_s=times, flight=flight)


def test_path_flights_hops_and_merging():
    p = _zigzag()
    assert p.flight_distance_m == pytest.approx(70.0)
    hops = p.hops_m()
    assert hops.shape == (2, 2, 2)
    merged = p.merged()
    assert merged.n_points == 5 and merged.hops_m().shape == (1, 2, 2)
    assert merged.flight_distance_m == pytest.approx(50.0)  # straight from (20, 0) to (60, 30)
    assert merged.drift_time_s == pytest.approx(p.drift_time_s)


def test_path_energy_account():
    p = _zigzag()
    b = EnergyBudget()
    e = p.energy(b)
    assert e.flight_wh == pytest.approx(70.0 * b.flight_wh_per_m)
    assert e.solar_wh == pytest.approx(187.0 / 3600.0 * 400.0 / 24.0)
    assert e.net_wh == pytest.approx(e.solar_wh - e.flight_wh - e.loads_wh)
    np.testing.assert_allclose(p.position_at([0.0, 30.0, 187.0]), [[0.0, 0.0], [5.0, 0.0], [70.0, 30.0]])


def test_path_from_segments_times():
    segs = [
        (np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]), False),
        (np.array([[2.0, 0.0], [2.0, 10.0]]), True),
    ]
    p = DriftPath.from_segments(segs, t0_s=100.0, dt_s=60.0, flight_speed_mps=5.0)
    np.testing.assert_allclose(p.times_s, [100.0, 160.0, 220.0, 222.0])
    assert p.flight.tolist() == [False, False, True]
    with pytest.raises(ValueError):
        DriftPath(points_m=np.zeros((3, 2)), times_s=np.zeros(3), flight=np.zeros(1, dtype=bool))


def test_fast_cell_rollout_is_identical_to_the_generic_one(monkeypatch):
    from oceanloc.planning.drift_rrt import propagation
    from oceanloc.reproduce.dillard_drrt import thesis_problem

    problem = thesis_problem()
    rng = np.random.default_rng(0)
    pts = np.vstack(
        [rng.uniform(-5000, 5000, size=(500, 2)), [[5000.0, 0.0], [-4000.0, -3000.0], [-4000.0, 4000.0]]]
    )

    def roll():
        return problem.propagator.rollout(
            problem.space, pts, 400, goal_m=problem.goal_m, goal_tolerance_m=100.0, stride=3
        )

    assert propagation._CellStepper.build(problem.propagator, problem.space) is not None
    fast = roll()
    monkeypatch.setattr(propagation._CellStepper, "build", classmethod(lambda cls, prop, space: None))
    generic = roll()
    for name in ("samples_m", "goal_distance_m", "goal_step", "reaches_goal", "closest_m", "end_step"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(generic, name))


def test_one_planner_name_parser_for_files_commands_and_the_factory():
    from oceanloc.errors import ConfigError
    from oceanloc.planning.drift_rrt.planner import PLANNER_NAMES, make_planner, parse_planner_name

    assert parse_planner_name(" OceanLoc ") == "oceanloc"
    assert PLANNER_NAMES == ("thesis-single", "thesis-optimality-seeking", "oceanloc")
    with pytest.raises(ConfigError, match=r"--planner must be one of thesis-single, .*got 'rrt'"):
        parse_planner_name("rrt", "--planner")
    with pytest.raises(ConfigError, match="planner must be one of"):
        make_planner("rrt")
