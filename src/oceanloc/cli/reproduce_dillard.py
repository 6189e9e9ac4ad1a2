"""``oceanloc reproduce dillard-filters`` and ``oceanloc reproduce dillard-lab-tdoa`` (AquaQuad thesis)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from oceanloc.cli import reproduce
from oceanloc.cli._common import (
    Scheduler,
    Workers,
    console,
    ensure_dir,
    err_console,
    progress_bar,
    write_json,
)
from oceanloc.config.flock import load_flock_scenario
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.reproduce.dillard_filters import (
    METRICS,
    THESIS_RUN_TIME_S,
    THESIS_TABLE_2,
    DillardFiltersResult,
    reproduce_dillard_filters,
)
from oceanloc.reproduce.dillard_lab_tdoa import (
    THESIS_MEAN_ABS_NOISE_S,
    THESIS_MSE_X_M2,
    THESIS_MSE_Y_M2,
    LabTdoaResult,
    reproduce_dillard_lab_tdoa,
)

_ROW_NAMES = ("X (m²)", "Y (m²)", "U (m/s)²", "V (m/s)²")

_SCENARIO_HELP = "Built-in flock scenario name or TOML file."


def _pm(mean: float, spread: float) -> str:
    return f"{mean:.4g} ± {spread:.2g}"


def print_table_2(res: DillardFiltersResult) -> None:
    """Table 2 with the thesis' single-run values beside our Monte Carlo mean ± sd and paired delta ± SE."""
    ekf, ukf = res.variants["ekf"], res.variants["ukf"]
    table = Table(title=f"Table 2: bearing-only tracking MSE, thesis (1 run) vs oceanloc ({res.runs} runs)")
    for col in ("state", "thesis EKF", "EKF mean ± sd", "thesis UKF", "UKF mean ± sd", "thesis Δ", "Δ ± SE"):
        table.add_column(col, justify="right")
    delta, se = res.paired_difference("ekf", "ukf")
    for i, (name, key) in enumerate(zip(_ROW_NAMES, METRICS, strict=True)):
        te, tu = THESIS_TABLE_2["ekf"][key], THESIS_TABLE_2["ukf"][key]
        table.add_row(
            name,
            f"{te:.4f}",
            _pm(ekf.mse_mean[i], ekf.mse_sd[i]),
            f"{tu:.4f}",
            _pm(ukf.mse_mean[i], ukf.mse_sd[i]),
            f"{te - tu:.4f}",
            _pm(delta[i], se[i]),
        )
    console.print(table)
    stats = Table(title="Per filter: consistency, efficiency, cost")
    for col in ("filter", "position MSE (m²)", "NEES (n=6)", "RMSE/√PCRLB", "step/track (µs)", "one run (s)"):
        stats.add_column(col, justify="right")
    n_steps = res.times_s.size
    for key, v in res.variants.items():
        thesis = f" (thesis {THESIS_RUN_TIME_S[key]:.2f})" if key in THESIS_RUN_TIME_S else ""
        stats.add_row(
            v.variant.label + (" [control]" if key.endswith("control") else ""),
            f"{v.mse_mean[0] + v.mse_mean[1]:.4g}",
            f"{v.nees_mean:.3g}",
            f"{v.rmse_over_sqrt_pcrlb:.3g}",
            f"{v.step_time_s * 1e6:.1f}",
            f"{v.step_time_s * n_steps:.3g}{thesis}",
        )
    console.print(stats)
    pos = delta[0] + delta[1]
    pos_se = float(np.hypot(se[0], se[1]))
    verdict = "below" if pos > 0 else "not below"
    console.print(
        f"UKF position MSE is {verdict} the EKF's: EKF - UKF = {pos:.4g} ± {pos_se:.2g} m² (paired, 1 SE)."
    )
    if "ekf-control" in res.variants:
        d_same, se_same = res.paired_difference("ekf-control", "ukf")
        console.print(
            f"With the same motion model ({res.variants['ukf'].variant.motion}) EKF - UKF = "
            f"{d_same[0] + d_same[1]:.4g} ± {np.hypot(se_same[0], se_same[1]):.2g} m²: the gap comes from "
            "the motion model, not from the unscented transform (alpha = "
            f"{res.scenario.filters.ukf_alpha:g})."
        )


