"""Figures of flock tracking, dilution of precision and time delays.

Each ``*_figure`` function takes a result object from the library and returns a matplotlib
:class:`~matplotlib.figure.Figure` (tests inspect its artists); :func:`save` writes one as PNG, and
:func:`filter_figures` / :func:`lab_figures` write every figure of a reproduction into a folder. Nothing is
shown on screen (matplotlib's Agg canvas is used directly, so no display or backend setting is needed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import LogNorm, Normalize
from matplotlib.figure import Figure

from oceanloc.estimation.time_delay import RecordingDelay
from oceanloc.evaluation.flock import FilterMonteCarlo, TrackingHdopMonteCarlo
from oceanloc.planning.dop import DopMap, PlacementResult, hdop_unit
from oceanloc.report.figures._style import save_figure
from oceanloc.reproduce.dillard_filters import DillardFiltersResult
from oceanloc.reproduce.dillard_lab_tdoa import LabTdoaResult
from oceanloc.sim.flock import scenario_sensor_model

__all__ = [
    "correlation_figure",
    "estimate_figure",
    "filter_figures",
    "geometry_figure",
    "hdop_map_figure",
    "lab_figures",
    "lab_residual_hdop_figure",
    "lab_tdoa_figure",
    "lab_track_figure",
    "placement_figure",
    "residuals_figure",
    "rmse_figure",
    "save",
]

_STATE_NAMES = ("x", "y", "u", "v", "ax", "ay")
_KIND_LABEL = {"bearing": "Bearing-only", "range": "Range-only", "tdoa": "TDOA"}
_TRUTH_STYLE = {"color": "k", "ls": "--", "lw": 1.4, "zorder": 5, "label": "true target track"}


def save(fig: Figure, path: Path) -> Path:
    """Write ``fig`` as PNG (see :func:`oceanloc.report.figures._style.save_figure`)."""
    return save_figure(fig, path)


def _draw_nodes(ax: Axes, mc: FilterMonteCarlo, lw: float) -> None:
    """Every node's drift path (one colour each) and its start (a dot)."""
    for i in range(mc.nodes_m.shape[1]):
        (line,) = ax.plot(mc.nodes_m[:, i, 0], mc.nodes_m[:, i, 1], lw=lw, label=f"node {i + 1}")
        ax.plot(*mc.nodes_m[0, i], "o", color=line.get_color(), ms=5)


def geometry_figure(mc: FilterMonteCarlo) -> Figure:
    """Thesis Figure 25: the nodes' drift paths (dots at their starts) and the target's track; the right
    panel zooms on the nodes at equal scale."""
    fig = Figure(figsize=(11, 4.5), layout="constrained")
    whole, zoom = fig.subplots(1, 2, width_ratios=[2, 1])
    for ax in (whole, zoom):
        _draw_nodes(ax, mc, 2.0)
        ax.plot(mc.truth[:, 0], mc.truth[:, 1], **_TRUTH_STYLE)
        ax.plot(*mc.truth[0, :2], "k*", ms=10, zorder=6, ls="none", label="target start")
        ax.set(xlabel="east (m)", ylabel="north (m)")
        ax.grid(alpha=0.3)
    n = mc.nodes_m.shape[1]
    layout = {"ring": "drifting on a ring", "y": "in a Y", "fixed": "fixed"}[mc.scenario.nodes.layout]
    whole.set_title(f"{n} nodes {layout}; the target's track")
    nodes = mc.nodes_m.reshape(-1, 2)
    centre = 0.5 * (nodes.min(axis=0) + nodes.max(axis=0))
    half = 0.6 * float(np.max(nodes.max(axis=0) - nodes.min(axis=0))) or 1.0
    zoom.set(xlim=(centre[0] - half, centre[0] + half), ylim=(centre[1] - half, centre[1] + half))
    zoom.set_aspect("equal")
    zoom.set_title("the nodes (equal scale)")
    zoom.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    return fig


