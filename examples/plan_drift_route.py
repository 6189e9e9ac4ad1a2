"""Plan an energy-aware drift route in an analytic current (AquaQuad thesis IV.B-C).

``dillard-drift-continuous`` is the thesis' vortex as its analytic formula (Appendix C, RK4) on a 10 km
square with two rectangular islands. ``problem_from_scenario`` builds the planning problem; two planners,
each ``plan(problem, rng, budget) -> result``, are made by name: oceanloc's drift/hop lattice planner and
the thesis' DR-RRT* (single solution). Prints each plan's flight energy (IV.14) against flying straight to
the goal, the distance flown and the compute time.
"""

import numpy as np

from oceanloc.config.drift import load_drift_scenario, problem_from_scenario
from oceanloc.planning.drift_rrt import make_planner

scenario = load_drift_scenario("dillard-drift-continuous")
problem = problem_from_scenario(scenario)
start, goal = problem.start_m, problem.goal_m
print(f"{scenario.name}: start ({start[0]:.0f}, {start[1]:.0f}) m, goal ({goal[0]:.0f}, {goal[1]:.0f}) m")

for name in ("oceanloc", "thesis-single"):
    result = make_planner(name)(problem, np.random.default_rng(scenario.seed))
    path = result.path
    saving = 100.0 * (1.0 - result.flight_energy_wh / result.direct_flight_wh)
    legs_m = np.linalg.norm(np.diff(path.points_m, axis=0), axis=1)
    flown_m = float(legs_m[path.flight].sum())
    print(
        f"{name:>13}: {result.status.name}, flight energy {result.flight_energy_wh:.2f} Wh "
        f"(direct flight {result.direct_flight_wh:.2f} Wh, saving {saving:.1f} %), {flown_m:.0f} m flown, "
        f"{path.times_s[-1] / 3600:.1f} h to the goal, computed in {result.compute_s:.2f} s"
    )
