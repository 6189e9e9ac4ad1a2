import numpy as np

from oceanloc.planning.drift_rrt.thesis import ThesisOptions, plan_thesis
from oceanloc.report.figures.drift import energy_figure, following_figure, paths_figure, tree_figure
from oceanloc.reproduce.dillard_drrt import thesis_problem


def test_figures_are_written(tmp_path):
    problem = thesis_problem()
    res = plan_thesis(problem, np.random.default_rng(0), options=ThesisOptions(keep_tree=True))
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