def estimate_figure(mc: FilterMonteCarlo, key: str) -> Figure:
    """Thesis Figures 26 and 28: run 0's estimated positions and the true track drawn over them."""
    v = mc.variants[key]
    fig = Figure(figsize=(8, 5))
    ax = fig.add_subplot()
    _draw_nodes(ax, mc, 1.5)
    est = v.example_estimates
    ax.plot(
        est[:, 0], est[:, 1], ".", color="C4", ms=2.5, alpha=0.7, zorder=4, label=f"{v.variant.label}, run 0"
    )
    ax.plot(mc.truth[:, 0], mc.truth[:, 1], **_TRUTH_STYLE)
    kind = _KIND_LABEL.get(mc.scenario.kind, mc.scenario.kind)
    ax.set(
        xlabel="east (m)",
        ylabel="north (m)",
        title=f"{kind} tracking by {mc.nodes_m.shape[1]} nodes: {v.variant.label}",
    )
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, markerscale=4)
    return fig


def residuals_figure(mc: FilterMonteCarlo, key: str) -> Figure:
    """Thesis Figures 27 and 29: truth minus estimate of run 0 (position and velocity), with the Monte Carlo
    RMSE envelope."""
    v = mc.variants[key]
    t = mc.example_times_s
    idx = np.searchsorted(mc.times_s, t)
    diff = mc.truth[idx] - v.example_estimates
    rmse = v.rmse_time[idx]
    fig = Figure(figsize=(9, 6))
    axes = fig.subplots(2, 1, sharex=True)
    for ax, cols, what in ((axes[0], (0, 1), "position (m)"), (axes[1], (2, 3), "velocity (m/s)")):
        for c in cols:
            (line,) = ax.plot(t, diff[:, c], lw=0.8, label=f"{_STATE_NAMES[c]}, run 0")
            ax.fill_between(
                t,
                -rmse[:, c],
                rmse[:, c],
                color=line.get_color(),
                alpha=0.15,
                label=f"±RMSE {_STATE_NAMES[c]}",
            )
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylabel(f"truth - estimate,\n{what}")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
        lim = np.nanpercentile(np.abs(np.concatenate([diff[:, cols], rmse[:, cols]])), 99) * 1.3 or 1.0
        ax.set_ylim(-lim, lim)
    axes[0].set_title(f"Residuals: {v.variant.label} (RMSE over {mc.runs} runs)")
    axes[1].set_xlabel("time (s)")
    return fig


