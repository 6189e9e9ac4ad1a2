"""Drift planning in time-varying currents: every leg drifts from its own start time (issue 11, section 4).

The reported flight energy of a plan must equal a step-by-step re-simulation of the plan in the same
field (:func:`resimulate_plan`), for a periodic analytic field and for a gridded product with a time axis.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from oceanloc.models.currents import DoubleGyreCurrent, GridCurrent, UniformCurrent, is_steady
from oceanloc.models.energy import EnergyBudget
from oceanloc.models.obstacles import ObstacleMap
from oceanloc.planning.drift_rrt.lattice import LatticeOptions, plan_lattice
from oceanloc.planning.drift_rrt.objective import HdopTerm
from oceanloc.planning.drift_rrt.problem import DriftProblem, PlanBudget, PlanStatus
from oceanloc.planning.drift_rrt.propagation import DriftPropagator
from oceanloc.planning.drift_rrt.resimulate import resimulate_plan
from oceanloc.planning.drift_rrt.space import DriftSpace
from oceanloc.planning.drift_rrt.thesis import ThesisOptions, plan_thesis

PERIOD_S = 6 * 3600.0
FAST = LatticeOptions(spacing_m=800.0, stride=4, refine_rounds=0, random_offset=False)


def gyre_problem(t0_s: float = 0.0, epsilon: float = 0.5) -> DriftProblem:
    """A 10 km x 5 km double gyre whose dividing line swings with a 6 h period."""
    field = DoubleGyreCurrent(
        length_m=5000.0, amplitude_mps=0.5, epsilon=epsilon, omega_rad_s=2 * math.pi / PERIOD_S
    )
    return DriftProblem(
        space=DriftSpace(obstacles=ObstacleMap(bounds_m=field.bounds_m)),
        propagator=DriftPropagator(field=field, dt_s=120.0, method="euler"),
        start_m=np.array([1000.0, 1000.0]),
        goal_m=np.array([9000.0, 4000.0]),
        goal_tolerance_m=150.0,
        energy=EnergyBudget(),
        hdop=HdopTerm(others_m=[[0.0, 0.0], [10_000.0, 0.0], [0.0, 5000.0]], target_m=[9100.0, 3900.0]),
        horizon_s=4 * 3600.0,
        t0_s=t0_s,
    )


def test_steadiness_of_the_fields():
    assert is_steady(UniformCurrent(velocity_mps=(0.1, 0.0)))
    assert is_steady(DoubleGyreCurrent(epsilon=0.0))
    assert not is_steady(DoubleGyreCurrent(epsilon=0.25))
    grid = dict(x_m=[0.0, 1.0], y_m=[0.0, 1.0])
    assert is_steady(GridCurrent(**grid, u_mps=np.zeros((1, 2, 2)), v_mps=np.zeros((1, 2, 2))))
    assert not is_steady(
        GridCurrent(**grid, u_mps=np.zeros((2, 2, 2)), v_mps=np.zeros((2, 2, 2)), time_s=[0.0, 60.0])
    )


@pytest.mark.parametrize("t0_s", [0.0, 0.25 * PERIOD_S, 0.6 * PERIOD_S])
def test_lattice_energy_equals_the_resimulation_in_a_periodic_gyre(t0_s):
    problem = gyre_problem(t0_s)
    result = plan_lattice(problem, np.random.default_rng(0), None, FAST)
    assert result.status is PlanStatus.EXACT
    flown = resimulate_plan(problem, result.path)
    assert flown.reaches_goal and not flown.blocked
    assert flown.max_deviation_m == pytest.approx(0.0, abs=1e-6)
    assert result.flight_energy_wh == pytest.approx(flown.flight_energy_wh, rel=1e-12, abs=1e-12)
    assert result.path.times_s[0] == t0_s
    assert flown.arrival_s == pytest.approx(float(result.path.times_s[-1]), abs=1e-6)


def test_a_plan_flown_at_another_time_costs_something_else():
    """The re-simulation sees the clock: the plan for a quarter period flown at 0 drifts elsewhere."""
    result = plan_lattice(gyre_problem(0.25 * PERIOD_S), np.random.default_rng(0), None, FAST)
    assert not result.direct_chosen and not result.path.flight.all()
    early = resimulate_plan(gyre_problem(0.0), result.path)
    assert early.max_deviation_m > 200.0


def test_thesis_planner_energy_equals_the_resimulation_in_a_periodic_gyre():
    problem = gyre_problem(0.25 * PERIOD_S)
    for mode in ("single", "optimality-seeking"):
        result = plan_thesis(
            problem, np.random.default_rng(3), PlanBudget(max_iterations=3000), ThesisOptions(mode=mode)
        )
        assert result.path is not None
        flown = resimulate_plan(problem, result.path)
        assert flown.max_deviation_m == pytest.approx(0.0, abs=1e-6)
        assert result.flight_energy_wh == pytest.approx(flown.flight_energy_wh, rel=1e-12, abs=1e-12)
        if result.status is PlanStatus.EXACT:
            assert flown.reaches_goal


def test_steady_field_plans_are_unchanged_by_the_start_time():
    steady = gyre_problem(0.0, epsilon=0.0)
    a = plan_lattice(steady, np.random.default_rng(0), None, FAST)
    b = plan_lattice(dataclasses.replace(steady, t0_s=5000.0), np.random.default_rng(0), None, FAST)
    assert a.flight_energy_wh == pytest.approx(b.flight_energy_wh, rel=1e-12)
    assert resimulate_plan(steady, a.path).flight_energy_wh == pytest.approx(a.flight_energy_wh, rel=1e-12)


# -- a gridded product with a time axis, through the scenario loader ------------------------------------

NC_TOML = """
[scenario]
name = "tidal"
[currents]
kind = "netcdf"
path = "tidal.nc"
[drift]
integrator = "euler"
dt_s = 120.0
horizon_h = {horizon_h}
[route]
start_m = [500.0, 500.0]
goal_m = [5000.0, 3000.0]
goal_tolerance_m = 150.0
{start}
[vehicle]
flight_legs = "any"
"""


def write_tidal_netcdf(path) -> None:
    """A 6 km x 4 km current turning once every 8 h (0.4 m/s), hourly slices over 10 h from 06:00."""
    xr = pytest.importorskip("xarray")
    x = np.arange(0.0, 6001.0, 500.0)
    y = np.arange(0.0, 4001.0, 500.0)
    hours = np.arange(11)
    phase = 2 * np.pi * hours / 8.0
    u = np.broadcast_to((0.4 * np.cos(phase))[:, None, None], (hours.size, y.size, x.size))
    v = np.broadcast_to((0.4 * np.sin(phase))[:, None, None], (hours.size, y.size, x.size))
    times = np.datetime64("2024-03-01T06:00:00", "s") + hours * np.timedelta64(3600, "s")
    ms = {"units": "m s-1"}
    ds = xr.Dataset(
        {
            "uo": (
                ("time", "y", "x"),
                u.astype(np.float32),
                {"standard_name": "eastward_sea_water_velocity", **ms},
            ),
            "vo": (
                ("time", "y", "x"),
                v.astype(np.float32),
                {"standard_name": "northward_sea_water_velocity", **ms},
            ),
        },
        coords={
            "time": ("time", times, {"standard_name": "time"}),
            "y": ("y", y, {"standard_name": "projection_y_coordinate", "units": "m", "axis": "Y"}),
            "x": ("x", x, {"standard_name": "projection_x_coordinate", "units": "m", "axis": "X"}),
        },
    )
    ds.to_netcdf(path)


def _tidal_scenario(tmp_path, start: str, horizon_h: float = 4.0):
    from oceanloc.config.drift import load_drift_scenario

    write_tidal_netcdf(tmp_path / "tidal.nc")
    path = tmp_path / "tidal.toml"
    path.write_text(NC_TOML.format(start=start, horizon_h=horizon_h))
    return load_drift_scenario(path)


def test_netcdf_with_a_time_axis_plans_in_time_from_an_iso_start(tmp_path):
    from oceanloc.config.drift import problem_from_scenario

    sc = _tidal_scenario(tmp_path, 'start_time = "2024-03-01T08:00:00"')
    problem = problem_from_scenario(sc)
    assert problem.t0_s == 7200.0  # two hours after the first slice
    assert not is_steady(problem.propagator.field)
    result = plan_lattice(
        problem, np.random.default_rng(0), None, LatticeOptions(spacing_m=500.0, refine_rounds=0)
    )
    assert result.status is PlanStatus.EXACT
    flown = resimulate_plan(problem, result.path)
    assert flown.reaches_goal
    assert flown.max_deviation_m == pytest.approx(0.0, abs=1e-6)
    assert result.flight_energy_wh == pytest.approx(flown.flight_energy_wh, rel=1e-12, abs=1e-12)
    # A start given in seconds is the same clock.
    same = problem_from_scenario(_tidal_scenario(tmp_path, "start_time_s = 7200.0"))
    assert same.t0_s == problem.t0_s


@pytest.mark.parametrize(
    ("start", "horizon_h", "reason"),
    [
        ('start_time = "2024-03-01T05:00:00"', 4.0, "must lie within the current's time axis, [0, 36000) s"),
        ("start_time_s = 36000.0", 4.0, "must lie within the current's time axis"),
        ("start_time_s = 0.0", 12.0, "shorten [drift] horizon_h to at most 10 h"),
        ('start_time = "yesterday"', 4.0, "must be an ISO 8601 time"),
        ('start_time = "2024-03-01T08:00:00"\nstart_time_s = 1.0', 4.0, "not both"),
    ],
)
def test_netcdf_start_time_errors_name_the_field_and_the_range(tmp_path, start, horizon_h, reason):
    from oceanloc.errors import ConfigError

    with pytest.raises(ConfigError) as err:
        _tidal_scenario(tmp_path, start, horizon_h)
    assert "[route]" in str(err.value) and "tidal.toml" in str(err.value)
    assert reason in str(err.value)


GYRE_TOML = """
[scenario]
name = "gyre"
[currents]
kind = "double-gyre"
length_m = 5000.0
epsilon = 0.5
period_h = 6.0
[drift]
integrator = "euler"
dt_s = 120.0
horizon_h = 4.0
[route]
start_m = [1000.0, 1000.0]
goal_m = [9000.0, 4000.0]
{start}
"""


@pytest.mark.parametrize(
    ("start", "expected"),
    [("start_time_s = 5400.0", 5400.0), ("", 0.0)],
)
def test_periodic_scenario_start_time(tmp_path, start, expected):
    from oceanloc.config.drift import load_drift_scenario, problem_from_scenario

    path = tmp_path / "gyre.toml"
    path.write_text(GYRE_TOML.format(start=start))
    assert problem_from_scenario(load_drift_scenario(path)).t0_s == expected


@pytest.mark.parametrize(
    ("start", "reason"),
    [
        ("start_time_s = 1e300", "[route] field 'start_time_s': must be <= 10000000000.0"),
        ('start_time = "2024-01-01T00:00:00"', "needs a current product with a time axis"),
    ],
)
def test_periodic_scenario_start_time_errors(tmp_path, start, reason):
    from oceanloc.config.drift import load_drift_scenario
    from oceanloc.errors import ConfigError

    path = tmp_path / "gyre.toml"
    path.write_text(GYRE_TOML.format(start=start))
    with pytest.raises(ConfigError, match=None) as err:
        load_drift_scenario(path)
    assert reason in str(err.value)


def test_a_problem_needs_a_finite_start_time():
    from oceanloc.errors import ConfigError

    with pytest.raises(ConfigError, match="start time t0_s must be finite"):
        gyre_problem(float("nan"))
