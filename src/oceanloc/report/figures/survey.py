"""Figures of the transponder-survey work (Garcia et al. 2019 Figs. 1-8; thesis Fig. 5.3)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from scipy import stats

from oceanloc._typing import FloatArray
from oceanloc.estimation.consistency import ConfidenceEllipse, confidence_ellipse
from oceanloc.evaluation.survey import SingleSurvey, SurveyMonteCarlo
from oceanloc.planning.site_planners import PlannerSettings, site_planner_label, site_planner_name
from oceanloc.report.figures._style import save_figure
from oceanloc.reproduce.garcia2018 import Garcia2018Result
from oceanloc.reproduce.garcia2019 import Garcia2019Result
from oceanloc.reproduce.survey_tables import MajorAxisSweep
from oceanloc.sim.survey import SurveyRuns

_PLANNER_COLOURS = {
    "k0": "tab:gray",
    "k1": "tab:blue",
    "k2": "tab:orange",
    "k3": "tab:green",
    "greedy": "tab:red",
    "random-disk": "tab:purple",
}
_CYCLE = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink")


def estimates_figure(
    estimates_en_m: FloatArray,
    truth_en_m: FloatArray,
    actual: ConfidenceEllipse,
    fitted: ConfidenceEllipse,
    path: Path,
) -> Figure:
    """Fig. 1: estimates in the E-N plane with the eq. (22) ellipse and the one fitted to the samples."""
    fig = Figure(figsize=(6, 5.5))
    ax = fig.add_subplot()
    ax.scatter(estimates_en_m[:, 0], estimates_en_m[:, 1], s=6, alpha=0.5, label="estimated E-N positions")
    ax.plot(*truth_en_m, "r*", ms=12, label="true E-N position")
    ax.plot(*fitted.points().T, "b-", label="estimated 95% confidence (fitted)")
    ax.plot(*actual.points().T, "k--", label="actual 95% confidence (eq. 22)")
    ax.set(xlabel="east (m)", ylabel="north (m)", title="MAP estimates after N = 4 ranges")
    ax.axis("equal")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    save_figure(fig, path)
    return fig


def nees_figure(nees: FloatArray, dof: int, path: Path, title: str) -> Figure:
    """Figs. 2, 4, 7: normalized NEES histogram with the chi-square pdf."""
    fig = Figure(figsize=(6, 4))
    ax = fig.add_subplot()
    top = float(np.percentile(nees, 99.5))
    bins = int(np.clip(2.0 * np.sqrt(nees.size), 8, 40))  # about 2 sqrt(R) bins: no gaps at 50 runs
    ax.hist(
        nees, bins=bins, range=(0, top), density=True, alpha=0.6, label=f"NEES (eq. 44), {nees.size} runs"
    )
    x = np.linspace(0, top, 300)
    ax.plot(x, stats.chi2(dof).pdf(x), color="tab:orange", lw=2, label=f"chi-square pdf, {dof} dof")
    ax.set(xlabel="NEES (1)", ylabel="probability density (1)", title=title)
    ax.legend()
    save_figure(fig, path)
    return fig


def planner_colour(settings: PlannerSettings, index: int = 0) -> str:
    """One colour per planner, the same in every survey figure (random baselines grey and purple)."""
    return _PLANNER_COLOURS.get(site_planner_name(settings), _CYCLE[index % len(_CYCLE)])


def logdet_rmse_figure(studies: Sequence[SurveyMonteCarlo], path: Path, title: str) -> Figure:
    """Figs. 3 and 6 (thesis 5.x): mean log det Y_n against n, and the RMSEE of every transponder against
    n (one panel per transponder), one line per planner labelled by :func:`site_planner_label`.

    Returns the figure (written to ``path``).
    """
    m = studies[0].scenario.n_transponders
    cols = 1 if m == 1 else 2
    rows = -(-m // cols)
    fig = Figure(figsize=(5.5 + 4.0 * cols, 1.2 + 3.0 * max(rows, 1)), layout="constrained")
    grid = fig.add_gridspec(rows, 1 + cols, width_ratios=[1.4] + [1.0] * cols)
    ax_ld = fig.add_subplot(grid[:, 0])
    rm_axes = [fig.add_subplot(grid[i // cols, 1 + i % cols]) for i in range(m)]
    for i, study in enumerate(studies):
        settings = study.scenario.planner
        style = {"color": planner_colour(settings, i), "lw": 1.5}
        if settings.kind.startswith("random"):
            style["ls"] = "--"
        n = np.arange(1, study.log_det.mean.size + 1)
        ax_ld.plot(n, study.log_det.mean, label=site_planner_label(settings), **style)
        for j, ax in enumerate(rm_axes):
            ax.semilogy(n, study.rmsee_m[:, j], **style)
    ax_ld.set(xlabel="measurement n", ylabel="mean log det Y_n (nats)", title="D-optimal value")
    for j, ax in enumerate(rm_axes):
        ax.set(xlabel="measurement n", ylabel="RMSEE (m)", title=f"RMSEE, transponder {j + 1}")
    for ax in (ax_ld, *rm_axes):
        ax.grid(alpha=0.3)
    ax_ld.legend(loc="lower right", title="planner")
    runs = studies[0].runs
    fig.suptitle(f"{title} ({runs} runs)")
    save_figure(fig, path)
    return fig


def trajectories_figure(
    runs: Sequence[tuple[PlannerSettings, SurveyRuns]], path: Path, title: str, *, ellipses: bool = False
) -> Figure:
    """Fig. 8: measurement paths of one run per planner, with the transponders (and 95 % ellipses).

    Final ellipses of centimetres vanish on a plot tens of metres wide, so when the largest is under 2 %
    of the plot's span they are drawn magnified about their estimates by a round factor, stated in the
    legend; the estimates themselves are drawn at their true places (crosses over the hollow transponder
    triangles). The legend sits below the axes, off the data. Returns the figure (written to ``path``).
    """
    fig = Figure(figsize=(7, 7.5), layout="constrained")
    ax = fig.add_subplot()
    first = runs[0][1]
    truth = first.transponders_enu_m
    finals = [
        confidence_ellipse(run.estimates_m[0, -1, :, :2], run.covariances_m2[0, -1, :, :2, :2])
        for _, run in runs
    ]
    points = np.concatenate([truth[:, :2], *(run.sites_enu_m[0, :, :2] for _, run in runs)])
    span = float(np.max(np.ptp(points, axis=0)))
    largest = max(float(np.max(e.semi_major_m)) for e in finals)
    magnify = _round_magnification(0.04 * span / largest) if largest < 0.02 * span else 1
    ax.plot(
        truth[:, 0], truth[:, 1], "^", mfc="none", mec="red", mew=1.5, ms=12, label="transponders (truth)"
    )
    for i, ((settings, run), final) in enumerate(zip(runs, finals, strict=True)):
        colour = planner_colour(settings, i)
        sites = run.sites_enu_m[0]
        ax.plot(
            sites[:, 0], sites[:, 1], ".-", color=colour, lw=1.2, ms=4, label=site_planner_label(settings)
        )
        if ellipses:
            centre = final.center_m[..., None, :]
            for k, pts in enumerate(centre + magnify * (final.points() - centre)):
                extra = {"label": f"95 % ellipses (x{magnify:g})" if magnify > 1 else "95 % ellipses"}
                ax.plot(pts[:, 0], pts[:, 1], color=colour, lw=1, ls=":", **(extra if k == 0 else {}))
        ax.plot(
            *final.center_m.T,
            "x",
            color=colour,
            ms=7,
            mew=1.5,
            zorder=5,
            **({"label": "final estimates"} if i == 0 else {}),
        )
    start = first.sites_enu_m[0, 0]
    ax.plot(start[0], start[1], "*", color="black", ms=14, zorder=6, label="start p_V(1)")
    ax.set(xlabel="east (m)", ylabel="north (m)", title=title)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    fig.legend(loc="outside lower center", ncol=3, fontsize=8)
    save_figure(fig, path)
    return fig


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
) -> Figure:
    """Journal Fig. 5 / thesis Fig. 5.3: planned next sites as the reach grows, with the error ellipse's
    major axis (the least-informed direction) through the estimate."""
    fig = Figure(figsize=(7, 7.5), layout="constrained")
    ax = fig.add_subplot()
    axis = np.linalg.eigh(cov_en_m2)[1][:, -1]
    span = 1.1 * float(np.max(np.linalg.norm(planned_en_m - estimate_en_m, axis=1)))
    line = estimate_en_m + np.outer(np.linspace(-span, span, 2), axis)
    ell = confidence_ellipse(estimate_en_m, cov_en_m2, 0.95)
    axes_text = f"{float(ell.semi_major_m):.1f} x {float(ell.semi_minor_m):.2f} m"
    ax.plot(
        line[:, 0],
        line[:, 1],
        "--",
        color="tab:purple",
        label=f"major axis of the 95 % error ellipse ({axes_text})",
    )
    sc = ax.scatter(
        planned_en_m[:, 0],
        planned_en_m[:, 1],
        c=reaches_m,
        marker="D",
        s=25,
        cmap="viridis",
        label="planned p_V(2)",
    )
    fig.colorbar(sc, ax=ax, label="reach per epoch (m)")
    ax.plot(*start_en_m, "r*", ms=12, label="p_V(1)")
    ax.plot(*estimate_en_m, "k^", ms=8, label="transponder estimate")
    ax.set(xlabel="east (m)", ylabel="north (m)", title=title)
    ax.axis("equal")
    ax.grid(alpha=0.3)
    fig.legend(loc="outside lower center", ncol=2, fontsize=8)
    save_figure(fig, path)
    return fig


def consistency_figure(result: SurveyMonteCarlo, path: Path, title: str) -> Figure:
    """NEES consistency by epoch: mean NEES with its 3-SE band around ``3M``, and the share of runs above
    the ``chi2(3M)`` 95 % quantile against the 5 % a consistent estimator gives."""
    cons = result.consistency
    n = np.arange(1, cons.mean_nees.size + 1)
    fig = Figure(figsize=(11, 4), layout="constrained")
    ax_mean, ax_frac = fig.subplots(1, 2)
    lo, hi = cons.mean_band
    ax_mean.fill_between(n, lo, hi, color="tab:green", alpha=0.2, label=f"{cons.dof} +- 3 SE")
    ax_mean.axhline(cons.dof, color="tab:green", lw=1)
    ax_mean.semilogy(n, cons.mean_nees, color="tab:blue", label="mean NEES (eq. 44)")
    ax_mean.set(
        xlabel="measurement n",
        ylabel="mean NEES (1, log scale)",
        title=f"Mean NEES, chi-square {cons.dof} dof",
    )
    ax_frac.axhline(100 * (1 - cons.confidence), color="tab:green", lw=1, label="expected (5 %)")
    ax_frac.plot(n, 100 * cons.fraction_above, color="tab:blue", label="ours")
    ax_frac.set(
        xlabel="measurement n",
        ylabel="runs above the 95 % quantile (%)",
        title="Share of runs above chi2 q95",
    )
    for ax in (ax_mean, ax_frac):
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right")
    fig.suptitle(f"{title} ({cons.runs} runs)")
    save_figure(fig, path)
    return fig


def single_survey_figures(survey: SingleSurvey, out: Path) -> list[Path]:
    """The trajectory of one survey with the final 95 % ellipses."""
    scen = survey.scenario
    path = out / f"{scen.name}_trajectory.png"
    trajectories_figure(
        [(scen.planner, survey.run)],
        path,
        f"{scen.name}: measurement path and 95 % ellipses",
        ellipses=True,
    )
    return [path]


def monte_carlo_figures(result: SurveyMonteCarlo, out: Path) -> list[Path]:
    """``simulate survey`` with many runs: log det and RMSEE per transponder, NEES at the last epoch,
    NEES consistency by epoch, and run 0's path."""
    scen = result.scenario
    label = site_planner_label(scen.planner)
    title = f"{scen.name}, planner {label}"
    paths = [out / f"{scen.name}_logdet_rmse.png", out / f"{scen.name}_nees.png"]
    logdet_rmse_figure([result], paths[0], title)
    nees_figure(result.nees[:, -1], result.nees_final.dof, paths[1], f"{title}: NEES at n = {scen.epochs}")
    paths.append(out / f"{scen.name}_consistency.png")
    consistency_figure(result, paths[-1], title)
    paths.append(out / f"{scen.name}_trajectory_run0.png")
    trajectories_figure([(scen.planner, result.sample_run(0))], paths[-1], f"{title}: run 0", ellipses=True)
    return paths