def rmse_figure(mc: FilterMonteCarlo) -> Figure:
    """Position RMSE over time of every variant beside the square root of the PCRLB."""
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    t = mc.times_s
    step = max(1, t.size // 4000)
    for v in mc.variants.values():
        pos = np.hypot(v.rmse_time[::step, 0], v.rmse_time[::step, 1])
        style = {"ls": ":", "lw": 2.0} if v.variant.is_control else {"ls": "-", "lw": 1.2}
        ax.semilogy(
            t[::step], pos, label=v.variant.label + (" [control]" if v.variant.is_control else ""), **style
        )
    ax.semilogy(t[::step], np.sqrt(mc.pcrlb_position_m2[::step]), "k--", lw=1, label="√PCRLB")
    ax.set(xlabel="time (s)", ylabel="position RMSE (m)", title=f"Position RMSE over {mc.runs} runs")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    return fig


def filter_figures(result: DillardFiltersResult, folder: Path) -> list[Path]:
    """Write the figures of ``reproduce dillard-filters`` (thesis Figures 25-29 and RMSE vs the bound)."""
    mc = result.monte_carlo
    figures = {"fig25_geometry.png": geometry_figure(mc)}
    for number, key in ((26, "ekf"), (28, "ukf")):
        figures[f"fig{number}_{key}_track.png"] = estimate_figure(mc, key)
        figures[f"fig{number + 1}_{key}_residuals.png"] = residuals_figure(mc, key)
    figures["rmse_vs_pcrlb.png"] = rmse_figure(mc)
    return [save(fig, folder / name) for name, fig in figures.items()]


def lab_residual_hdop_figure(mc: TrackingHdopMonteCarlo) -> Figure:
    """Thesis Figure 67: the position residual of run 0 and the HDOP at the same times."""
    fig = Figure(figsize=(9, 5))
    axes = fig.subplots(2, 1, sharex=True)
    t = mc.times_s
    axes[0].plot(t, mc.residual_m[0], lw=0.8, color="C0")
    axes[0].set(ylabel="position residual (m)", title="UKF: position residual and HDOP (run 0)")
    axes[1].plot(t, mc.hdop_m[0], lw=0.8, color="C1")
    axes[1].set(ylabel="HDOP (m)", xlabel="time (s)")
    for ax in axes:
        ax.axvspan(0.0, mc.settle_s, color="0.9", zorder=0)
    axes[0].text(
        0.5 * mc.settle_s,
        0.95,
        "settling",
        transform=axes[0].get_xaxis_transform(),
        ha="center",
        va="top",
        fontsize=7,
        color="0.4",
    )
    axes[1].text(
        0.03,
        0.95,
        f"Pearson r = {mc.pearson[0]:.2f} (mean over {mc.runs} runs {np.mean(mc.pearson):.2f})",
        transform=axes[1].transAxes,
        ha="left",
        va="top",
        fontsize=8,
        bbox={"facecolor": "white", "edgecolor": "0.7", "alpha": 0.9},
    )
    return fig


def lab_tdoa_figure(mc: TrackingHdopMonteCarlo) -> Figure:
    """Thesis Figure 62: the measurements before and after the noise (run 0), one colour per pair."""
    fig = Figure(figsize=(9, 5))
    ax = fig.add_subplot()
    t = mc.times_s
    scale, unit = (1e3, "ms") if mc.noise_unit == "s" else (1.0, mc.noise_unit)
    pairs = scenario_sensor_model(mc.scenario).pairs
    for p in range(mc.clean.shape[1]):
        what = f"nodes {pairs[p][0] + 1} - {pairs[p][1] + 1}" if pairs is not None else f"node {p + 1}"
        ax.plot(t, mc.measured[:, p] * scale, ".", ms=1.5, alpha=0.3, color=f"C{p}")
        ax.plot(t, mc.clean[:, p] * scale, lw=1.2, color=f"C{p}", label=f"{what}, true")
    ax.plot([], [], ".", color="0.5", label="noisy (dots)")
    name = "TDOA" if mc.scenario.kind == "tdoa" else mc.scenario.kind
    ax.set(
        xlabel="time (s)", ylabel=f"{name} ({unit})", title=f"{name} measurements of run 0: true and noisy"
    )
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, markerscale=2)
    return fig


