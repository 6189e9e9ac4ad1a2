"""Figures for field data: GNSS-A residuals and tracks, localized logs (PNG through matplotlib)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from oceanloc.estimation.gnssa import GnssaResult
from oceanloc.estimation.noise import StationaryNoise
from oceanloc.field.gnssa_surveys import GnssaSurveys
from oceanloc.field.repeatability import SurveySpread
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
        fig = gnssa_spread_figure(list(surveys.results), surveys.spread)
        paths.append(save_figure(fig, folder / "gnssa_spread.png"))
    return paths


def gnssa_residual_figure(survey: GnssaSurvey, result: GnssaResult) -> Figure:
    """Residuals of one survey against time and horizontal offset, the track, and the sound speed.

    Used pings are dots, excluded pings crosses; the grey band is the per-ping +-1 sigma.
    """
    used = result.used
    t_min = (survey.t_transmit_s - survey.t_transmit_s[0]) / 60.0
    offset = np.hypot(
        survey.transmit_enu_m[:, 0] - result.position_enu_m[0],
        survey.transmit_enu_m[:, 1] - result.position_enu_m[1],
    )
    resid_cm = 100.0 * result.residual_m
    fig = Figure(figsize=(11, 7.5))
    axes = fig.subplots(2, 2)
    ax = axes[0, 0]
    order = np.argsort(t_min)
    ax.fill_between(t_min[order], -100 * result.sigma_m[order], 100 * result.sigma_m[order], color="0.85")
    ax.plot(t_min[used], resid_cm[used], ".", ms=3, label="used")
    ax.plot(t_min[~used], resid_cm[~used], "x", color="C3", label="excluded")
    ax.set(xlabel="time since first ping [min]", ylabel="residual c TWTT - path [cm]")
    ax.set_ylim(*_clip_limits(resid_cm[used]))
    ax.legend(loc="upper right", fontsize=8)
    ax = axes[0, 1]
    ax.plot(offset[used], resid_cm[used], ".", ms=3)
    ax.plot(offset[~used], resid_cm[~used], "x", color="C3")
    ax.set(xlabel="horizontal offset from transponder [m]", ylabel="residual [cm]")
    ax.set_ylim(*_clip_limits(resid_cm[used]))
    ax = axes[1, 0]
    ax.plot(survey.transmit_enu_m[:, 0], survey.transmit_enu_m[:, 1], "-", lw=0.5, color="0.6")
    sc = ax.scatter(
        survey.transmit_enu_m[used, 0], survey.transmit_enu_m[used, 1], c=resid_cm[used], s=6, cmap="coolwarm"
    )
    ax.plot(*result.position_enu_m[:2], "k*", ms=10, label="transponder")
    ax.set(xlabel="east [m]", ylabel="north [m]", aspect="equal")
    fig.colorbar(sc, ax=ax, label="residual [cm]")
    ax = axes[1, 1]
    if result.knot_times_s.size:
        ax.plot((result.knot_times_s - survey.t_transmit_s[0]) / 60.0, result.sound_speed_knots_mps, "o-")
    ax.set(xlabel="time since first ping [min]", ylabel="sound speed [m/s]")
    e, n, u = result.position_enu_m
    se, sn, su = result.sigma_enu_m
    fig.suptitle(
        f"{survey.name}: E {e:+.3f}±{se:.3f}  N {n:+.3f}±{sn:.3f}  U {u:+.3f}±{su:.3f} m, "
        f"{result.pings_used} pings, RMS {100 * result.residual_rms_m:.1f} cm"
    )
    fig.tight_layout()
    return fig


def gnssa_spread_figure(results: list[GnssaResult], spread: SurveySpread) -> Figure:
    """Per-survey positions at the spread's reference epoch with 1-sigma bars, relative to the mean, for
    E, N and U."""
    pos, sig = spread.positions_enu_m, spread.sigma_enu_m
    dev_cm = 100.0 * (pos - pos.mean(axis=0))
    fig = Figure(figsize=(11, 3.8))
    axes = fig.subplots(1, 3, sharey=True)
    idx = np.arange(len(results))
    for k, (ax, name) in enumerate(zip(axes, ("east", "north", "up"), strict=True)):
        ax.errorbar(dev_cm[:, k], idx, xerr=100.0 * sig[:, k], fmt="o", capsize=3)
        ax.axvline(0.0, color="0.5", lw=0.8)
        ax.set(xlabel=f"{name} - mean [cm]", title=f"std {np.std(dev_cm[:, k], ddof=1):.1f} cm")
    axes[0].set_yticks(idx, [r.name.removeprefix("gnssa_data_") for r in results])
    moved = "as surveyed" if spread.velocity is None else f"moved to one epoch ({spread.velocity.source})"
    fig.suptitle(f"GNSS-A positions across surveys, {moved}", fontsize=10)
    fig.tight_layout()
    return fig


def write_range_noise_figure(noise: list[StationaryNoise], path: Path) -> Path:
    """``localize noise --figures``: :func:`range_noise_figure` as PNG."""
    return save_figure(range_noise_figure(noise), path)


def range_noise_figure(noise: list[StationaryNoise]) -> Figure:
    """Running range and noise estimates of eq. (30) per beacon, with +-1 standard error (PLANS Fig. 5)."""
    fig = Figure(figsize=(10, 3.6 * len(noise)))
    axes = fig.subplots(len(noise), 2, squeeze=False)
    for (ax_r, ax_s), est in zip(axes, noise, strict=True):
        run = est.running
        i = np.arange(1, run.range_m.size + 1)
        se_r = run.sigma_m / np.sqrt(i)
        ax_r.plot(i, run.range_m, "+", color="C3", ms=4)
        ax_r.axhline(run.final_range_m, color="C3")
        ax_r.plot(i, run.final_range_m + se_r, color="C0", lw=0.8)
        ax_r.plot(i, run.final_range_m - se_r, color="C0", lw=0.8)
        ax_r.set(xlabel="number of data n", ylabel=f"range to beacon {est.beacon} [m]")
        ax_r.set_title(f"segment {est.segment}: {est.t_end_s - est.t_start_s:.0f} s", fontsize=9)
        ax_s.plot(i, 1e3 * run.sigma_m, ".", color="C0", ms=3)
        ax_s.axhline(1e3 * est.sigma_m, color="C3")
        ax_s.fill_between(
            i,
            1e3 * (run.sigma_m - run.sigma_of_sigma_m),
            1e3 * (run.sigma_m + run.sigma_of_sigma_m),
            color="0.85",
        )
        ax_s.set(
            xlabel="number of data n",
            ylabel="sigma [mm]",
            title=f"beacon {est.beacon}, segment {est.segment}: "
            f"{1e3 * est.sigma_m:.0f} ± {1e3 * est.sigma_se_m:.0f} mm,"
            f" {est.n_outliers} outliers removed",
        )
        ax_s.set_ylim(0.0, 3e3 * est.sigma_m)
    fig.tight_layout()
    return fig


def _clip_limits(values: np.ndarray) -> tuple[float, float]:
    if values.size == 0:
        return -1.0, 1.0
    lo, hi = np.percentile(values, [0.5, 99.5])
    pad = 0.2 * (hi - lo) + 1e-3
    return float(lo - pad), float(hi + pad)
