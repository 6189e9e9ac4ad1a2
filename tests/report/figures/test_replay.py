import pytest
from matplotlib.colors import to_hex

from oceanloc.estimation.gnssa import GnssaOptions
from oceanloc.io.gnssa import lajolla_paths, read_gnssa
from oceanloc.report.figures.replay import planner_colours, replay_curves_figure, replay_tracks_figure
from oceanloc.reproduce.garcia2019_replay import gnssa_replay_settings, replay_gnssa

PLANNERS = ["recorded", "k0", "k1", "k5", "greedy"]


@pytest.fixture(scope="module")
def replay():
    survey = read_gnssa(lajolla_paths()[3])
    return replay_gnssa(
        survey, GnssaOptions(sound_speed_mps=1504.4), runs=2, seed=1, planners=PLANNERS,
        settings=lambda rec: gnssa_replay_settings(rec, epochs=5),
    ).experiment  # fmt: skip


def test_every_planner_gets_its_own_colour():
    colours = planner_colours(["recorded", "k0", "k1", "k4", "k5", "k10", "greedy"])
    assert len(set(colours.values())) == 7


def test_curves_figure_has_one_line_per_planner_and_one_legend(replay):
    fig = replay_curves_figure(replay.studies, 0, "t", unit_m=0.01)
    ax_ld, ax_rm = fig.axes
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["recorded order", "k = 0 (random yaw)", "k = 1", "k = 5", "greedy"]
    assert len(ax_ld.get_lines()) == len(ax_rm.get_lines()) == 5
    assert len({to_hex(line.get_color()) for line in ax_rm.get_lines()}) == 5
    assert ax_rm.get_ylabel() == "RMSEE of transponder 1 [cm]" and ax_ld.get_legend() is None


def test_tracks_figure_has_one_panel_per_planner_with_x_labels_on_every_column(replay):
    fig = replay_tracks_figure(replay.records, replay.studies, "t")
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in visible] == [
        "recorded order",
        "k = 0 (random yaw)",
        "k = 1",
        "k = 5",
        "greedy",
    ]
    # 4 columns: panels 2..4 of the first row have nothing below them except panel 5 under panel 1
    assert [ax.get_xlabel() for ax in visible] == ["", "east [m]", "east [m]", "east [m]", "east [m]"]
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == [
        "recorded locations",
        "chosen records",
        "last record",
        "reference transponders",
        "start p_V(1)",
    ]
