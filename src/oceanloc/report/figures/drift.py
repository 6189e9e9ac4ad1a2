"""Figures of drift planning: trees and paths over the current (thesis Figs. 46, 50), energy per run
(Figs. 51, 53), position swaps (Figs. 70-71) and path following (Fig. 72). Every function writes a PNG
and returns its path; nothing is shown on screen.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon, Rectangle

from oceanloc._typing import FloatArray
from oceanloc.evaluation.drift import ScenarioPlan
from oceanloc.evaluation.path_following import FollowingStudy, SwapStudy
from oceanloc.models.paths import DriftPath
from oceanloc.planning.drift_rrt.problem import DriftProblem, SearchTree
from oceanloc.report.figures._style import save_figure
from oceanloc.reproduce.dillard_drrt import DillardReport, DillardSamplePlans

PATH_COLOURS = {
    "thesis-single": "tab:orange",
    "thesis-optimality-seeking": "tab:red",
    "oceanloc": "magenta",
    "best achievable": "black",
}


def draw_map(ax: Axes, problem: DriftProblem, *, quiver_n: int = 21, km: bool = True) -> None:
    """Current quiver, obstacles, start and goal on ``ax`` (axes in km if ``km``)."""
    s = 1e-3 if km else 1.0
    x0, x1, y0, y1 = problem.space.bounds_m
    gx, gy = np.meshgrid(np.linspace(x0, x1, quiver_n), np.linspace(y0, y1, quiver_n))
    u, v = problem.propagator.field.velocity_xy(gx, gy, problem.t0_s)
    ax.quiver(gx * s, gy * s, u, v, color="tab:blue", alpha=0.55, width=0.0025)
    obs = problem.space.obstacles
    for a, b, c, d in obs.rectangles_m:
        ax.add_patch(Rectangle((a * s, c * s), (b - a) * s, (d - c) * s, color="0.15", zorder=3))
        if obs.inflation_m > 0:
            m = obs.inflation_m
            ax.add_patch(
                Rectangle(
                    ((a - m) * s, (c - m) * s),
                    (b - a + 2 * m) * s,
                    (d - c + 2 * m) * s,
                    fill=False,
                    ls=":",
                    color="0.3",
                )
            )
    for poly in obs.polygons_m:
        ax.add_patch(Polygon(poly * s, closed=True, color="0.15", zorder=3))
    if obs.grid is not None:
        g = obs.grid
        ny, nx = g.occupied.shape
        ax.imshow(
            np.where(g.occupied, 1.0, np.nan),
            extent=(g.x0_m * s, (g.x0_m + nx * g.cell_m) * s, g.y0_m * s, (g.y0_m + ny * g.cell_m) * s),
            origin="lower",
            cmap="Greys",
            vmin=0,
            vmax=1.2,
            zorder=2,
        )
    ax.plot(*(problem.start_m * s), "p", color="tab:green", ms=13, mec="k", zorder=5, label="start")
    ax.plot(*(problem.goal_m * s), "*", color="tab:red", ms=15, mec="k", zorder=5, label="goal")
    ax.add_patch(
        Circle(tuple(problem.goal_m * s), problem.goal_tolerance_m * s, fill=False, color="tab:red", lw=0.8)
    )
    ax.set_xlim(x0 * s, x1 * s)
    ax.set_ylim(y0 * s, y1 * s)
    ax.set_aspect("equal")
    unit = "km" if km else "m"
    ax.set_xlabel(f"east, {unit}")
    ax.set_ylabel(f"north, {unit}")


def draw_path(
    ax: Axes, path: DriftPath, colour: str, label: str, *, km: bool = True, lw: float = 2.0
) -> None:
    """Drift edges solid, flights dashed with take-off/landing circles."""
    s = 1e-3 if km else 1.0
    p = path.points_m * s
    drift = ~path.flight
    segs = np.stack([p[:-1], p[1:]], axis=1)
    first = True
    for seg in segs[drift]:
        ax.plot(seg[:, 0], seg[:, 1], "-", color=colour, lw=lw, label=label if first else None, zorder=4)
        first = False
    for seg in segs[path.flight]:
        ax.plot(
            seg[:, 0], seg[:, 1], "--", color=colour, lw=lw * 0.8, zorder=4, label=label if first else None
        )
        ax.plot(seg[:, 0], seg[:, 1], "o", color=colour, mfc="none", ms=6, zorder=4)
        first = False


def draw_tree(ax: Axes, tree: SearchTree, *, km: bool = True) -> None:
    """Drift branches in black, hop branches in green (the thesis' colours)."""
    s = 1e-3 if km else 1.0
    child = np.arange(1, tree.parent.size)
    par = tree.parent[1:]
    a = tree.positions_m[par] * s
    b = tree.positions_m[child] * s
    hop = tree.hop[1:]
    from matplotlib.collections import LineCollection

    ax.add_collection(
        LineCollection(np.stack([a[~hop], b[~hop]], axis=1), colors="k", linewidths=0.4, alpha=0.6, zorder=2)
    )
    ax.add_collection(
        LineCollection(
            np.stack([a[hop], b[hop]], axis=1), colors="tab:green", linewidths=0.6, alpha=0.7, zorder=2
        )
    )


def tree_figure(
    path: Path, problem: DriftProblem, tree: SearchTree, plan: DriftPath | None, title: str
) -> Path:
    """Thesis Figs. 46 and 50: the DR-RRT* tree, its drift and hop branches and the final path."""
    fig = Figure(figsize=(7, 7))
    ax = fig.add_subplot()
    draw_map(ax, problem)
    draw_tree(ax, tree)
    if plan is not None:
        draw_path(ax, plan, "magenta", "final path")
    ax.set_title(title)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=3, fontsize=8)
    return save_figure(fig, path)


