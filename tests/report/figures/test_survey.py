def test_round_magnification_is_one_two_or_five_times_a_power_of_ten():
    from oceanloc.report.figures.survey import _round_magnification

    assert [_round_magnification(f) for f in (0.5, 1.0, 3.7, 19.9, 20.0, 480.0)] == [1, 1, 2, 10, 20, 200]


import functools  # noqa: E402

import matplotlib.colors as mcolors  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from oceanloc.config.survey import load_survey_scenario  # noqa: E402
from oceanloc.evaluation.survey import survey_monte_carlo  # noqa: E402
from oceanloc.report.figures import survey as figures  # noqa: E402


@functools.cache
def _studies(name="garcia2019-m4", planners=("k0", "k1", "greedy")):
    base = load_survey_scenario(name).with_overrides(epochs=4)
    return [survey_monte_carlo(base.with_overrides(planner=p), 3, seed=5) for p in planners]


def test_monte_carlo_figure_labels_every_planner_and_draws_every_transponder(tmp_path):
    studies = _studies()
    fig = figures.logdet_rmse_figure(studies, tmp_path / "f.png", "test")
    assert (tmp_path / "f.png").stat().st_size > 10_000
    ax_ld, *rm_axes = fig.axes
    assert len(rm_axes) == 4  # one RMSEE panel per transponder
    labels = [t.get_text() for t in ax_ld.get_legend().get_texts()]
    assert labels == ["k = 0 (random yaw)", "k = 1", "greedy"]
    colours = {mcolors.to_hex(line.get_color()) for line in ax_ld.get_lines()}
    assert len(colours) == 3
    for j, ax in enumerate(rm_axes):
        assert ax.get_title() == f"RMSEE, transponder {j + 1}" and ax.get_ylabel() == "RMSEE (m)"
        for line, study in zip(ax.get_lines(), studies, strict=True):
            np.testing.assert_array_equal(line.get_ydata(), study.rmsee_m[:, j])
    assert ax_ld.get_ylabel() == "mean log det Y_n (nats)"


def test_trajectories_figure_colours_planners_and_keeps_the_legend_off_the_axes(tmp_path):
    studies = _studies()
    runs = [(s.scenario.planner, s.sample_run(0)) for s in studies]
    fig = figures.trajectories_figure(runs, tmp_path / "t.png", "paths", ellipses=True)
    ax = fig.axes[0]
    assert ax.get_legend() is None and len(fig.legends) == 1
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert {"k = 0 (random yaw)", "k = 1", "greedy", "transponders (truth)", "final estimates"} <= set(labels)
    paths = {line.get_label(): mcolors.to_hex(line.get_color()) for line in ax.get_lines()}
    assert len({paths["k = 0 (random yaw)"], paths["k = 1"], paths["greedy"]}) == 3
    assert ax.get_xlabel() == "east (m)" and ax.get_ylabel() == "north (m)"


def test_consistency_figure_draws_mean_nees_and_share_above_q95(tmp_path):
    study = _studies()[1]
    fig = figures.consistency_figure(study, tmp_path / "c.png", "test")
    ax_mean, ax_frac = fig.axes
    assert ax_mean.get_yscale() == "log"
    np.testing.assert_array_equal(ax_mean.get_lines()[-1].get_ydata(), study.consistency.mean_nees)
    np.testing.assert_array_equal(ax_frac.get_lines()[-1].get_ydata(), 100 * study.consistency.fraction_above)
    assert "(%)" in ax_frac.get_ylabel()


@pytest.mark.parametrize(("runs", "bins"), [(50, 14), (500, 40), (4, 8)])
def test_nees_histogram_bins_follow_the_number_of_runs(tmp_path, runs, bins):
    nees = np.random.default_rng(1).chisquare(3, runs)
    fig = figures.nees_figure(nees, 3, tmp_path / "n.png", "t")
    assert len(fig.axes[0].patches) == bins
