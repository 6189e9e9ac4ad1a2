"""Figures for field data: GNSS-A residuals and tracks, localized logs (PNG through matplotlib)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from oceanloc.estimation.gnssa import GnssaResult, gnssa_epoch_utc
from oceanloc.estimation.noise import StationaryNoise
from oceanloc.field.gnssa_surveys import GnssaSurveys
from oceanloc.io.gnssa import GnssaSurvey
from oceanloc.report.figures._style import save_figure


def write_gnssa_figures(surveys: GnssaSurveys, folder: Path) -> list[Path]:
    """Every figure of ``localize gnssa --figures``: ``<survey>_residuals.png`` per survey and, for two or
    more surveys, ``gnssa_spread.png``."""
    paths = [
        save_figure(gnssa_residual_figure(s, r), folder / f"{s.name}_residuals.png")
        for s, r in zip(surveys.surveys, surveys.results, strict=True)
    ]
    if surveys.spread is not None:
        fig = gnssa_spread_figure(surveys)
        paths.append(save_figure(fig, folder / "gnssa_spread.png"))
    return paths


def gnssa_residual_figure(survey: GnssaSurvey, result: GnssaResult) -> Figure:
    """Residuals of one survey against time and horizontal offset, the track coloured by residual, and
    the estimated sound speed.

    Used pings are dots, excluded pings red crosses (those beyond the axis drawn at its edge as
    triangles); the grey band is the per-ping +-1 sigma.
    """
    used = result.used
    t_min = (survey.t_transmit_s - survey.t_transmit_s[0]) / 60.0
    offset = np.hypot(
        survey.transmit_enu_m[:, 0] - result.position_enu_m[0],
        survey.transmit_enu_m[:, 1] - result.position_enu_m[1],
    )
    resid_cm = 100.0 * result.residual_m
    lo, hi = _clip_limits(resid_cm[used])
    fig = Figure(figsize=(11, 8.5), layout="constrained")
    axes = fig.subplots(2, 2)
    ax = axes[0, 0]
    order = np.argsort(t_min)
    sig_cm = 100 * result.sigma_m[order]
    ax.fill_between(t_min[order], -sig_cm, sig_cm, color="0.85", label="±1σ per ping")
    ax.plot(t_min[used], resid_cm[used], ".", ms=3, color="C0", label=f"used ({int(used.sum())})")
    _excluded(ax, t_min[~used], resid_cm[~used], lo, hi)
    ax.set(xlabel="time since first ping [min]", ylabel="residual c TWTT - path [cm]", ylim=(lo, hi))
    ax.set_title("(a) residuals against time", fontsize=10)
    ax = axes[0, 1]
    ax.plot(offset[used], resid_cm[used], ".", ms=3, color="C0")
    _excluded(ax, offset[~used], resid_cm[~used], lo, hi)
    ax.set(xlabel="horizontal offset from transponder [m]", ylabel="residual [cm]", ylim=(lo, hi))
    ax.set_title("(b) residuals against offset (far pings: ray bending)", fontsize=10)
    ax = axes[1, 0]
    ax.plot(survey.transmit_enu_m[:, 0], survey.transmit_enu_m[:, 1], "-", lw=0.5, color="0.6", label="track")
    vmax = float(np.percentile(np.abs(resid_cm[used]), 99)) if used.any() else 1.0
    sc = ax.scatter(
        survey.transmit_enu_m[used, 0], survey.transmit_enu_m[used, 1], c=resid_cm[used], s=6,
        cmap="coolwarm", vmin=-vmax, vmax=vmax,
    )  # fmt: skip
    ax.plot(*result.position_enu_m[:2], "k*", ms=12, label="transponder (estimate)")
    ax.set(xlabel="east [m]", ylabel="north [m]", aspect="equal")
    ax.set_title("(c) transmit positions, coloured by residual", fontsize=10)
    fig.colorbar(sc, ax=ax, label="residual [cm]")
    ax = axes[1, 1]
    if result.knot_times_s.size:
        knots_min = (result.knot_times_s - survey.t_transmit_s[0]) / 60.0
        ax.plot(knots_min, result.sound_speed_knots_mps, "o-", color="C0", label="estimated knots")
        ax.legend(loc="best", fontsize=8)
    else:
        ax.axhline(result.sound_speed_mps, color="C0", label="one constant speed")
        ax.legend(loc="best", fontsize=8)
    ax.set(xlabel="time since first ping [min]", ylabel="sound speed [m/s]")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_title("(d) harmonic-mean sound speed", fontsize=10)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    more, more_labels = axes[1, 0].get_legend_handles_labels()
    fig.legend(handles + more, labels + more_labels, loc="outside lower center", ncol=6, fontsize=8)
    e, n, u = result.position_enu_m
    se, sn, su = result.sigma_enu_m
    fig.suptitle(
        f"{survey.name}: E {e:+.3f} ± {se:.3f}, N {n:+.3f} ± {sn:.3f}, U {u:+.3f} ± {su:.3f} m (1σ), "
        f"{result.pings_used} pings used, RMS {100 * result.residual_rms_m:.1f} cm",
        fontsize=11,
    )
    return fig


def _excluded(ax, x: np.ndarray, y: np.ndarray, lo: float, hi: float) -> None:
    """Excluded pings as red crosses; those beyond the y-axis at its edge as triangles pointing out."""
    inside = (y >= lo) & (y <= hi)
    ax.plot(x[inside], y[inside], "x", color="C3", label=f"excluded ({x.size})")
    ax.plot(x[y > hi], np.full(int((y > hi).sum()), hi), "^", color="C3", ms=5,
            label="excluded, beyond the axis")  # fmt: skip
    ax.plot(x[y < lo], np.full(int((y < lo).sum()), lo), "v", color="C3", ms=5)


def gnssa_spread_figure(surveys: GnssaSurveys) -> Figure:
    """Per-survey positions relative to their mean with 1-sigma bars, for E, N and U: filled at the
    spread's reference epoch (moved by the site velocity), hollow as surveyed."""
    spread, raw = surveys.spread, surveys.as_surveyed
    if spread is None or raw is None:
        raise ValueError("the spread figure needs two or more surveys")
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    axes = fig.subplots(1, 3, sharey=True)
    idx = np.arange(spread.n_surveys)
    moved = spread.velocity is not None
    for k, (ax, name) in enumerate(zip(axes, ("east", "north", "up"), strict=True)):
        if moved:
            dev = 100.0 * (raw.positions_enu_m[:, k] - raw.positions_enu_m[:, k].mean())
            ax.plot(dev, idx + 0.15, "o", mfc="none", color="0.5", label="as surveyed")
        dev = 100.0 * (spread.positions_enu_m[:, k] - spread.positions_enu_m[:, k].mean())
        label = "at one epoch, ±1σ" if moved else "as surveyed, ±1σ"
        ax.errorbar(
            dev, idx, xerr=100.0 * spread.sigma_enu_m[:, k], fmt="o", capsize=3, color="C0", label=label
        )
        ax.axvline(0.0, color="0.5", lw=0.8)
        ax.set(xlabel=f"{name} - mean [cm]")
        std, rms = 100 * spread.std_enu_m[k], 100 * spread.rms_sigma_enu_m[k]
        ax.set_title(f"{name}: std {std:.1f} cm, RMS σ {rms:.1f} cm", fontsize=10)
        ax.grid(axis="x", alpha=0.3)
    names = [r.name.removeprefix("gnssa_data_").replace("$", r"\$") for r in surveys.results]
    axes[0].set_yticks(idx, names)
    axes[0].set_ylim(-0.6, spread.n_surveys - 0.4)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    if moved:
        v = spread.velocity.velocity_enu_mm_yr
        epoch = gnssa_epoch_utc(spread.reference_epoch_s)[:10]
        how = f"moved to {epoch} by {spread.velocity.source} (E {v[0]:+.1f}, N {v[1]:+.1f} mm/yr)"
    else:
        how = "as surveyed (no site velocity)"
    fig.suptitle(f"GNSS-A positions across {spread.n_surveys} surveys, {how}", fontsize=10)
    return fig


