"""Figures of drift planning: trees and paths over the current (thesis Figs. 46, 50), energy per run
(Figs. 51, 53), position swaps (Figs. 70-71) and path following (Fig. 72). Every function writes a PNG
and returns its path; nothing is shown on screen.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Polygon, Rectangle
from matplotlib.ticker import MaxNLocator

from oceanloc._typing import FloatArray
from oceanloc.evaluation.drift import ScenarioPlan
from oceanloc.evaluation.path_following import FollowingStudy, SwapStudy
from oceanloc.io.paths import safe_file_stem
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
DRIFTER_COLOURS = ("tab:purple", "tab:orange", "tab:cyan", "tab:brown")
"""Colours of drifter 1, 2, ... in the swap figures (distinct from the planner colours' magenta)."""
KM = 1e-3


def _colour(name: str, k: int) -> str:
    return PATH_COLOURS.get(name, DRIFTER_COLOURS[k % len(DRIFTER_COLOURS)])


def _figure(size: tuple[float, float] = (7.0, 7.6)) -> tuple[Figure, Axes]:
    """A constrained-layout figure, so a legend placed outside the axes never covers labels."""
    fig = Figure(figsize=size, layout="constrained")
    return fig, fig.add_subplot()


def _map_figure(problem: DriftProblem, legend_rows: int = 2) -> tuple[Figure, Axes]:
    """A figure shaped like the map (7 in wide), with room for the title and ``legend_rows`` of legend."""
    x0, x1, y0, y1 = problem.space.bounds_m
    height = 6.2 * min(max((y1 - y0) / (x1 - x0), 0.35), 1.6) + 1.0 + 0.22 * legend_rows
    return _figure((7.0, height))


def _legend_below(fig: Figure, ax: Axes, extra: Sequence[Line2D] = (), ncol: int = 3) -> None:
    """The axes' labelled artists and ``extra`` proxies in one legend under the axes (outside them)."""
    handles, labels = ax.get_legend_handles_labels()
    handles = [*handles, *extra]
    labels = [*labels, *(h.get_label() for h in extra)]
    fig.legend(handles, labels, loc="outside lower center", ncol=ncol, fontsize=8, frameon=False)


def leg_style_handles(colour: str = "0.25") -> list[Line2D]:
    """Legend proxies saying which line style is drift and which is flight."""
    return [
        Line2D([], [], color=colour, ls="-", lw=2.0, label="drift leg (solid)"),
        Line2D(
            [], [], color=colour, ls="--", lw=1.6, marker="o", mfc="none", ms=5,
            label="flight leg (dashed; o take-off / landing)",
        ),
    ]  # fmt: skip


def draw_map(
    ax: Axes, problem: DriftProblem, *, quiver_n: int = 21, km: bool = True, endpoints: bool = True
) -> None:
    """Current quiver (with a scale arrow), obstacles and, if ``endpoints``, start and goal on ``ax``
    (axes in km if ``km``)."""
    s = KM if km else 1.0
    x0, x1, y0, y1 = problem.space.bounds_m
    gx, gy = np.meshgrid(np.linspace(x0, x1, quiver_n), np.linspace(y0, y1, quiver_n))
    u, v = problem.propagator.field.velocity_xy(gx, gy, problem.t0_s)
    q = ax.quiver(gx * s, gy * s, u, v, color="tab:blue", alpha=0.55, width=0.0025)
    speed = np.hypot(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
    finite = speed[np.isfinite(speed)]
    if finite.size and float(finite.max()) > 0:
        ref = float(f"{float(np.percentile(finite, 90)):.1g}")
        ax.quiverkey(
            q, 0.96, 1.025, ref, f"current {ref:g} m/s", labelpos="W", coordinates="axes",
            fontproperties={"size": 8},
        )  # fmt: skip
    _draw_obstacles(ax, problem, s)
    if endpoints:
        draw_endpoints(ax, problem, "tab:green", "tab:red", km=km)
    ax.set_xlim(x0 * s, x1 * s)
    ax.set_ylim(y0 * s, y1 * s)
    ax.set_aspect("equal")
    unit = "km" if km else "m"
    ax.set_xlabel(f"east, {unit}")
    ax.set_ylabel(f"north, {unit}")


def _draw_obstacles(ax: Axes, problem: DriftProblem, s: float) -> None:
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


def draw_endpoints(
    ax: Axes,
    problem: DriftProblem,
    start_colour: str,
    goal_colour: str,
    *,
    km: bool = True,
    prefix: str = "",
    start_size: float = 13.0,
    goal_size: float = 15.0,
) -> None:
    """Start (pentagon), goal (star) and the goal disk; labels ``"{prefix}start"``, ``"{prefix}goal"``."""
    s = KM if km else 1.0
    start, goal = problem.start_m * s, problem.goal_m * s
    ax.plot(*start, "p", color=start_colour, ms=start_size, mec="k", zorder=5, label=f"{prefix}start")
    ax.plot(*goal, "*", color=goal_colour, ms=goal_size, mec="k", zorder=6, label=f"{prefix}goal")
    ax.add_patch(
        Circle(tuple(problem.goal_m * s), problem.goal_tolerance_m * s, fill=False, color=goal_colour, lw=0.8)
    )


def _polyline(segs: FloatArray) -> FloatArray:
    """``(n, 2, 2)`` segments as one ``(m, 2)`` polyline, NaN rows where consecutive segments do not join."""
    if segs.shape[0] == 0:
        return np.zeros((0, 2))
    breaks = np.flatnonzero(np.any(segs[1:, 0] != segs[:-1, 1], axis=1)) + 1
    pieces = np.split(segs, breaks)
    rows: list[FloatArray] = []
    for piece in pieces:
        rows += [piece[:, 0], piece[-1:, 1], np.full((1, 2), np.nan)]
    return np.concatenate(rows)


def draw_path(
    ax: Axes,
    path: DriftPath,
    colour: str,
    label: str,
    *,
    km: bool = True,
    lw: float = 2.0,
    alpha: float = 1.0,
    zorder: float = 4,
) -> None:
    """Drift legs solid, flights dashed with take-off/landing circles; the drift line carries ``label``
    (or, for a path that only flies, the flight line)."""
    s = KM if km else 1.0
    p = path.points_m * s
    segs = np.stack([p[:-1], p[1:]], axis=1)
    drift, flight = _polyline(segs[~path.flight]), _polyline(segs[path.flight])
    style = {"color": colour, "alpha": alpha, "zorder": zorder}
    if drift.size:
        ax.plot(drift[:, 0], drift[:, 1], "-", lw=lw, label=label, gid="drift", **style)
    if flight.size:
        ax.plot(
            flight[:, 0], flight[:, 1], "--", lw=0.8 * lw, marker="o", mfc="none", ms=6,
            label=None if drift.size else label, gid="flight", **style,
        )  # fmt: skip


def draw_tree(ax: Axes, tree: SearchTree, *, km: bool = True) -> list[Line2D]:
    """Drift branches in black, hop branches in green (the thesis' colours); returns legend proxies."""
    s = KM if km else 1.0
    child = np.arange(1, tree.parent.size)
    par = tree.parent[1:]
    a = tree.positions_m[par] * s
    b = tree.positions_m[child] * s
    hop = tree.hop[1:]
    ax.add_collection(
        LineCollection(np.stack([a[~hop], b[~hop]], axis=1), colors="k", linewidths=0.4, alpha=0.6, zorder=2)
    )
    ax.add_collection(
        LineCollection(
            np.stack([a[hop], b[hop]], axis=1), colors="tab:green", linewidths=0.6, alpha=0.7, zorder=2
        )
    )
    return [
        Line2D([], [], color="k", lw=0.6, alpha=0.6, label="tree: drift branch"),
        Line2D([], [], color="tab:green", lw=0.8, alpha=0.7, label="tree: hop branch"),
    ]


def build_tree_figure(problem: DriftProblem, tree: SearchTree, plan: DriftPath | None, title: str) -> Figure:
    """Thesis Figs. 46 and 50: the DR-RRT* tree, its drift and hop branches and the final path."""
    fig, ax = _map_figure(problem)
    draw_map(ax, problem)
    proxies = draw_tree(ax, tree)
    if plan is not None:
        draw_path(ax, plan, "magenta", "final path")
    ax.set_title(title, loc="left")
    _legend_below(fig, ax, [*proxies, *leg_style_handles()])
    return fig


def tree_figure(
    path: Path, problem: DriftProblem, tree: SearchTree, plan: DriftPath | None, title: str
) -> Path:
    """Write :func:`build_tree_figure` to ``path`` (PNG)."""
    return save_figure(build_tree_figure(problem, tree, plan, title), path)


def build_paths_figure(problem: DriftProblem, plans: Mapping[str, DriftPath], title: str) -> Figure:
    """Final paths of several planners over the current and obstacles; the best achievable, when given,
    is drawn as a wide pale underlay so the paths that coincide with it stay visible."""
    fig, ax = _map_figure(problem)
    draw_map(ax, problem)
    for k, (name, plan) in enumerate(plans.items()):
        if name == "best achievable":
            draw_path(ax, plan, "black", name, lw=5.0, alpha=0.3, zorder=3.5)
        else:
            draw_path(ax, plan, _colour(name, k), name)
    ax.set_title(title, loc="left")
    _legend_below(fig, ax, leg_style_handles())
    return fig


def paths_figure(path: Path, problem: DriftProblem, plans: Mapping[str, DriftPath], title: str) -> Path:
    """Write :func:`build_paths_figure` to ``path`` (PNG)."""
    return save_figure(build_paths_figure(problem, plans, title), path)


def build_swap_figure(problems: Sequence[DriftProblem], plans: Mapping[str, DriftPath], title: str) -> Figure:
    """Thesis Figs. 70-71: each drifter's plan in its own colour, with each drifter's own start (pentagon)
    and goal (star) in that colour; where one drifter's start is the other's goal, the larger start
    marker rings the goal star."""
    fig, ax = _map_figure(problems[0], legend_rows=3)
    draw_map(ax, problems[0], endpoints=False)
    for k, (prob, plan) in enumerate(zip(problems, plans, strict=True)):
        colour = DRIFTER_COLOURS[k % len(DRIFTER_COLOURS)]
        name = f"drifter {k + 1}"
        if plan is not None:
            draw_path(ax, plan, colour, name)
        draw_endpoints(ax, prob, colour, colour, prefix=f"{name} ", start_size=17.0, goal_size=11.0)
    ax.set_title(title, loc="left")
    _legend_below(fig, ax, leg_style_handles(), ncol=4)
    return fig


def swap_figure(
    path: Path, problems: Sequence[DriftProblem], plans: Sequence[DriftPath | None], title: str
) -> Path:
    """Write :func:`build_swap_figure` to ``path`` (PNG)."""
    return save_figure(build_swap_figure(problems, plans, title), path)


ENERGY_MARKERS = {"thesis-single": "o", "thesis-optimality-seeking": "x", "oceanloc": "+"}


def build_energy_figure(
    energies: Mapping[str, FloatArray], direct_wh: float, best_wh: float, title: str
) -> Figure:
    """Thesis Figs. 51/53: flight energy of every run (one marker per planner, so coinciding runs of the two
    DR-RRT* modes stay visible), with direct flight and the best achievable."""
    fig, ax = _figure((8.0, 4.8))
    for k, (name, e) in enumerate(energies.items()):
        ax.plot(
            np.arange(e.size), e, ENERGY_MARKERS.get(name, "."), ms=4 if e.size > 100 else 6,
            mfc="none", color=_colour(name, k), label=name,
        )  # fmt: skip
    ax.axhline(direct_wh, color="0.4", ls="--", label=f"direct flight {direct_wh:.1f} Wh")
    ax.axhline(best_wh, color="k", ls=":", label=f"best achievable {best_wh:.1f} Wh")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("run")
    ax.set_ylabel("flight energy, Wh")
    ax.set_title(title, loc="left")
    _legend_below(fig, ax)
    return fig


def energy_figure(
    path: Path, energies: Mapping[str, FloatArray], direct_wh: float, best_wh: float, title: str
) -> Path:
    """Write :func:`build_energy_figure` to ``path`` (PNG)."""
    return save_figure(build_energy_figure(energies, direct_wh, best_wh, title), path)


def build_following_figure(
    problem: DriftProblem,
    plan: DriftPath,
    tracks: Sequence[FloatArray],
    hops: Sequence[FloatArray],
    watch_circle_m: float,
    title: str,
) -> Figure:
    """Thesis Fig. 72: planned path, watch circles and the tracks actually followed (plus signs every
    10 steps) with their flights (dotted)."""
    fig, ax = _map_figure(problem)
    draw_map(ax, problem)
    draw_path(ax, plan, "magenta", "plan")
    for k, takeoff in enumerate(plan.hops_m()[:, 0]):
        ax.add_patch(
            Circle(
                tuple(takeoff * KM), watch_circle_m * KM, fill=False, color="tab:purple", lw=1.0, zorder=5,
                label=f"watch circle ({watch_circle_m:g} m)" if k == 0 else None,
            )
        )  # fmt: skip
    for i, track in enumerate(tracks):
        ax.plot(
            track[::10, 0] * KM, track[::10, 1] * KM, "+", ms=4, color="tab:red", alpha=0.6,
            label="followed: drift (every 10 steps)" if i == 0 else None,
        )  # fmt: skip
    flights = [seg for h in hops for seg in h]
    if flights:
        ax.add_collection(
            LineCollection(
                np.asarray(flights) * KM, colors="tab:red", linestyles=":", linewidths=0.9, alpha=0.7
            )
        )
        ax.plot([], [], ":", color="tab:red", lw=0.9, label="followed: flight")
    ax.set_title(title, loc="left")
    _legend_below(fig, ax, leg_style_handles("magenta"))
    return fig


def following_figure(
    path: Path,
    problem: DriftProblem,
    plan: DriftPath,
    tracks: Sequence[FloatArray],
    hops: Sequence[FloatArray],
    watch_circle_m: float,
    title: str,
) -> Path:
    """Write :func:`build_following_figure` to ``path`` (PNG)."""
    return save_figure(build_following_figure(problem, plan, tracks, hops, watch_circle_m, title), path)


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
        folder / f"{safe_file_stem(study.scenario)}-following.png",
        study.problem,
        study.plan.path,  # type: ignore[arg-type]
        study.runs.tracks(),
        study.runs.flights(),
        study.settings.watch_circle_m,
        f"Path following, {study.scenario} (thesis Fig. 72)",
    )


def swap_figures(folder: Path, study: SwapStudy) -> list[Path]:
    """``oceanloc simulate drift-swap``: both plans in one figure, then each drifter following its plan."""
    written = [
        swap_figure(
            folder / f"{safe_file_stem(study.scenario)}-plans.png",
            study.swap.problems,
            [r.path for r in study.swap.results],
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
                folder / f"{safe_file_stem(study.scenario)}-drifter{k + 1}-following.png",
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