def paths_figure(path: Path, problem: DriftProblem, plans: Mapping[str, DriftPath], title: str) -> Path:
    """Final paths of several planners over the current and obstacles."""
    fig = Figure(figsize=(7, 7))
    ax = fig.add_subplot()
    draw_map(ax, problem)
    for name, plan in plans.items():
        draw_path(ax, plan, PATH_COLOURS.get(name, "tab:purple"), name)
    ax.set_title(title)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=3, fontsize=8)
    return save_figure(fig, path)


def swap_figure(
    path: Path, problems: Sequence[DriftProblem], plans: Mapping[str, DriftPath], title: str
) -> Path:
    """Thesis Figs. 70-71: each drifter's plan in its own colour, with each drifter's start and goal."""
    return paths_figure(path, problems[0], plans, title)


def energy_figure(
    path: Path, energies: Mapping[str, FloatArray], direct_wh: float, best_wh: float, title: str
) -> Path:
    """Thesis Figs. 51/53: flight energy of every run, with direct flight and the best achievable."""
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    for name, e in energies.items():
        ax.plot(np.arange(e.size), e, ".", ms=3, color=PATH_COLOURS.get(name, "tab:purple"), label=name)
    ax.axhline(direct_wh, color="tab:red", ls="--", label=f"direct flight {direct_wh:.1f} Wh")
    ax.axhline(best_wh, color="k", ls=":", label=f"best achievable {best_wh:.1f} Wh")
    ax.set_xlabel("run")
    ax.set_ylabel("flight energy, Wh")
    ax.set_title(title)
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def following_figure(
    path: Path,
    problem: DriftProblem,
    plan: DriftPath,
    tracks: Sequence[FloatArray],
    hops: Sequence[FloatArray],
    watch_circle_m: float,
    title: str,
) -> Path:
    """Thesis Fig. 72: planned path, watch circles and the tracks actually followed (plus signs)."""
    fig = Figure(figsize=(7, 7))
    ax = fig.add_subplot()
    draw_map(ax, problem)
    draw_path(ax, plan, "magenta", "plan")
    for takeoff in plan.hops_m()[:, 0]:
        ax.add_patch(
            Circle(
                tuple(takeoff * 1e-3), watch_circle_m * 1e-3, fill=False, color="tab:purple", lw=1.0, zorder=5
            )
        )
    for i, track in enumerate(tracks):
        ax.plot(
            track[::10, 0] * 1e-3,
            track[::10, 1] * 1e-3,
            "+",
            ms=4,
            color="tab:red",
            alpha=0.6,
            label="followed" if i == 0 else None,
        )
    for h in hops:
        for seg in h:
            ax.plot(seg[:, 0] * 1e-3, seg[:, 1] * 1e-3, ":", color="tab:red", lw=0.8, alpha=0.6)
    ax.set_title(title)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=3, fontsize=8)
    return save_figure(fig, path)


