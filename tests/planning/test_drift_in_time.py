"""The drift planner in time (issue 26): exact checks against Zermelo's problem, objectives, the frozen field.

- Zermelo's navigation problem (a vehicle at speed F through water that moves): in a uniform current that
  changes in time the fastest path holds one heading and arrives at the first T with
  ``|goal - start - W(t0, t0 + T)| = F T`` (W the current's displacement); in a linear shear ``u = k y`` the
  optimal heading obeys ``tan(theta) = tan(theta0) - k t`` and the track has closed forms in ``theta``
  (Bryson and Ho, Applied Optimal Control, section 2.7). The planner's time is within 0.5 % of both.
- Energy with a deadline, the time objective, and a vehicle through the water: every reported figure is
  the plan's cost flown exactly.
- In a periodic double gyre the plan made in time costs less than the frozen-field plan re-flown in time.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from oceanloc.models.currents import DoubleGyreCurrent, LinearCurrent, TidalCurrent, UniformCurrent
from oceanloc.models.energy import EnergyBudget
from oceanloc.models.obstacles import ObstacleMap
from oceanloc.models.powered import leg_times_s
from oceanloc.planning.drift_rrt.lattice import LatticeOptions, plan_lattice
from oceanloc.planning.drift_rrt.oceanloc_planner import needs_time, plan_oceanloc
from oceanloc.planning.drift_rrt.problem import DriftProblem, PlanStatus
from oceanloc.planning.drift_rrt.propagation import DriftPropagator
from oceanloc.planning.drift_rrt.resimulate import resimulate_plan
from oceanloc.planning.drift_rrt.space import DriftSpace
from oceanloc.planning.drift_rrt.time_plan import plan_in_time
from oceanloc.planning.drift_rrt.time_values import TimeLatticeOptions

BOAT_SPEED = 1.0
BOAT = EnergyBudget(flight_speed_kn=BOAT_SPEED * 3600.0 / 1852.0, flight_power_w=50.0)
ZERMELO_OPTIONS = TimeLatticeOptions(spacing_m=500.0, slice_s=300.0, stencil_radius=4)


def water_problem(field, start, goal, bounds, *, objective="time", t0_s=0.0, horizon_s=4 * 3600.0, **kw):
    return DriftProblem(
        space=DriftSpace(obstacles=ObstacleMap(bounds_m=bounds)),
        propagator=DriftPropagator(field=field, dt_s=60.0, method="rk4"),
        start_m=np.asarray(start, dtype=float),
        goal_m=np.asarray(goal, dtype=float),
        goal_tolerance_m=1.0,
        energy=BOAT,
        horizon_s=horizon_s,
        t0_s=t0_s,
        objective=objective,
        propulsion="water",
        **kw,
    )


# -- Zermelo: a uniform current that changes in time ----------------------------------------------------


def tidal_arrival_s(field: TidalCurrent, start, goal, t0_s: float) -> float:
    """Zermelo's time in a uniform current: the first root of ``|g - s - W(t0, t0 + T)| - F T``."""
    from scipy.optimize import brentq

    s, g = np.asarray(start, float), np.asarray(goal, float)

    def gap(t: float) -> float:
        return float(np.linalg.norm(g - s - field.displacement_m(t0_s, t0_s + t)) - BOAT_SPEED * t)

    grid = np.linspace(1.0, 4e4, 8001)
    values = np.array([gap(t) for t in grid])
    i = int(np.flatnonzero(values <= 0.0)[0])
    return brentq(gap, grid[i - 1], grid[i], xtol=1e-9)