def write_range_noise_figure(noise: list[StationaryNoise], path: Path) -> Path:
    """``localize noise --figures``: :func:`range_noise_figure` as PNG."""
    return save_figure(range_noise_figure(noise), path)


def range_noise_figure(noise: list[StationaryNoise]) -> Figure:
    """Running range and noise estimates of eq. (30) per beacon, with +-1 standard error (PLANS Fig. 5)."""
    fig = Figure(figsize=(10, 3.8 * len(noise)))
    axes = fig.subplots(len(noise), 2, squeeze=False)
    for (ax_r, ax_s), est in zip(axes, noise, strict=True):
        run = est.running
        i = np.arange(1, run.range_m.size + 1)
        se_r = run.sigma_m / np.sqrt(i)
        ax_r.plot(i, run.range_m, "+", color="C3", ms=4, label="running mean")
        ax_r.axhline(run.final_range_m, color="C3", label="final estimate")
        ax_r.plot(i, run.final_range_m + se_r, color="C0", lw=0.8, label="±1 standard error")
        ax_r.plot(i, run.final_range_m - se_r, color="C0", lw=0.8)
        ax_r.set(xlabel="stationary ranges used n", ylabel=f"range to beacon {est.beacon} [m]")
        span = est.t_end_s - est.t_start_s
        ax_r.set_title(f"beacon {est.beacon}, segment {est.segment} ({span:.0f} s): range", fontsize=10)
        ax_r.legend(loc="upper right", fontsize=8)
        ax_s.fill_between(
            i, 1e3 * (run.sigma_m - run.sigma_of_sigma_m), 1e3 * (run.sigma_m + run.sigma_of_sigma_m),
            color="0.85", label="±1 standard error",
        )  # fmt: skip
        ax_s.plot(i, 1e3 * run.sigma_m, ".", color="C0", ms=3, label="running σ")
        ax_s.axhline(1e3 * est.sigma_m, color="C3", label="final σ")
        ax_s.set(xlabel="stationary ranges used n", ylabel="range noise σ [mm]")
        ax_s.set_title(
            f"beacon {est.beacon}: σ = {1e3 * est.sigma_m:.0f} ± {1e3 * est.sigma_se_m:.0f} mm, "
            f"{est.n_outliers} outliers removed",
            fontsize=10,
        )
        ax_s.set_ylim(0.0, 3e3 * est.sigma_m)
        ax_s.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig


def _clip_limits(values: np.ndarray) -> tuple[float, float]:
    if values.size == 0:
        return -1.0, 1.0
    lo, hi = np.percentile(values, [0.5, 99.5])
    pad = 0.2 * (hi - lo) + 1e-3
    return float(lo - pad), float(hi + pad)
