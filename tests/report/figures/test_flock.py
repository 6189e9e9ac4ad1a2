"""Flock figures: what each one draws (lines, labels, colours, z-order), from the returned Figure."""

import dataclasses

import numpy as np
import pytest
from matplotlib.colors import to_rgba

from oceanloc.config.flock import load_flock_scenario
from oceanloc.estimation.time_delay import estimate_recording_delay
from oceanloc.io.wav import example_recordings
from oceanloc.planning.dop import hdop_map, optimize_placement
from oceanloc.report.figures import flock as figures
from oceanloc.reproduce.dillard_filters import reproduce_dillard_filters
from oceanloc.reproduce.dillard_lab_tdoa import reproduce_dillard_lab_tdoa


def _lines(ax):
    return {line.get_label(): line for line in ax.get_lines()}


@pytest.fixture(scope="module")
def filters():
    sc = load_flock_scenario("dillard-filters").with_overrides(duration_s=2.0, dt_s=0.02)
    return reproduce_dillard_filters(sc, runs=2)


def test_track_figure_draws_the_truth_over_the_estimate_in_distinct_colours(filters):
    ax = figures.estimate_figure(filters.monte_carlo, "ekf").axes[0]
    lines = _lines(ax)
    truth, est = lines["true target track"], lines["EKF (constant-acceleration), run 0"]
    assert truth.get_zorder() > est.get_zorder() and truth.get_linestyle() == "--"
    colours = [to_rgba(line.get_color())[:3] for name, line in lines.items() if not name.startswith("_")]
    assert len(set(colours)) == len(colours)  # nodes, estimate and truth each their own colour
    assert ax.get_title() == "Bearing-only tracking by 4 nodes: EKF (constant-acceleration)"
    assert ax.get_xlabel() == "east (m)" and ax.get_ylabel() == "north (m)"


def test_filter_figures_are_written(filters, tmp_path):
    paths = figures.filter_figures(filters, tmp_path)
    assert paths[0].name == "fig25_geometry.png" and len(paths) == 6
    assert all(p.stat().st_size > 10_000 for p in paths)
    rmse = figures.rmse_figure(filters.monte_carlo).axes[0]
    labels = [line.get_label() for line in rmse.get_lines()]
    assert labels[-1] == "√PCRLB" and "EKF (listing) [control]" in labels
    residual = figures.residuals_figure(filters.monte_carlo, "ukf")
    assert [a.get_ylabel() for a in residual.axes] == [
        "truth - estimate,\nposition (m)",
        "truth - estimate,\nvelocity (m/s)",
    ]


def test_lab_figures():
    sc = load_flock_scenario("dillard-lab-tdoa").with_overrides(duration_s=3.0)
    mc = reproduce_dillard_lab_tdoa(sc, runs=1).monte_carlo
    track = figures.lab_track_figure(mc).axes[0]
    lines = _lines(track)
    assert lines["true target track"].get_zorder() > lines["UKF estimate"].get_zorder()
    assert len(lines["nodes"].get_xdata()) == 3
    tdoa = figures.lab_tdoa_figure(mc).axes[0]
    assert tdoa.get_ylabel() == "TDOA (ms)" and "nodes 2 - 3, true" in _lines(tdoa)
    residual = figures.lab_residual_hdop_figure(mc)
    assert [a.get_ylabel() for a in residual.axes] == ["position residual (m)", "HDOP (m)"]


def test_placement_figure_draws_the_fixed_node():
    res = optimize_placement(
        3,
        "bearing",
        min_standoff_m=50,
        max_standoff_m=100,
        fixed_nodes_m=[[80.0, 40.0]],
        starts=2,
        rng=np.random.default_rng(0),
    )
    ax = figures.placement_figure(res).axes[0]
    lines = _lines(ax)
    assert set(lines) == {"local solutions", "even ring", "best placement", "fixed nodes", "target"}
    np.testing.assert_array_equal(lines["fixed nodes"].get_xydata(), [[80.0, 40.0]])
    assert len(lines["best placement"].get_xdata()) == 3
    assert "m/rad" in ax.get_title()
    without = figures.placement_figure(dataclasses.replace(res, fixed_nodes_m=np.zeros((0, 2)))).axes[0]
    assert "fixed nodes" not in _lines(without)


def test_hdop_map_figure_marks_nodes_target_and_minimum():
    dop = hdop_map(
        [[100.0, 0.0], [0.0, 100.0]],
        [0.0, 0.0],
        "tdoa",
        x_range_m=(-100, 100),
        y_range_m=(-100, 100),
        resolution_m=20,
    )
    fig = figures.hdop_map_figure(dop)
    ax = fig.axes[0]
    assert set(_lines(ax)) == {"fixed nodes", "target", "lowest HDOP cell"}
    assert fig.axes[1].get_ylabel() == "HDOP (m/s)"  # the colour bar, geometric factor of TDOA


def test_correlation_figure_zooms_on_the_peak():
    res = estimate_recording_delay(*example_recordings())
    top, zoom = figures.correlation_figure(res).axes
    assert zoom.get_xlim()[1] - zoom.get_xlim()[0] < 0.1 * (top.get_xlim()[1] - top.get_xlim()[0])
    assert _lines(zoom)[f"delay {res.estimate.delay_s * 1e3:.4f} ms"].get_xdata()[0] == pytest.approx(
        1.2345,
        abs=1e-3,  # the true delay of the sample pair (1.2345 ms)
    )
    assert top.get_xlabel() == "lag (ms)" and "hydrophone_a.wav" in zoom.get_xlabel()