def plan_figure(path: Path, plan: ScenarioPlan) -> Path:
    """``oceanloc drift-plan``: the DR-RRT* tree and path, or the lattice planner's path, over the map."""
    title = f"{plan.scenario.name}: {plan.planner}"
    res = plan.result
    if res.tree is not None:
        return tree_figure(path, plan.problem, res.tree, res.path, title)
    return paths_figure(path, plan.problem, {plan.planner: res.path} if res.path is not None else {}, title)


def following_study_figure(folder: Path, study: FollowingStudy) -> Path:
    """``oceanloc simulate drift-follow``: the plan, its watch circles and the first followed tracks."""
    return following_figure(
        folder / f"{study.scenario}-following.png",
        study.problem,
        study.plan.path,  # type: ignore[arg-type]
        study.runs.tracks(),
        study.runs.flights(),
        study.settings.watch_circle_m,
        f"Path following, {study.scenario} (thesis Fig. 72)",
    )


def swap_figures(folder: Path, study: SwapStudy) -> list[Path]:
    """``oceanloc simulate drift-swap``: both plans in one figure, then each drifter following its plan."""
    plans = {f"drifter {k + 1}": r.path for k, r in enumerate(study.swap.results) if r.path is not None}
    written = [
        swap_figure(
            folder / f"{study.scenario}-plans.png",
            study.swap.problems,
            plans,
            "Two drifters swap positions (thesis Figs. 70-71)",
        )
    ]
    for k, (prob, res, f) in enumerate(
        zip(study.swap.problems, study.swap.results, study.followed, strict=True)
    ):
        if res.path is None or f is None:
            continue
        written.append(
            following_figure(
                folder / f"{study.scenario}-drifter{k + 1}-following.png",
                prob,
                res.path,
                f.tracks(),
                f.flights(),
                study.settings.watch_circle_m,
                f"Drifter {k + 1} following its plan (thesis Fig. 72)",
            )
        )
    return written


def dillard_drrt_figures(folder: Path, report: DillardReport, sample: DillardSamplePlans) -> list[Path]:
    """``oceanloc reproduce dillard-drrt --figures``: both DR-RRT* trees, the final paths of every planner
    and the best achievable, and the flight energy of every run."""
    problem = sample.problem
    written = [
        tree_figure(
            folder / "drrt_tree_single.png",
            problem,
            sample.single.tree,  # type: ignore[arg-type]
            sample.single.path,
            "DR-RRT* single solution (thesis Figs. 46, 50)",
        ),
        tree_figure(
            folder / "drrt_tree_optimality.png",
            problem,
            sample.optimality_seeking.tree,  # type: ignore[arg-type]
            sample.optimality_seeking.path,
            f"DR-RRT* optimality-seeking, {sample.iterations} iterations",
        ),
    ]
    plans = {
        "thesis-single": sample.single.path,
        "thesis-optimality-seeking": sample.optimality_seeking.path,
        "oceanloc": sample.oceanloc.path,
        "best achievable": report.reference.path,
    }
    written.append(
        paths_figure(
            folder / "drrt_paths.png",
            problem,
            {k: v for k, v in plans.items() if v is not None},
            "Final paths on the fixed field",
        )
    )
    energies = {name: r.energy_wh for name, r in report.fixed.runs.items()}
    written.append(
        energy_figure(
            folder / "drrt_energy.png",
            energies,
            report.direct_flight_wh,
            report.best_achievable_wh,
            "Flight energy per run (thesis Figs. 51, 53)",
        )
    )
    return written
