"""Figures for field data: GNSS-A residuals and tracks, localized logs (PNG through matplotlib)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from oceanloc.estimation.gnssa import GnssaResult
from oceanloc.io.gnssa import GnssaSurvey


def gnssa_residual_figure(survey: GnssaSurvey, result: GnssaResult, path: Path) -> Path:
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
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
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
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def gnssa_spread_figure(results: list[GnssaResult], path: Path) -> Path:
    """Per-survey positions with 1-sigma bars, relative to the mean, for E, N and U."""
    pos = np.array([r.position_enu_m for r in results])
    sig = np.array([r.sigma_enu_m for r in results])
    dev_cm = 100.0 * (pos - pos.mean(axis=0))
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.8), sharey=True)
    idx = np.arange(len(results))
    for k, (ax, name) in enumerate(zip(axes, ("east", "north", "up"), strict=True)):
        ax.errorbar(dev_cm[:, k], idx, xerr=100.0 * sig[:, k], fmt="o", capsize=3)
        ax.axvline(0.0, color="0.5", lw=0.8)
        ax.set(xlabel=f"{name} - mean [cm]", title=f"std {np.std(dev_cm[:, k], ddof=1):.1f} cm")
    axes[0].set_yticks(idx, [r.name.removeprefix("gnssa_data_") for r in results])
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _clip_limits(values: np.ndarray) -> tuple[float, float]:
    if values.size == 0:
        return -1.0, 1.0
    lo, hi = np.percentile(values, [0.5, 99.5])
    pad = 0.2 * (hi - lo) + 1e-3
    return float(lo - pad), float(hi + pad)
