"""Figures of flock tracking, dilution of precision and time delays, written as PNG.

Each function takes a result object from the library, writes one PNG and returns its path; nothing is
shown on screen (matplotlib's Agg canvas is used directly, so no display or backend setting is needed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure

from oceanloc.estimation.time_delay import DelayEstimate
from oceanloc.planning.dop import DopMap, PlacementResult
from oceanloc.report.figures._style import save_figure
from oceanloc.reproduce.dillard_filters import DillardFiltersResult
from oceanloc.reproduce.dillard_lab_tdoa import LabTdoaResult

_STATE_LABELS = ("x (m)", "y (m)", "u (m/s)", "v (m/s)", "ax (m/s²)", "ay (m/s²)")


def flock_geometry(result: DillardFiltersResult, path: Path) -> Path:
    """Thesis Figure 25: the nodes' drift paths and the target's track."""
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    for i in range(result.nodes_m.shape[1]):
        ax.plot(result.nodes_m[:, i, 0], result.nodes_m[:, i, 1], lw=2, label=f"node {i + 1}")
        ax.plot(*result.nodes_m[0, i], "k.", ms=6)
    ax.plot(result.truth[:, 0], result.truth[:, 1], "k--", lw=1, label="target")
    ax.set(xlabel="east (m)", ylabel="north (m)", title="Nodes drifting on a ring, target moving outward")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="best", fontsize=8)
    return save_figure(fig, path)


def estimate_vs_truth(result: DillardFiltersResult, key: str, path: Path) -> Path:
    """Thesis Figures 26 and 28: run 0's estimated positions over the true track."""
    v = result.variants[key]
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    for i in range(result.nodes_m.shape[1]):
        ax.plot(result.nodes_m[:, i, 0], result.nodes_m[:, i, 1], lw=1.5, label=f"node {i + 1}")
    ax.plot(result.truth[:, 0], result.truth[:, 1], "k-", lw=1, label="target")
    est = v.example_estimates
    ax.plot(est[:, 0], est[:, 1], "r+", ms=3, alpha=0.5, label="estimate")
    ax.set(
        xlabel="east (m)", ylabel="north (m)", title=f"Bearing-only tracking by four nodes: {v.variant.label}"
    )
    ax.legend(loc="best", fontsize=8)
    return save_figure(fig, path)


def residuals(result: DillardFiltersResult, key: str, path: Path) -> Path:
    """Thesis Figures 27 and 29: truth minus estimate of run 0 (position and velocity), with the Monte Carlo
    RMSE envelope."""
    v = result.variants[key]
    t = result.example_times_s
    truth = result.truth[np.searchsorted(result.times_s, t)]
    diff = truth - v.example_estimates
    rmse = v.rmse_time[np.searchsorted(result.times_s, t)]
    fig = Figure(figsize=(9, 6))
    axes = fig.subplots(2, 1, sharex=True)
    for ax, cols, what in ((axes[0], (0, 1), "position (m)"), (axes[1], (2, 3), "velocity (m/s)")):
        for c in cols:
            ax.plot(t, diff[:, c], lw=0.8, label=f"{_STATE_LABELS[c].split()[0]} (run 0)")
            ax.fill_between(
                t, -rmse[:, c], rmse[:, c], alpha=0.15, label=f"±RMSE {_STATE_LABELS[c].split()[0]}"
            )
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylabel(f"truth - estimate, {what}")
        ax.legend(loc="upper right", fontsize=7, ncol=2)
        lim = np.nanpercentile(np.abs(diff[:, cols]), 99) * 1.5 or 1.0
        ax.set_ylim(-lim, lim)
    axes[0].set_title(f"Residuals: {v.variant.label} ({result.runs} runs)")
    axes[1].set_xlabel("time (s)")
    return save_figure(fig, path)