@reproduce.app.command("dillard-filters")
def dillard_filters(
    runs: int = typer.Option(100, "--runs", min=1, help="Monte Carlo runs."),
    seed: int | None = typer.Option(None, "--seed", help="Master seed (default: the scenario's)."),
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Write the Table 2 figures as JSON.")
    ] = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help="Folder for the PNG figures (Figs. 25-29).")
    ] = None,
    scenario: str = typer.Option("dillard-filters", "--scenario", help=_SCENARIO_HELP),
    duration: float | None = typer.Option(None, "--duration", min=0.0, help="Override the duration (s)."),
    controls: bool = typer.Option(
        True, "--controls/--no-controls", help="Also run each filter with the other's motion model."
    ),
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Thesis Table 2: EKF vs UKF bearing-only tracking by four drifting nodes (Chapter III.E)."""
    from oceanloc.report.figures import flock as flock_figures

    sc = load_flock_scenario(scenario)
    if duration is not None:
        sc = sc.with_overrides(duration_s=duration)
    with open_executor(scheduler, workers) as executor, progress_bar(runs, "Monte Carlo runs") as advance:
        res = reproduce_dillard_filters(
            sc, runs=runs, seed=seed, controls=controls, executor=executor, progress=advance
        )
    print_table_2(res)
    if json_path is not None:
        write_json(json_path, res.to_json())
    if figures is not None:
        folder = ensure_dir(figures)
        written = [
            flock_figures.flock_geometry(res, folder / "fig25_geometry.png"),
            flock_figures.estimate_vs_truth(res, "ekf", folder / "fig26_ekf_track.png"),
            flock_figures.residuals(res, "ekf", folder / "fig27_ekf_residuals.png"),
            flock_figures.estimate_vs_truth(res, "ukf", folder / "fig28_ukf_track.png"),
            flock_figures.residuals(res, "ukf", folder / "fig29_ukf_residuals.png"),
            flock_figures.rmse_vs_bound(res, folder / "rmse_vs_pcrlb.png"),
        ]
        err_console.print(f"wrote {len(written)} figures to {folder}")


def print_lab(res: LabTdoaResult) -> None:
    """The lab test's figures beside ours."""
    table = Table(title=f"Lab TDOA UKF test (Chapter V.C): thesis (1 run) vs oceanloc ({res.runs} runs)")
    for col in ("quantity", "thesis", "oceanloc mean ± sd", "median"):
        table.add_column(col, justify="right")

    def row(name: str, thesis: str, values: np.ndarray, scale: float = 1.0) -> None:
        sd = float(np.std(values, ddof=1)) if values.size > 1 else 0.0
        median = f"{float(np.median(values)) * scale:.4g}"
        table.add_row(name, thesis, _pm(float(np.mean(values)) * scale, sd * scale), median)

    row("position MSE X (m²)", f"{THESIS_MSE_X_M2}", res.mse_xy_m2[:, 0])
    row("position MSE Y (m²)", f"{THESIS_MSE_Y_M2}", res.mse_xy_m2[:, 1])
    row("mean |TDOA noise| (ms)", f"{THESIS_MEAN_ABS_NOISE_S * 1e3:.1f}", res.mean_abs_noise_s, 1e3)
    row("corr(residual, HDOP), Pearson", "peaks coincide (Fig. 67)", res.pearson)
    row("corr(residual, HDOP), Spearman", "-", res.spearman)
    row("NIS / dof (R is half the noise)", "-", res.nis_ratio)
    console.print(table)


@reproduce.app.command("dillard-lab-tdoa")
def dillard_lab_tdoa(
    runs: int = typer.Option(20, "--runs", min=1, help="Monte Carlo runs (random target paths)."),
    seed: int | None = typer.Option(None, "--seed", help="Master seed (default: the scenario's)."),
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the summary as JSON.")] = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help="Folder for the PNG figures (Figs. 62, 63, 67).")
    ] = None,
    scenario: str = typer.Option("dillard-lab-tdoa", "--scenario", help=_SCENARIO_HELP),
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Thesis lab test: TDOA UKF, three nodes in a Y, random target; residual vs HDOP (Chapter V.C)."""
    from oceanloc.report.figures import flock as flock_figures

    with open_executor(scheduler, workers) as executor, progress_bar(runs, "Monte Carlo runs") as advance:
        res = reproduce_dillard_lab_tdoa(scenario, runs=runs, seed=seed, executor=executor, progress=advance)
    print_lab(res)
    if json_path is not None:
        write_json(json_path, res.to_json())
    if figures is not None:
        folder = ensure_dir(figures)
        flock_figures.lab_tdoa_measurements(res, folder / "fig62_tdoa.png")
        flock_figures.lab_track(res, folder / "fig63_track.png")
        flock_figures.lab_residual_and_hdop(res, folder / "fig67_residual_hdop.png")
        err_console.print(f"wrote 3 figures to {folder}")
