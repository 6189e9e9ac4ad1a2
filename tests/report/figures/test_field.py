import dataclasses

import numpy as np
import pytest
from matplotlib.colors import to_hex

from oceanloc.estimation.gnssa import GnssaOptions
from oceanloc.field.gnssa_surveys import process_gnssa_surveys
from oceanloc.io.gnssa import lajolla_paths
from oceanloc.report.figures.field import gnssa_residual_figure, gnssa_spread_figure, range_noise_figure


@pytest.fixture(scope="module")
def two_surveys():
    return process_gnssa_surveys(lajolla_paths()[3:5], GnssaOptions())


def test_residual_figure_has_four_labelled_panels_and_a_legend_outside_them(two_surveys):
    s, r = two_surveys.surveys[0], two_surveys.results[0]
    fig = gnssa_residual_figure(s, r)
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert [ax.get_title()[:3] for ax in panels] == ["(a)", "(b)", "(c)", "(d)"]
    assert all("[" in ax.get_xlabel() and "[" in ax.get_ylabel() for ax in panels)  # units
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels[:3] == ["±1σ per ping", f"used ({r.pings_used})", f"excluded ({len(r.exclusions)})"]
    assert "transponder (estimate)" in labels
    assert all(ax.get_legend() is None for ax in panels[:3])  # no legend over the residuals
    # excluded pings beyond the axis are drawn at its edge, not lost
    excluded = 100 * r.residual_m[~r.used]
    lo, hi = panels[0].get_ylim()
    edge = [line for line in panels[0].get_lines() if line.get_marker() in ("^", "v")]
    assert sum(line.get_xdata().size for line in edge) == int(np.sum((excluded > hi) | (excluded < lo)))


def test_spread_figure_draws_both_epochs_and_names_the_velocity(two_surveys):
    fig = gnssa_spread_figure(two_surveys)
    assert "moved to" in fig.get_suptitle() and "ITRF2014 PCFC" in fig.get_suptitle()
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["as surveyed", "at one epoch, ±1σ"]
    assert [ax.get_title().split(":")[0] for ax in fig.axes] == ["east", "north", "up"]
    assert [t.get_text() for t in fig.axes[0].get_yticklabels()] == ["20211210", "20220321"]
    as_surveyed = dataclasses.replace(two_surveys, spread=two_surveys.as_surveyed)
    assert "as surveyed (no site velocity)" in gnssa_spread_figure(as_surveyed).get_suptitle()


def test_range_noise_figure_has_a_legend_per_panel():
    from oceanloc.estimation.noise import StationaryNoise, running_range_noise

    rng = np.random.default_rng(1)
    est = [
        StationaryNoise(
            beacon=b,
            segment=0,
            t_start_s=0.0,
            t_end_s=300.0,
            running=running_range_noise(8.0 + 0.05 * b * rng.standard_normal(60)),
            n_ranges=60,
            n_outliers=0,
        )
        for b in (1, 2)
    ]
    fig = range_noise_figure(est)
    assert len(fig.axes) == 4
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == [
        "running mean", "final estimate", "±1 standard error"
    ]  # fmt: skip
    assert fig.axes[1].get_ylabel() == "range noise σ [mm]" and fig.axes[3].get_title().startswith("beacon 2")
    assert to_hex(fig.axes[0].get_lines()[0].get_color()) != to_hex(fig.axes[0].get_lines()[2].get_color())