def rmse_vs_bound(result: DillardFiltersResult, path: Path) -> Path:
    """Position RMSE over time of every variant beside the square root of the PCRLB."""
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    t = result.times_s
    step = max(1, t.size // 4000)
    for key, v in result.variants.items():
        pos = np.sqrt(v.rmse_time[::step, 0] ** 2 + v.rmse_time[::step, 1] ** 2)
        control = key.endswith("control")
        style = {"ls": ":", "lw": 2.0} if control else {"ls": "-", "lw": 1.0}
        ax.semilogy(t[::step], pos, label=v.variant.label + (" [control]" if control else ""), **style)
    ax.semilogy(t[::step], np.sqrt(result.pcrlb_position_m2[::step]), "k--", lw=1, label="sqrt(PCRLB)")
    ax.set(xlabel="time (s)", ylabel="position RMSE (m)", title=f"Position RMSE over {result.runs} runs")
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def lab_residual_and_hdop(result: LabTdoaResult, path: Path) -> Path:
    """Thesis Figure 67: the position residual of run 0 and the HDOP at the same times."""
    fig = Figure(figsize=(9, 5))
    axes = fig.subplots(2, 1, sharex=True)
    t = result.times_s
    axes[0].plot(t, result.residual_m[0], lw=0.8)
    axes[0].set(ylabel="position residual (m)", title="TDOA UKF: residual and HDOP (run 0)")
    axes[1].plot(t, result.hdop_m[0], lw=0.8, color="C1")
    axes[1].set(ylabel="HDOP (m)", xlabel="time (s)")
    r = result.pearson[0]
    axes[1].text(
        0.01,
        0.9,
        f"Pearson r = {r:.2f} (mean over runs {np.mean(result.pearson):.2f})",
        transform=axes[1].transAxes,
        fontsize=8,
    )
    return save_figure(fig, path)


def lab_tdoa_measurements(result: LabTdoaResult, path: Path) -> Path:
    """Thesis Figure 62: TDOA pseudo-measurements before and after the noise (run 0)."""
    fig = Figure(figsize=(9, 5))
    ax = fig.add_subplot()
    t = result.times_s
    for p in range(result.tdoa_clean_s.shape[1]):
        ax.plot(t, result.tdoa_noisy_s[:, p] * 1e3, ".", ms=1, alpha=0.3, color=f"C{p}")
        ax.plot(t, result.tdoa_clean_s[:, p] * 1e3, lw=1, color=f"C{p}", label=f"pair {p + 1}")
    ax.set(xlabel="time (s)", ylabel="TDOA (ms)", title="TDOA pseudo-measurements: true (lines) and noisy")
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def lab_track(result: LabTdoaResult, path: Path) -> Path:
    """Thesis Figure 63: run 0's estimated track over the true one, with the three nodes."""
    fig = Figure(figsize=(6, 6))
    ax = fig.add_subplot()
    ax.plot(result.truth[:, 0], result.truth[:, 1], "k-", lw=1, label="target")
    ax.plot(result.estimates[:, 0], result.estimates[:, 1], "r-", lw=0.6, alpha=0.7, label="UKF estimate")
    ax.plot(result.nodes_m[:, 0], result.nodes_m[:, 1], "b^", ms=9, label="nodes")
    ax.set(xlabel="x (m)", ylabel="y (m)", title="Lab TDOA test (simulated)")
    ax.set_aspect("equal")
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def hdop_map_figure(dop: DopMap, path: Path) -> Path:
    """Thesis Figure 32: HDOP as one node moves over the grid (log colour scale, singular cells blank)."""
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot()
    values = np.where(np.isfinite(dop.hdop), dop.hdop, np.nan)
    finite = values[np.isfinite(values)]
    norm = LogNorm(vmin=float(finite.min()), vmax=float(np.percentile(finite, 99))) if finite.size else None
    mesh = ax.pcolormesh(dop.x_m, dop.y_m, values, shading="auto", norm=norm, cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="HDOP (m)" if dop.sigma != 1.0 else "HDOP")
    ax.plot(dop.fixed_nodes_m[:, 0], dop.fixed_nodes_m[:, 1], "w^", ms=10, mec="k", label="fixed nodes")
    ax.plot(*dop.target_m, "r*", ms=14, mec="k", label="target")
    ax.set(xlabel="moving node east (m)", ylabel="moving node north (m)", title=f"{dop.kind} HDOP map")
    ax.set_aspect("equal")
    ax.legend(fontsize=8, loc="upper right")
    return save_figure(fig, path)


def placement_figure(result: PlacementResult, target_m: np.ndarray, kind: str, path: Path) -> Path:
    """Thesis Figures 34-35: local solutions from every start (dots) and the best placement (triangles)."""
    fig = Figure(figsize=(6, 6))
    ax = fig.add_subplot()
    pts = result.start_nodes_m.reshape(-1, 2)
    ax.plot(pts[:, 0], pts[:, 1], ".", color="0.6", ms=4, label="local solutions")
    ax.plot(
        result.ring_nodes_m[:, 0],
        result.ring_nodes_m[:, 1],
        "o",
        mfc="none",
        mec="C0",
        ms=10,
        label="even ring",
    )
    ax.plot(result.nodes_m[:, 0], result.nodes_m[:, 1], "^", color="C3", ms=10, label="best")
    ax.plot(*target_m, "k*", ms=14, label="target")
    ax.set(
        xlabel="east (m)",
        ylabel="north (m)",
        title=f"{kind} HDOP-optimal placement: {result.hdop:.4g} (ring {result.ring_hdop:.4g})",
    )
    ax.set_aspect("equal")
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def correlation_figure(estimate: DelayEstimate, path: Path, names: tuple[str, str] = ("A", "B")) -> Path:
    """Thesis Figure 17: the correlation of the two recordings against lag, the chosen delay marked."""
    fig = Figure(figsize=(8, 4))
    ax = fig.add_subplot()
    ax.plot(estimate.lags_s, estimate.correlation, lw=0.8)
    ax.axvline(estimate.delay_s, color="r", lw=1, ls="--", label=f"delay {estimate.delay_s * 1e3:.3f} ms")
    ax.set(
        xlabel=f"lag (s): arrival at {names[0]} minus arrival at {names[1]}",
        ylabel="normalized correlation",
        title=f"{estimate.method}: {names[0] if estimate.first == 'A' else names[1]} heard it first "
        f"(peak ratio {estimate.peak_ratio:.2f})",
    )
    ax.legend(fontsize=8)
    return save_figure(fig, path)
