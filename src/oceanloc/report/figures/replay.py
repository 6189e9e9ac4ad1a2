"""Figures of replays on recorded data (journal Figs. 10-12 style): curves per planner and chosen tracks."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from oceanloc.evaluation.replay import ReplayStudy
from oceanloc.field.replay import RECORDED, RecordSet, planner_label
from oceanloc.report.figures._style import save_figure
from oceanloc.reproduce.garcia2019_replay import ReplayExperiment

_COLOURS = {
    RECORDED: "black",
    "k0": "tab:gray",
    "k1": "tab:blue",
    "k2": "tab:orange",
    "k3": "tab:green",
    "greedy": "tab:red",
    "random-disk": "tab:purple",
}
_SPARE = ("tab:brown", "tab:pink", "tab:olive", "tab:cyan", "gold", "navy", "lime")


def planner_colours(names: list[str]) -> dict[str, str]:
    """One distinct colour per planner: the fixed ones above, then spare colours in order."""
    spare = iter(_SPARE)
    return {n: _COLOURS[n] if n in _COLOURS else next(spare, "0.4") for n in names}


def write_replay_figures(exp: ReplayExperiment, folder: Path, stem: str, *, unit_m: float) -> list[Path]:
    """Every figure of ``replay logs/gnssa --figures`` for one record set: ``<stem>_replay_curves.png``
    and ``<stem>_replay_tracks.png``."""
    curves = replay_curves_figure(
        exp.studies, 0, f"{exp.records.name}: replay on recorded data", unit_m=unit_m
    )
    tracks = replay_tracks_figure(exp.records, exp.studies, f"{exp.records.name}: chosen records, run 0")
    return [
        save_figure(curves, folder / f"{stem}_replay_curves.png"),
        save_figure(tracks, folder / f"{stem}_replay_tracks.png"),
    ]


def replay_curves_figure(
    studies: Mapping[str, ReplayStudy], transponder: int, title: str, *, unit_m: float = 1.0
) -> Figure:
    """Journal Figs. 10-11: mean log det Y_n and RMSEE of one transponder against n, one line per planner.

    ``unit_m`` scales the RMSEE axis (0.01 draws centimetres).
    """
    fig = Figure(figsize=(11, 4.5), layout="constrained")
    ax_ld, ax_rm = fig.subplots(1, 2)
    colours = planner_colours(list(studies))
    for name, study in studies.items():
        n = np.arange(1, study.epochs + 1)
        style = {"color": colours[name], "label": planner_label(name), "lw": 1.5}
        if name == RECORDED:
            style["ls"] = "--"
        ax_ld.plot(n, study.log_det.mean, **style)
        ax_rm.semilogy(n, study.rmsee_m[:, transponder] / unit_m, **style)
    unit = "cm" if unit_m == 0.01 else "m"
    ax_ld.set(xlabel="measurement n", ylabel="mean log det Y_n (Y in m^-2)", title="(a) D-optimal value")
    ax_rm.set(
        xlabel="measurement n", ylabel=f"RMSEE of transponder {transponder + 1} [{unit}]", title="(b) RMSEE"
    )
    for ax in (ax_ld, ax_rm):
        ax.grid(alpha=0.3)
    fig.legend(*ax_ld.get_legend_handles_labels(), loc="outside right center", fontsize=8)
    fig.suptitle(title)
    return fig


def replay_tracks_figure(
    records: RecordSet, studies: Mapping[str, ReplayStudy], title: str, *, run: int = 0
) -> Figure:
    """Journal Fig. 12: the records chosen by each planner in one run, over every recorded location.

    One panel per planner (shared axes), so planners whose paths coincide (or a recorded order that
    stays where the vehicle stood still) hide nothing; the last site of each path is a square.
    """
    names = list(studies)
    cols = min(4, len(names))
    rows = -(-len(names) // cols)
    fig = Figure(figsize=(3.2 * cols + 1.0, 3.3 * rows + 0.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, sharex=True, sharey=True, squeeze=False)).ravel()
    loc = records.location_enu_m
    ref = records.reference_enu_m
    colours = planner_colours(names)
    start = studies[names[0]].histories.sites_enu_m[run, 0]
    for ax, name in zip(axes, names, strict=False):
        sites = studies[name].histories.sites_enu_m[run]
        ax.plot(loc[:, 0], loc[:, 1], ".", color="0.8", ms=2, label="recorded locations")
        ax.plot(sites[:, 0], sites[:, 1], ".-", lw=1, ms=3, color=colours[name], label="chosen records")
        ax.plot(sites[-1, 0], sites[-1, 1], "s", color=colours[name], mec="k", ms=6, label="last record")
        ax.plot(ref[:, 0], ref[:, 1], "^", color="gold", ms=9, mec="k", label="reference transponders")
        ax.plot(start[0], start[1], "o", mfc="none", mec="k", mew=1.5, ms=9, label="start p_V(1)")
        ax.set_title(planner_label(name), fontsize=10, color=colours[name])
        ax.set_aspect("equal", adjustable="box")
        ax.grid(alpha=0.3)
    for ax in axes[len(names) :]:
        ax.set_visible(False)
    for c in range(cols):  # the lowest panel of each column carries its x labels
        lowest = axes[max(i for i in range(c, len(names), cols))]
        lowest.xaxis.set_tick_params(labelbottom=True)
        lowest.set_xlabel("east [m]")
    for ax in axes[::cols]:
        ax.set_ylabel("north [m]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=5, fontsize=8)
    fig.suptitle(title)
    return fig
