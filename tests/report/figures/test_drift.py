import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex

from oceanloc.config.drift import load_drift_scenario, problem_from_scenario
from oceanloc.planning.drift_rrt.planner import make_planner
from oceanloc.planning.drift_rrt.thesis import ThesisOptions, plan_thesis
from oceanloc.report.figures.drift import (
    build_energy_figure,
    build_following_figure,
    build_paths_figure,
    build_swap_figure,
    build_tree_figure,
    energy_figure,
    following_figure,
    paths_figure,
    tree_figure,
)
from oceanloc.reproduce.dillard_drrt import thesis_problem
from oceanloc.sim.drifters import swap_positions


def _legend_labels(fig) -> list[str]:
    return [t.get_text() for legend in fig.legends for t in legend.get_texts()]


def _lines(fig, gid):
    return [line for line in fig.axes[0].get_lines() if line.get_gid() == gid]


def _no_overlap(fig) -> None:
    """The legend (outside the axes) covers neither axis label."""
    FigureCanvasAgg(fig).draw()
    legend = fig.legends[0].get_window_extent()
    ax = fig.axes[0]
    for label in (ax.xaxis.label, ax.yaxis.label):
        assert not legend.overlaps(label.get_window_extent())
    assert not legend.overlaps(ax.get_window_extent())


@pytest.fixture(scope="module")
def thesis_plan():
    problem = thesis_problem()
    return problem, plan_thesis(problem, np.random.default_rng(0), options=ThesisOptions(keep_tree=True))


def test_figures_are_written(tmp_path, thesis_plan):
    problem, res = thesis_plan
    outs = [
        tree_figure(tmp_path / "tree.png", problem, res.tree, res.path, "tree"),
        paths_figure(tmp_path / "paths.png", problem, {"thesis-single": res.path}, "paths"),
        energy_figure(
            tmp_path / "energy.png", {"thesis-single": np.array([30.0, 28.0])}, 49.5, 22.1, "energy"
        ),
        following_figure(
            tmp_path / "f.png", problem, res.path, [res.path.points_m], [res.path.hops_m()], 150.0, "f"
        ),
    ]
    for out in outs:
        assert out.exists() and out.stat().st_size > 10_000
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plans_say_which_line_is_drift_and_which_is_flight(thesis_plan):
    problem, res = thesis_plan
    fig = build_paths_figure(problem, {"thesis-single": res.path, "best achievable": res.path}, "p")
    labels = _legend_labels(fig)
    assert "drift leg (solid)" in labels and any(label.startswith("flight leg (dashed") for label in labels)
    assert {"thesis-single", "best achievable", "start", "goal"} <= set(labels)
    drift, flight = _lines(fig, "drift"), _lines(fig, "flight")
    assert drift and flight
    assert {line.get_linestyle() for line in drift} == {"-"}
    assert {line.get_linestyle() for line in flight} == {"--"}
    # The best achievable is a wide pale underlay, under the planner's line.
    widths = sorted(line.get_linewidth() for line in drift)
    assert widths[-1] > 2 * widths[0]
    tree = build_tree_figure(problem, res.tree, res.path, "t")
    assert {"tree: drift branch", "tree: hop branch", "final path", "drift leg (solid)"} <= set(
        _legend_labels(tree)
    )


def test_swap_draws_two_colours_and_both_starts_and_goals():
    problem = problem_from_scenario(load_drift_scenario("dillard-drift-swap"))
    swap = swap_positions(problem, make_planner("oceanloc"), tuple(np.random.default_rng(i) for i in (0, 1)))
    fig = build_swap_figure(swap.problems, [r.path for r in swap.results], "swap")
    labels = _legend_labels(fig)
    for k in (1, 2):
        assert {f"drifter {k}", f"drifter {k} start", f"drifter {k} goal"} <= set(labels)
    colours = {to_hex(line.get_color()) for line in _lines(fig, "drift")}
    assert len(colours) == 2
    ax = fig.axes[0]
    starts = [line for line in ax.get_lines() if line.get_label().endswith(" start")]
    goals = [line for line in ax.get_lines() if line.get_label().endswith(" goal")]
    # Drifter 2 starts at drifter 1's goal and ends at its start.
    np.testing.assert_allclose(np.ravel(starts[1].get_xydata()), 1e-3 * problem.goal_m)
    np.testing.assert_allclose(np.ravel(goals[1].get_xydata()), 1e-3 * problem.start_m)
    assert to_hex(starts[0].get_color()) != to_hex(starts[1].get_color())


def test_the_gyre_plan_legend_covers_no_axis_label():
    scenario = load_drift_scenario("dillard-drift-gyre-netcdf")
    problem = problem_from_scenario(scenario)
    plan = make_planner("oceanloc")(problem, np.random.default_rng(scenario.seed))
    fig = build_paths_figure(problem, {"oceanloc": plan.path}, "gyre")
    _no_overlap(fig)
    # The figure follows the map's shape (the gyre is twice as wide as high).
    w, h = fig.get_size_inches()
    assert h < w


def test_following_and_energy_figures(thesis_plan):
    problem, res = thesis_plan
    fig = build_following_figure(problem, res.path, [res.path.points_m], [res.path.hops_m()], 150.0, "f")
    labels = _legend_labels(fig)
    assert "watch circle (150 m)" in labels and "followed: flight" in labels and "plan" in labels
    _no_overlap(fig)
    energies = {"thesis-single": np.array([30.0, 28.0]), "thesis-optimality-seeking": np.array([30.0, 27.0])}
    fig = build_energy_figure(energies, 49.5, 22.1, "e")
    markers = {line.get_label(): line.get_marker() for line in fig.axes[0].get_lines()}
    assert markers["thesis-single"] != markers["thesis-optimality-seeking"]
    assert "direct flight 49.5 Wh" in _legend_labels(fig)
