"""Figures of the transponder-survey work (Garcia et al. 2019 Figs. 1-8; thesis Fig. 5.3)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from scipy import stats

from oceanloc._typing import FloatArray
from oceanloc.estimation.consistency import ConfidenceEllipse, confidence_ellipse
from oceanloc.evaluation.survey import SurveyMonteCarlo
from oceanloc.planning.site_planners import site_planner_label
from oceanloc.report.figures._style import save_figure
from oceanloc.sim.survey import SurveyRuns

_K_COLOURS = {0: "tab:gray", 1: "tab:blue", 2: "tab:orange", 3: "tab:green"}


def estimates_figure(
    estimates_en_m: FloatArray,
    truth_en_m: FloatArray,
    actual: ConfidenceEllipse,
    fitted: ConfidenceEllipse,
    path: Path,
) -> Path:
    """Fig. 1: estimates in the E-N plane with the eq. (22) ellipse and the one fitted to the samples."""
    fig = Figure(figsize=(6, 5.5))
    ax = fig.add_subplot()
    ax.scatter(estimates_en_m[:, 0], estimates_en_m[:, 1], s=6, alpha=0.5, label="estimated E-N positions")
    ax.plot(*truth_en_m, "r*", ms=12, label="true E-N position")
    ax.plot(*fitted.points().T, "b-", label="estimated 95% confidence (fitted)")
    ax.plot(*actual.points().T, "k--", label="actual 95% confidence (eq. 22)")
    ax.set(xlabel="east [m]", ylabel="north [m]", title="MAP estimates after N = 4 ranges")
    ax.axis("equal")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    return save_figure(fig, path)


def nees_figure(nees: FloatArray, dof: int, path: Path, title: str) -> Path:
    """Figs. 2, 4, 7: normalized NEES histogram with the chi-square pdf."""
    fig = Figure(figsize=(6, 4))
    ax = fig.add_subplot()
    top = float(np.percentile(nees, 99.5))
    ax.hist(nees, bins=40, range=(0, top), density=True, alpha=0.6, label="NEES (eq. 44)")
    x = np.linspace(0, top, 300)
    ax.plot(x, stats.chi2(dof).pdf(x), color="tab:orange", lw=2, label=f"chi-square pdf, {dof} dof")
    ax.set(xlabel="NEES", ylabel="density", title=title)
    ax.legend()
    return save_figure(fig, path)


def logdet_rmse_figure(
    studies: Mapping[int, SurveyMonteCarlo], transponder: int, path: Path, title: str
) -> Path:
    """Figs. 3 and 6: mean log det Y_n and RMSEE (one transponder) against n for every horizon."""
    fig = Figure(figsize=(11, 4))
    ax_ld, ax_rm = fig.subplots(1, 2)
    for k, study in sorted(studies.items()):
        n = np.arange(1, study.log_det.mean.size + 1)
        label = site_planner_label(study.scenario.planner)
        ax_ld.plot(n, study.log_det.mean, color=_K_COLOURS.get(k), label=label)
        ax_rm.semilogy(n, study.rmsee_m[:, transponder], color=_K_COLOURS.get(k), label=label)
    ax_ld.set(xlabel="measurement n", ylabel="mean log det Y_n", title="(a) D-optimal value")
    ax_rm.set(xlabel="measurement n", ylabel=f"RMSEE of transponder {transponder + 1} [m]", title="(b) RMSEE")
    for ax in (ax_ld, ax_rm):
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle(title)
    return save_figure(fig, path)


def trajectories_figure(
    runs: Mapping[str, SurveyRuns], path: Path, title: str, *, ellipses: bool = False
) -> Path:
    """Fig. 8: measurement paths of one run per planner, with the transponders (and 95 % ellipses).

    Final ellipses of centimetres vanish on a plot tens of metres wide, so when the largest is under 2 %
    of the plot's span they are drawn magnified about their estimates by a round factor, stated in the
    legend; the estimates themselves are drawn at their true places.
    """
    fig = Figure(figsize=(7, 6.5))
    ax = fig.add_subplot()
    first = next(iter(runs.values()))
    truth = first.transponders_enu_m
    colours = ["tab:gray", "tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown"]
    finals = {
        label: confidence_ellipse(run.estimates_m[0, -1, :, :2], run.covariances_m2[0, -1, :, :2, :2])
        for label, run in runs.items()
    }
    points = np.concatenate([truth[:, :2], *(run.sites_enu_m[0, :, :2] for run in runs.values())])
    span = float(np.max(np.ptp(points, axis=0)))
    largest = max(float(np.max(e.semi_major_m)) for e in finals.values())
    magnify = _round_magnification(0.04 * span / largest) if largest < 0.02 * span else 1
    for (label, run), colour in zip(runs.items(), colours, strict=False):
        sites = run.sites_enu_m[0]
        ax.plot(sites[:, 0], sites[:, 1], ".-", color=colour, lw=1, ms=3, label=label)
        if ellipses:
            final = finals[label]
            centre = final.center_m[..., None, :]
            for k, pts in enumerate(centre + magnify * (final.points() - centre)):
                extra = {"label": f"95 % ellipses (x{magnify:g})" if magnify > 1 else "95 % ellipses"}
                ax.plot(pts[:, 0], pts[:, 1], color=colour, lw=1, **(extra if k == 0 else {}))
            ax.plot(*final.center_m.T, "x", color=colour, ms=6)
    ax.plot(truth[:, 0], truth[:, 1], "r^", ms=10, mec="k", label="transponders")
    start = first.sites_enu_m[0, 0]
    ax.plot(start[0], start[1], "o", color="tab:green", mec="k", ms=10, label="start")
    ax.set(xlabel="east [m]", ylabel="north [m]", title=title)
    ax.axis("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def _round_magnification(factor: float) -> float:
    """The largest of 1, 2, 5 times a power of ten not above ``factor`` (at least 1)."""
    if factor <= 1.0:
        return 1.0
    decade = 10.0 ** np.floor(np.log10(factor))
    return float(max(m * decade for m in (1.0, 2.0, 5.0) if m * decade <= factor))


def major_axis_figure(
    planned_en_m: FloatArray,
    reaches_m: FloatArray,
    start_en_m: FloatArray,
    estimate_en_m: FloatArray,
    cov_en_m2: FloatArray,
    path: Path,
    title: str,
) -> Path:
    """Journal Fig. 5 / thesis Fig. 5.3: planned next sites as the reach grows, with the error ellipse's
    major axis (the least-informed direction) through the estimate."""
    fig = Figure(figsize=(7, 6.5))
    ax = fig.add_subplot()
    axis = np.linalg.eigh(cov_en_m2)[1][:, -1]
    span = 1.1 * float(np.max(np.linalg.norm(planned_en_m - estimate_en_m, axis=1)))
    line = estimate_en_m + np.outer(np.linspace(-span, span, 2), axis)
    ax.plot(line[:, 0], line[:, 1], "--", color="tab:purple", label="major axis of the error ellipse")
    ell = confidence_ellipse(estimate_en_m, cov_en_m2, 0.95)
    scale = span / max(float(ell.semi_major_m), 1e-12) * 0.3
    shape = confidence_ellipse(estimate_en_m, cov_en_m2 * scale**2, 0.95)
    ax.plot(*shape.points().T, color="tab:purple", lw=1, label="error ellipse (shape, scaled)")
    sc = ax.scatter(planned_en_m[:, 0], planned_en_m[:, 1], c=reaches_m, marker="D", s=25, cmap="viridis")
    fig.colorbar(sc, ax=ax, label="reach [m]")
    ax.plot(*start_en_m, "r*", ms=12, label="p_V(1)")
    ax.plot(*estimate_en_m, "k^", ms=8, label="transponder estimate")
    ax.set(xlabel="east [m]", ylabel="north [m]", title=title)
    ax.axis("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, path)