def _sweep_figure(sweep: MajorAxisSweep, path: Path, title: str) -> Path:
    major_axis_figure(
        sweep.planned_enu_m[:, :2],
        sweep.reaches_m,
        sweep.start_enu_m[:2],
        sweep.estimate_m[:2],
        sweep.covariance_m2[:2, :2],
        path,
        title,
    )
    return path


def garcia2019_figures(result: Garcia2019Result, out: Path) -> list[Path]:
    """Journal Figs. 1-8 from a ``reproduce garcia2019`` result; returns the paths written."""
    from oceanloc.reproduce import garcia2019

    est = result.estimator
    paths = [out / "fig1_estimates_en.png", out / "fig2_nees_n4.png"]
    estimates_figure(
        est.estimates_m[:, :2],
        garcia2019.ESTIMATOR_TRUTH_M[:2],
        est.actual_ellipse,
        est.sample_ellipse,
        paths[0],
    )
    nees_figure(est.nees, 3, paths[1], f"Fig. 2: NEES at n = N = 4 ({est.nees.size} runs)")
    k_fig = garcia2019.NEES_FIGURE_HORIZON
    for label, curves, hist in (("M1", "3", "4"), ("M4", "6", "7")):
        by_k = result.studies[label]
        paths.append(out / f"fig{curves}_{label.lower()}_logdet_rmse.png")
        logdet_rmse_figure([s for _, s in sorted(by_k.items())], paths[-1], f"Fig. {curves}: {label}")
        if k_fig in by_k:
            s = by_k[k_fig]
            paths.append(out / f"fig{hist}_nees_{label.lower()}_k{k_fig}.png")
            title = f"Fig. {hist}: NEES at n = {s.scenario.epochs}, {label}, k = {k_fig} ({s.runs} runs)"
            nees_figure(s.nees[:, -1], 3 * s.scenario.n_transponders, paths[-1], title)
    paths.append(
        _sweep_figure(
            result.fig5, out / "fig5_major_axis.png", "Fig. 5: k = 1 plan vs speed, after the first range"
        )
    )
    runs = [(s.scenario.planner, s.sample_run(0)) for _, s in sorted(result.studies["M4"].items())]
    paths.append(out / "fig8_trajectories_m4.png")
    trajectories_figure(runs, paths[-1], "Fig. 8: measurement paths, run 0")
    return paths


def garcia2018_figures(result: Garcia2018Result, out: Path) -> list[Path]:
    """Thesis Sections 5.2 and 5.4 (log det and RMSEE, random disk vs greedy) and Fig. 5.3."""
    paths = []
    for label, by_k in result.studies.items():
        paths.append(out / f"greedy_{label.lower()}_logdet_rmse.png")
        logdet_rmse_figure(
            [s for _, s in sorted(by_k.items())], paths[-1], f"Thesis greedy vs random disk, {label}"
        )
    paths.append(
        _sweep_figure(result.fig53, out / "fig5_3_major_axis.png", "Thesis Fig. 5.3: greedy point vs reach")
    )
    return paths
