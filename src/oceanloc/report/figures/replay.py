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


def write_replay_figures(exp: ReplayExperiment, folder: Path, stem: str, *, unit_m: float) -> list[Path]:
    """Every figure of ``replay logs/gnssa --figures`` for one record set: ``<stem>_replay_curves.png``
    and ``<stem>_replay_tracks.png``."""
    curves = replay_curves_figure(
        exp.studies, 0, folder / f"{stem}_replay_curves.png",
        f"{exp.records.name}: replay on recorded data", unit_m=unit_m,
    )  # fmt: skip
    title = f"{exp.records.name}: chosen records, run 0"
    tracks = replay_tracks_figure(exp.records, exp.studies, folder / f"{stem}_replay_tracks.png", title)
    return [curves, tracks]


def replay_curves_figure(
    studies: Mapping[str, ReplayStudy], transponder: int, path: Path, title: str, *, unit_m: float = 1.0
) -> Path:
    """Journal Figs. 10-11: mean log det Y_n and RMSEE of one transponder against n, one line per planner.

    ``unit_m`` scales the RMSEE axis (0.01 draws centimetres).
    """
    fig = Figure(figsize=(11, 4))
    ax_ld, ax_rm = fig.subplots(1, 2)
    for name, study in studies.items():
        n = np.arange(1, study.epochs + 1)
        style = {"color": _COLOURS.get(name), "label": planner_label(name), "lw": 1.5}
        if name == RECORDED:
            style["ls"] = "--"
        ax_ld.plot(n, study.log_det.mean, **style)
        ax_rm.semilogy(n, study.rmsee_m[:, transponder] / unit_m, **style)
    unit = "cm" if unit_m == 0.01 else "m"
    ax_ld.set(xlabel="measurement n", ylabel="mean log det Y_n", title="(a) D-optimal value")
    ax_rm.set(
        xlabel="measurement n", ylabel=f"RMSEE of transponder {transponder + 1} [{unit}]", title="(b) RMSEE"
    )
    for ax in (ax_ld, ax_rm):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    return save_figure(fig, path)


def replay_tracks_figure(
    records: RecordSet, studies: Mapping[str, ReplayStudy], path: Path, title: str, *, run: int = 0
) -> Path:
    """Journal Fig. 12: the records chosen by each planner in one run, over every recorded location."""
    fig = Figure(figsize=(7.5, 7))
    ax = fig.add_subplot()
    loc = records.location_enu_m
    ax.plot(loc[:, 0], loc[:, 1], ".", color="0.8", ms=3, label="recorded locations")
    for name, study in studies.items():
        sites = study.histories.sites_enu_m[run]
        ax.plot(
            sites[:, 0], sites[:, 1], ".-", lw=1, ms=3, color=_COLOURS.get(name), label=planner_label(name)
        )
    ref = records.reference_enu_m
    ax.plot(ref[:, 0], ref[:, 1], "r^", ms=10, mec="k", label="reference transponders")
    start = next(iter(studies.values())).histories.sites_enu_m[run, 0]
    ax.plot(start[0], start[1], "o", color="tab:green", mec="k", ms=10, label="p_V(1)")
    ax.set(xlabel="east [m]", ylabel="north [m]", title=title)
    ax.axis("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return save_figure(fig, path)
