"""Drift planning: speed and energy of DR-RRT* and oceanloc's planner on the thesis scenario.

Prints, beside the targets and the thesis' MATLAB figures (Table 4, Core i7-2600):
- median single-solution DR-RRT* compute time (target <= 50 ms; thesis 190 ms);
- median time of a 25,000-iteration optimality-seeking run (target <= 1 s; thesis 4964 ms);
- oceanloc planner: success rate, mean saving over direct flight (target >= 50 % with 100 % success, or within
  3 % of the best achievable), ratio to the best achievable energy, median compute (target <= 100 ms);
- OMPL RRT* against oceanloc on the like-for-like geometric problem (no current, obstacles are no-fly zones,
  same bounds): path length and time, with the exact shortest path from the visibility graph.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from oceanloc.models.currents import UniformCurrent
from oceanloc.planning.drift_rrt.oceanloc_planner import plan_oceanloc
from oceanloc.planning.drift_rrt.problem import DriftProblem, PlanBudget
from oceanloc.planning.drift_rrt.propagation import DriftPropagator
from oceanloc.planning.drift_rrt.reference import best_achievable
from oceanloc.planning.drift_rrt.space import DriftSpace
from oceanloc.planning.drift_rrt.thesis import ThesisOptions, plan_thesis
from oceanloc.reproduce.dillard_drrt import THESIS_TABLE4, thesis_problem

SINGLE_RUNS = 1000
OPTIMALITY_RUNS = 7
OCEANLOC_RUNS = 100


def _line(label: str, measured: str, target: str, thesis: str = "") -> None:
    print(f"{label:<46} {measured:>22}   target {target:<16} {thesis}")


def _shortest_path_visibility(problem: DriftProblem) -> float:
    """Exact shortest obstacle-free path among rectangles: Dijkstra on the visibility graph of corners."""
    from scipy.sparse.csgraph import dijkstra

    eps = 1e-6
    nodes = [problem.start_m, problem.goal_m]
    for a, b, c, d in problem.space.obstacles.rectangles_m:
        nodes += [
            np.array(p)
            for p in ((a - eps, c - eps), (b + eps, c - eps), (b + eps, d + eps), (a - eps, d + eps))
        ]
    pts = np.array(nodes)
    n = pts.shape[0]
    a = np.broadcast_to(pts[:, None, :], (n, n, 2))
    b = np.broadcast_to(pts[None, :, :], (n, n, 2))
    free = problem.space.obstacles.segment_free(a, b)
    w = np.where(free, np.linalg.norm(a - b, axis=-1), 0.0)
    return float(dijkstra(w, indices=0)[1])


def _ompl_rrtstar(problem: DriftProblem, seconds: float, seed: int) -> tuple[float, float]:
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    if hasattr(ou, "setLogLevel"):
        ou.setLogLevel(ou.LogLevel.LOG_NONE)
    if hasattr(ou, "RNG"):
        ou.RNG.setSeed(seed)
    x0, x1, y0, y1 = problem.space.bounds_m
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0, x0)
    bounds.setHigh(0, x1)
    bounds.setLow(1, y0)
    bounds.setHigh(1, y1)
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    valid = problem.space.is_valid_xy
    ss.setStateValidityChecker(lambda s: bool(valid(float(s[0]), float(s[1]))))
    # Check motions every 10 m (OMPL's discretized motion validation; ours is exact).
    ss.getSpaceInformation().setStateValidityCheckingResolution(10.0 / space.getMaximumExtent())
    start = space.allocState()
    goal = space.allocState()
    start[0], start[1] = (float(v) for v in problem.start_m)
    goal[0], goal[1] = (float(v) for v in problem.goal_m)
    ss.setStartAndGoalStates(start, goal, problem.goal_tolerance_m)
    ss.setPlanner(og.RRTstar(ss.getSpaceInformation()))
    tic = time.perf_counter()
    solved = ss.solve(seconds)
    elapsed = time.perf_counter() - tic
    if not solved or not ss.haveExactSolutionPath():
        return float("nan"), elapsed
    return float(ss.getSolutionPath().length()), elapsed


def main() -> None:
    problem = thesis_problem()
    direct = problem.direct_flight_wh
    print(f"thesis scenario, fixed field; {problem.energy.convention}; direct flight {direct:.2f} Wh")

    single = [
        plan_thesis(problem, np.random.default_rng(s), options=ThesisOptions(mode="single"))
        for s in range(SINGLE_RUNS)
    ]
    t_single = np.median([r.compute_s for r in single])
    e_single = np.mean([r.flight_energy_wh for r in single if r.success])
    _line(
        f"DR-RRT* single solution, median of {SINGLE_RUNS}",
        f"{1e3 * t_single:.1f} ms",
        "<= 50 ms",
        f"thesis {1e3 * THESIS_TABLE4['thesis-single']['compute_s_mean']:.0f} ms (mean)",
    )
    _line(
        "  success, mean energy, saving",
        f"{np.mean([r.success for r in single]):.0%}, {e_single:.2f} Wh, {1 - e_single / direct:.1%}",
        "-",
        "thesis 38.69 Wh, 22%",
    )

    opt = [
        plan_thesis(
            problem,
            np.random.default_rng(s),
            PlanBudget(max_iterations=25_000),
            ThesisOptions(mode="optimality-seeking"),
        )
        for s in range(OPTIMALITY_RUNS)
    ]
    t_opt = np.median([r.compute_s for r in opt])
    _line(
        f"DR-RRT* 25,000 iterations, median of {OPTIMALITY_RUNS}",
        f"{t_opt:.3f} s",
        "<= 1 s",
        f"thesis {THESIS_TABLE4['thesis-optimality-seeking']['compute_s_mean']:.3f} s (mean)",
    )
    e_opt = np.mean([r.flight_energy_wh for r in opt if r.success])
    _line("  mean energy, saving", f"{e_opt:.2f} Wh, {1 - e_opt / direct:.1%}", "-", "thesis 36.26 Wh, 27%")

    tic = time.perf_counter()
    ref = best_achievable(problem)
    best = ref.flight_energy_wh
    _line(
        "best achievable (50 m lattice reference)",
        f"{best:.2f} Wh, {1 - best / direct:.1%}",
        "-",
        f"({time.perf_counter() - tic:.0f} s to compute)",
    )

    ours = [plan_oceanloc(problem, np.random.default_rng(s)) for s in range(OCEANLOC_RUNS)]
    ok = np.array([r.success for r in ours])
    e = np.array([r.flight_energy_wh for r in ours])[ok]
    saving = float(np.mean(1 - e / direct))
    _line(f"oceanloc planner, {OCEANLOC_RUNS} runs: success", f"{ok.mean():.0%}", "100 %")
    _line("  mean saving over direct flight", f"{saving:.1%}", ">= 50 %")
    _line("  mean energy / best achievable", f"{np.mean(e) / best:.3f}", "<= 1.03 if < 50 %")
    _line("  median compute", f"{1e3 * np.median([r.compute_s for r in ours]):.1f} ms", "<= 100 ms")

    geometric = dataclasses.replace(
        problem,
        space=DriftSpace(obstacles=problem.space.obstacles, flights_avoid_obstacles=True),
        propagator=DriftPropagator(field=UniformCurrent(velocity_mps=(0.0, 0.0)), dt_s=60.0, method="euler"),
        horizon_s=60.0,
    )
    # Into the goal disk: the last straight leg of the shortest path to the goal, shortened by the tolerance.
    exact = _shortest_path_visibility(geometric) - geometric.goal_tolerance_m
    print(
        "\nlike-for-like geometric problem (no current, obstacles are no-fly zones): "
        f"exact shortest path into the {geometric.goal_tolerance_m:g} m goal disk {exact:.1f} m"
    )
    geo = [plan_oceanloc(geometric, np.random.default_rng(s)) for s in range(10)]
    lengths = [r.path.flight_distance_m for r in geo if r.success and r.path is not None]
    _line(
        "  oceanloc lattice, median of 10",
        f"{np.median(lengths):.1f} m ({np.median(lengths) / exact - 1:+.2%})",
        "-",
        f"{1e3 * np.median([r.compute_s for r in geo]):.0f} ms",
    )
    try:
        import ompl  # noqa: F401
    except ImportError:
        print("  OMPL: not installed (pip install ompl; wheels exist for Linux, Python 3.11-3.13)")
        return
    for seconds in (0.1, 1.0):
        runs = [_ompl_rrtstar(geometric, seconds, s + 1) for s in range(5)]
        length = np.nanmedian([r[0] for r in runs])
        _line(
            f"  OMPL RRT* {seconds:g} s budget, median of 5",
            f"{length:.1f} m ({length / exact - 1:+.2%})",
            "-",
            f"{1e3 * np.median([r[1] for r in runs]):.0f} ms",
        )


if __name__ == "__main__":
    main()