def lab_track_figure(mc: TrackingHdopMonteCarlo) -> Figure:
    """Thesis Figure 63: run 0's estimated track and the true one over it, with the nodes."""
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot()
    ax.plot(mc.estimates[:, 0], mc.estimates[:, 1], "-", color="C3", lw=0.8, alpha=0.8, label="UKF estimate")
    ax.plot(mc.truth[:, 0], mc.truth[:, 1], **_TRUTH_STYLE)
    ax.plot(mc.nodes_m[:, 0], mc.nodes_m[:, 1], "b^", ms=9, ls="none", label="nodes")
    ax.set(xlabel="east (m)", ylabel="north (m)", title="UKF tracking of run 0 (simulated)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    return fig


def lab_figures(result: LabTdoaResult, folder: Path) -> list[Path]:
    """Write the figures of ``reproduce dillard-lab-tdoa`` (thesis Figures 62, 63 and 67)."""
    mc = result.monte_carlo
    return [
        save(lab_tdoa_figure(mc), folder / "fig62_tdoa.png"),
        save(lab_track_figure(mc), folder / "fig63_track.png"),
        save(lab_residual_hdop_figure(mc), folder / "fig67_residual_hdop.png"),
    ]


def hdop_map_figure(dop: DopMap) -> Figure:
    """Thesis Figure 32: HDOP as one node moves over the grid (log colour scale over a decade or more,
    singular cells blank)."""
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot()
    values = np.where(np.isfinite(dop.hdop), dop.hdop, np.nan)
    finite = values[np.isfinite(values)]
    norm = None
    if finite.size:
        lo, hi = float(finite.min()), float(np.percentile(finite, 99))
        # A log scale where the map spans a decade or more; a linear one (plain tick labels) otherwise.
        norm = LogNorm(vmin=lo, vmax=hi) if hi > 10 * lo else Normalize(vmin=lo, vmax=hi)
    mesh = ax.pcolormesh(dop.x_m, dop.y_m, values, shading="auto", norm=norm, cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=f"HDOP ({hdop_unit(dop.kind, dop.sigma)})")
    ax.plot(
        dop.fixed_nodes_m[:, 0], dop.fixed_nodes_m[:, 1], "w^", ms=10, mec="k", ls="none", label="fixed nodes"
    )
    ax.plot(*dop.target_m, "r*", ms=14, mec="k", ls="none", label="target")
    best = dop.minimum()
    if best is not None:
        ax.plot(
            best[1],
            best[2],
            "o",
            ms=11,
            mfc="none",
            mec="r",
            mew=2,
            ls="none",
            clip_on=False,
            label="lowest HDOP cell",
        )
    ax.set(xlabel="moving node east (m)", ylabel="moving node north (m)", title=f"{dop.kind} HDOP map")
    ax.set_aspect("equal")
    ax.legend(fontsize=8, loc="lower left", bbox_to_anchor=(0.0, 1.06), ncol=3, frameon=False)
    return fig


def placement_figure(result: PlacementResult) -> Figure:
    """Thesis Figures 34-35: local solutions from every start (dots), the even ring, the best placement
    (triangles) and the nodes already in place (squares)."""
    fig = Figure(figsize=(7, 6.5))
    ax = fig.add_subplot()
    pts = result.start_nodes_m.reshape(-1, 2)
    ax.plot(pts[:, 0], pts[:, 1], ".", color="0.6", ms=4, ls="none", label="local solutions")
    ring = result.ring_nodes_m
    ax.plot(ring[:, 0], ring[:, 1], "o", mfc="none", mec="C0", ms=10, ls="none", label="even ring")
    ax.plot(
        result.nodes_m[:, 0], result.nodes_m[:, 1], "^", color="C3", ms=10, ls="none", label="best placement"
    )
    if result.fixed_nodes_m.size:
        fx = result.fixed_nodes_m
        ax.plot(fx[:, 0], fx[:, 1], "s", color="C2", mec="k", ms=10, ls="none", label="fixed nodes")
    ax.plot(*result.target_m, "k*", ms=14, ls="none", label="target")
    unit = hdop_unit(result.kind, result.sigma)
    ax.set(
        xlabel="east (m)",
        ylabel="north (m)",
        title=f"{result.kind} HDOP-optimal placement: {result.hdop:.4g} {unit} (ring {result.ring_hdop:.4g})",
    )
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return fig


def correlation_figure(result: RecordingDelay, zoom_samples: int = 40) -> Figure:
    """Thesis Figure 17: the correlation of the two recordings against lag (the whole window returned by
    the estimate, and a zoom of ``zoom_samples`` samples each side of the peak), the chosen delay marked."""
    est = result.estimate
    names = tuple(Path(s).name for s in result.sources)
    fig = Figure(figsize=(9, 6), layout="constrained")
    axes = fig.subplots(2, 1)
    lag_ms = est.lags_s * 1e3
    half_ms = zoom_samples / est.sample_rate_hz * 1e3
    near = np.abs(lag_ms - est.delay_s * 1e3) <= half_ms
    for ax, keep, style in ((axes[0], slice(None), "-"), (axes[1], near, ".-")):
        ax.plot(lag_ms[keep], est.correlation[keep], style, lw=0.8, ms=3, label="correlation")
        ax.axvline(est.delay_s * 1e3, color="r", lw=1, ls="--", label=f"delay {est.delay_s * 1e3:.4f} ms")
        ax.set_ylabel("normalized\ncorrelation (1)")
    axes[0].axvspan(lag_ms[near][0], lag_ms[near][-1], color="0.85", zorder=0, label="zoom below")
    axes[0].set_title(
        f"{est.method}: {Path(result.first_source).name} heard it first (peak ratio {est.peak_ratio:.2f})"
    )
    axes[0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[0].set_xlabel("lag (ms)")
    axes[1].set_xlabel(f"lag (ms): arrival at {names[0]} minus arrival at {names[1]}")
    axes[1].set_title(f"zoom: ±{zoom_samples} samples around the peak", fontsize=9)
    return fig