def test_tidal_displacement_is_the_integral_of_the_current():
    from scipy.integrate import quad

    f = TidalCurrent(mean_mps=(0.1, -0.05), amplitude_mps=(0.4, 0.3), period_s=21_600.0, phase_rad=0.5)
    for i in range(2):
        exact = quad(lambda t, i=i: f.velocity_xy(0.0, 0.0, t)[i], 1000.0, 9000.0, epsabs=1e-10)[0]
        assert f.displacement_m(1000.0, 9000.0)[i] == pytest.approx(exact, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("goal", [(6000.0, 4000.0), (0.0, 7000.0)])
def test_zermelo_uniform_current_changing_in_time(goal):
    field = TidalCurrent(mean_mps=(0.1, 0.0), amplitude_mps=(0.4, 0.3), period_s=21_600.0, phase_rad=0.5)
    exact = tidal_arrival_s(field, (0.0, 0.0), goal, 0.0)
    problem = water_problem(field, (0.0, 0.0), goal, (-4000.0, 10000.0, -4000.0, 10000.0))
    result = plan_in_time(problem, np.random.default_rng(0), None, ZERMELO_OPTIONS)
    assert result.status is PlanStatus.EXACT
    # Exact optimum (to integration error, 1e-4) at most; within 0.5 % of it.
    assert exact * (1 - 1e-4) <= result.cost <= 1.005 * exact
    assert result.cost == pytest.approx(result.path.duration_s, rel=1e-12)


# -- Zermelo: linear shear ------------------------------------------------------------------------------


def _shear_track(k: float, theta0: float, theta: float) -> tuple[float, float]:
    """Position reached from the origin with the optimal heading law in ``u = k y`` (Bryson and Ho 2.7)."""

    def sec(a: float) -> float:
        return 1.0 / math.cos(a)

    def log_sec_tan(a: float) -> float:
        return math.log(sec(a) + math.tan(a))

    f = BOAT_SPEED
    y = (f / k) * (sec(theta0) - sec(theta))
    x = (
        -(f / (2 * k)) * (log_sec_tan(theta) - log_sec_tan(theta0))
        + (f / (2 * k)) * (sec(theta) * math.tan(theta) - sec(theta0) * math.tan(theta0))
        - (f / k) * sec(theta0) * (math.tan(theta) - math.tan(theta0))
    )
    return x, y


def shear_arrival_s(k: float, goal) -> float:
    """Zermelo's time to ``goal`` from the origin in ``u = k y``: solve the closed-form track for the
    initial and final headings; the time is ``(tan theta0 - tan theta_f) / k``."""
    from scipy.optimize import fsolve

    g = np.asarray(goal, dtype=float)
    best = math.inf
    for a in np.linspace(-1.3, 1.3, 14):
        for b in np.linspace(-1.3, 1.3, 14):

            def miss(z: np.ndarray) -> np.ndarray:
                if not (abs(z[0]) < 1.55 and abs(z[1]) < 1.55):
                    return np.array([1e9, 1e9])
                return np.asarray(_shear_track(k, z[0], z[1])) - g

            sol, _, ier, _ = fsolve(miss, [a, b], full_output=True, xtol=1e-13)
            if ier == 1 and np.allclose(miss(sol), 0.0, atol=1e-6):
                t = (math.tan(sol[0]) - math.tan(sol[1])) / k
                if t > 0:
                    best = min(best, t)
    return best


def test_shear_closed_form_agrees_with_integrating_the_optimal_control():
    from scipy.integrate import solve_ivp

    k, theta0 = 1e-4, 0.6
    t_end = 5000.0

    def rhs(t, s):
        theta = math.atan(math.tan(theta0) - k * t)
        return [BOAT_SPEED * math.cos(theta) + k * s[1], BOAT_SPEED * math.sin(theta)]

    sol = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0], rtol=1e-12, atol=1e-9)
    theta_f = math.atan(math.tan(theta0) - k * t_end)
    assert np.allclose(sol.y[:, -1], _shear_track(k, theta0, theta_f), atol=1e-5)


@pytest.mark.parametrize("goal", [(8000.0, 0.0), (6000.0, 3000.0)])
def test_zermelo_linear_shear(goal):
    k = 1e-4
    exact = shear_arrival_s(k, goal)
    field = LinearCurrent(matrix_per_s=((0.0, k), (0.0, 0.0)))
    problem = water_problem(field, (0.0, 0.0), goal, (-2000.0, 12000.0, -4000.0, 6000.0))
    result = plan_in_time(problem, np.random.default_rng(0), None, ZERMELO_OPTIONS)
    assert result.status is PlanStatus.EXACT
    assert exact * (1 - 1e-4) <= result.cost <= 1.005 * exact


# -- water legs -------------------------------------------------------------------------------------------


def test_water_leg_time_in_a_uniform_current_is_the_closed_form():
    """Holding a course across a steady uniform current: ground speed ``w.e + sqrt(F^2 - (w.n)^2)``."""
    w = np.array([0.3, -0.4])
    field = UniformCurrent(velocity_mps=(0.3, -0.4))
    a, b = np.array([0.0, 0.0]), np.array([3000.0, 4000.0])
    e = (b - a) / 5000.0
    n = np.array([-e[1], e[0]])
    ground = w @ e + math.sqrt(BOAT_SPEED**2 - (w @ n) ** 2)
    tau, ok = leg_times_s("water", field, a, b, 0.0, BOAT_SPEED)
    assert bool(ok) and float(tau) == pytest.approx(5000.0 / ground, rel=1e-12)
    tau_air, _ = leg_times_s("air", field, a, b, 0.0, BOAT_SPEED)
    assert float(tau_air) == pytest.approx(5000.0 / BOAT_SPEED)


def test_water_leg_against_a_current_stronger_than_the_vehicle_is_infeasible():
    field = UniformCurrent(velocity_mps=(-1.5, 0.0))
    tau, ok = leg_times_s("water", field, [0.0, 0.0], [1000.0, 0.0], 0.0, BOAT_SPEED)
    assert not bool(ok) and math.isinf(float(tau))


# -- objectives, deadline, exact accounting ---------------------------------------------------------------

PERIOD_S = 6 * 3600.0


def gyre(t0_s: float = 0.0, **kw) -> DriftProblem:
    """Two 5 km gyres (0.5 m/s, eps 0.25, 6 h period), an island on the divide, 0.5 Wh per hour."""
    field = DoubleGyreCurrent(
        length_m=5000.0, amplitude_mps=0.5, epsilon=0.25, omega_rad_s=2 * math.pi / PERIOD_S
    )
    base = dict(
        space=DriftSpace(
            obstacles=ObstacleMap(
                bounds_m=field.bounds_m, rectangles_m=np.array([[4500.0, 5500.0, 2000.0, 3000.0]])
            )
        ),
        propagator=DriftPropagator(field=field, dt_s=300.0, method="rk4"),
        start_m=np.array([1500.0, 4250.0]),
        goal_m=np.array([8000.0, 750.0]),
        goal_tolerance_m=150.0,
        energy=EnergyBudget(),
        horizon_s=12 * 3600.0,
        t0_s=t0_s,
        time_weight_wh_per_h=0.5,
    )
    base.update(kw)
    return DriftProblem(**base)


FAST = TimeLatticeOptions(spacing_m=400.0, slice_s=1800.0)


@pytest.mark.parametrize("t0_s", [0.0, 0.3 * PERIOD_S])
def test_plan_in_time_costs_what_it_reports_and_beats_the_frozen_field(t0_s):
    problem = gyre(t0_s)
    assert needs_time(problem)
    result = plan_in_time(problem, np.random.default_rng(0), None, FAST)
    assert result.status is PlanStatus.EXACT
    flown = resimulate_plan(problem, result.path)
    assert flown.reaches_goal and not flown.blocked
    assert flown.max_deviation_m == pytest.approx(0.0, abs=1e-6)
    assert result.flight_energy_wh == pytest.approx(flown.flight_energy_wh, rel=1e-12, abs=1e-12)
    assert result.cost == pytest.approx(problem.objective_of(flown.path), rel=1e-12)
    frozen = plan_lattice(problem, np.random.default_rng(0), None, LatticeOptions(spacing_m=400.0))
    assert result.cost < problem.objective_of(resimulate_plan(problem, frozen.path).path)


def test_deadline_is_met_and_costs_energy():
    free = plan_in_time(gyre(), np.random.default_rng(0), None, FAST)
    hours = free.path.duration_s / 3600.0
    tight = gyre(max_duration_s=0.5 * hours * 3600.0)
    result = plan_in_time(tight, np.random.default_rng(0), None, FAST)
    assert result.status is PlanStatus.EXACT
    assert result.path.duration_s <= tight.max_duration_s + 1e-6
    assert result.flight_energy_wh >= free.flight_energy_wh - 1e-9
    assert math.isfinite(tight.objective_of(result.path))
    assert math.isinf(tight.objective_of(free.path))


def test_a_deadline_shorter_than_the_direct_flight_fails_honestly():
    problem = gyre(max_duration_s=60.0)  # the goal is 7.4 km away: 12 minutes of flight
    result = plan_oceanloc(problem, np.random.default_rng(0))
    assert result.status is PlanStatus.FAILED and result.path is None
    assert "deadline" in result.message


def test_time_objective_in_the_air_is_the_direct_flight():
    """Flying (10 m/s) beats any current (0.5 m/s): the fastest plan flies straight into the goal disk."""
    problem = gyre(objective="time")
    result = plan_oceanloc(problem, np.random.default_rng(0))
    into_disk_s = (problem.direct_flight_m - problem.goal_tolerance_m) / problem.energy.flight_speed_mps
    assert into_disk_s - 1e-6 <= result.cost <= into_disk_s * 1.001


def test_energy_in_the_water_is_power_times_powered_time():
    field = TidalCurrent(mean_mps=(0.2, 0.0), amplitude_mps=(0.0, 0.3), period_s=21_600.0)
    problem = water_problem(
        field,
        (0.0, 0.0),
        (6000.0, 1000.0),
        (-2000.0, 8000.0, -3000.0, 4000.0),
        objective="energy",
        time_weight_wh_per_h=2.0,
    )
    result = plan_oceanloc(problem, np.random.default_rng(0))
    assert result.status is PlanStatus.EXACT
    flown = resimulate_plan(problem, result.path)
    assert flown.reaches_goal
    assert result.flight_energy_wh == pytest.approx(BOAT.flight_power_w * result.path.flight_time_s / 3600.0)
    assert flown.flight_energy_wh == pytest.approx(result.flight_energy_wh, rel=1e-9)
    # Riding the mean current east costs less than motoring straight at the start time.
    assert result.cost <= problem.objective_of(resimulate_plan(problem, _direct(problem)).path) + 1e-9


def _direct(problem: DriftProblem):
    from oceanloc.planning.drift_rrt.direct import direct_flight_path

    path, _ = direct_flight_path(problem)
    return path


def test_steady_air_problems_keep_the_steady_lattice():
    from tests.planning.drift_fixtures import uniform_problem

    problem = uniform_problem()
    assert not needs_time(problem)
    a = plan_oceanloc(problem, np.random.default_rng(3))
    b = plan_lattice(
        problem,
        np.random.default_rng(3),
        None,
        LatticeOptions(spacing_m=300.0, stride=4, envelope="dense", refine_rounds=1, cloud_half_width=4),
    )
    assert a.flight_energy_wh == b.flight_energy_wh
