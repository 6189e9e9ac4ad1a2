"""``oceanloc simulate survey`` and ``oceanloc demo``: closed-loop transponder surveys on any scenario."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from oceanloc.cli import root, simulate
from oceanloc.cli._common import (
    FiguresOut,
    JsonOut,
    Scheduler,
    Seed,
    Workers,
    console,
    ensure_dir,
    progress_bar,
    write_json,
)
from oceanloc.config.survey import PlannerSettings, SurveyScenario, load_survey_scenario
from oceanloc.estimation.consistency import confidence_ellipse
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.evaluation.survey import SurveyMonteCarlo, survey_monte_carlo
from oceanloc.planning.site_planners import parse_site_planner, site_planner_label, site_planner_name
from oceanloc.sim.survey import SurveyRuns, simulate_surveys

_REPORT_EPOCHS = (3, 7, 30)


@simulate.app.command("survey")
def survey_command(
    scenario: str = typer.Option(
        ..., "--scenario", help="Scenario TOML file, or a built-in name (oceanloc scenarios list)."
    ),
    runs: int | None = typer.Option(
        None, "--runs", min=1, help="Runs (default: the scenario's; 1: one survey)."
    ),
    planner: str | None = typer.Option(
        None,
        "--planner",
        help="Override the planner: k0 (random yaw), k1..k10 (look-ahead), greedy, random-disk.",
    ),
    horizon: int | None = typer.Option(None, "--horizon", min=1, help="Override the look-ahead steps k."),
    epochs: int | None = typer.Option(None, "--epochs", min=1, help="Override the number of epochs N."),
    seed: Seed = None,
    json_path: JsonOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Simulate a transponder survey: one run prints each transponder's truth, estimate, error and 95 %
    ellipse; many runs print the Monte Carlo metrics (RMSEE, log det Y_n, NEES, planning time)."""
    scen = _with_overrides(load_survey_scenario(scenario), planner, horizon, epochs)
    n_runs = scen.runs if runs is None else runs
    seed = scen.seed if seed is None else seed
    if n_runs == 1:
        _single_run(scen, seed, json_path, figures)
        return
    with open_executor(scheduler, workers) as executor, progress_bar(n_runs, "Monte Carlo runs") as advance:
        result = survey_monte_carlo(scen, n_runs, seed, executor=executor, progress=advance)
    _monte_carlo_report(result, json_path, figures)


@root.app.command("demo")
def demo_command(
    out: Annotated[Path, typer.Option("--out", help="Folder for the trajectory figure.")] = Path(
        "oceanloc-demo"
    ),
    seed: Seed = None,
) -> None:
    """The built-in four-transponder survey (journal Table IV), k = 2 look-ahead planner, 50 epochs."""
    scen = load_survey_scenario("garcia2019-m4").with_planner(PlannerSettings(kind="lookahead", horizon=2))
    console.print(f"[bold]{scen.name}[/bold]: {scen.description}; planner k = 2, {scen.epochs} epochs")
    _single_run(scen, scen.seed if seed is None else seed, None, out)


def _with_overrides(
    scen: SurveyScenario, planner: str | None, horizon: int | None, epochs: int | None
) -> SurveyScenario:
    if planner is not None or horizon is not None:
        cur = scen.planner
        keep = "lookahead" if cur.kind == "lookahead" else site_planner_name(cur)
        scen = scen.with_planner(
            parse_site_planner(
                planner or keep, horizon=horizon or cur.horizon, max_distance_m=cur.max_distance_m
            )
        )
    if epochs is not None:
        scen = dataclasses.replace(scen, epochs=epochs)
    return scen


def _single_run(scen: SurveyScenario, seed: int, json_path: Path | None, figures: Path | None) -> None:
    from oceanloc.report.figures import survey as survey_figures

    run = simulate_surveys(scen, [0], seed)
    final = run.estimates_m[0, -1]
    cov = run.covariances_m2[0, -1]
    ell = confidence_ellipse(final[:, :2], cov[:, :2, :2])
    sigma_u = np.sqrt(cov[:, 2, 2])
    table = Table(
        title=f"After {scen.epochs} epochs (planner {site_planner_label(scen.planner)}, seed {seed})"
    )
    columns = ("m", "truth E, N, U (m)", "estimate E, N, U (m)", "error (m)", "95% ellipse a x b (m), dir")
    for col in (*columns, "1-sigma U (m)"):
        table.add_column(col, justify="right")
    errors = np.linalg.norm(run.errors_m[0, -1], axis=-1)
    for m in range(scen.n_transponders):
        table.add_row(
            str(m + 1), _triple(scen.transponders_enu_m[m]), _triple(final[m]), f"{errors[m]:.3f}",
            f"{ell.semi_major_m[m]:.3f} x {ell.semi_minor_m[m]:.3f}, {np.degrees(ell.angle_rad[m]):+.0f} deg",
            f"{sigma_u[m]:.3f}",
        )  # fmt: skip
    console.print(table)
    console.print(_epoch_table(run, scen))
    console.print(
        f"NEES at n = {scen.epochs}: {run.nees[0, -1]:.2f} (chi-square, {3 * scen.n_transponders} dof); "
        f"mean planning time {run.plan_time_s.mean() * 1e3:.2f} ms per epoch"
    )
    if figures:
        out = ensure_dir(figures)
        path = survey_figures.trajectories_figure(
            {f"planner {site_planner_label(scen.planner)}": run}, out / f"{scen.name}_trajectory.png",
            f"{scen.name}: measurement path and 95% ellipses", ellipses=True,
        )  # fmt: skip
        console.print(f"wrote {path}")
    if json_path:
        write_json(
            json_path,
            {
                "scenario": scen.name,
                "planner": site_planner_name(scen.planner),
                "seed": seed,
                "transponders": [
                    {
                        "m": m + 1,
                        "truth_enu_m": scen.transponders_enu_m[m],
                        "estimate_enu_m": final[m],
                        "error_m": errors[m],
                        "ellipse95_semi_axes_m": [ell.semi_major_m[m], ell.semi_minor_m[m]],
                        "ellipse95_angle_deg": np.degrees(ell.angle_rad[m]),
                        "sigma_u_m": sigma_u[m],
                    }
                    for m in range(scen.n_transponders)
                ],
                "log_det": run.log_det[0],
                "error_norm_m": np.linalg.norm(run.errors_m[0], axis=-1),
                "sites_enu_m": run.sites_enu_m[0],
                "nees_final": run.nees[0, -1],
            },
        )


def _epoch_table(run: SurveyRuns, scen: SurveyScenario) -> Table:
    epochs = [n for n in (*_REPORT_EPOCHS, scen.epochs) if n <= scen.epochs]
    table = Table(title="Error and D-optimal value by epoch")
    table.add_column("epoch n", justify="right")
    for m in range(scen.n_transponders):
        table.add_column(f"error m={m + 1} (m)", justify="right")
    table.add_column("RMSEE over m (m)", justify="right")
    table.add_column("log det Y_n", justify="right")
    norms = np.linalg.norm(run.errors_m[0], axis=-1)
    for n in sorted(set(epochs)):
        row = [f"{v:.3f}" for v in norms[n - 1]]
        table.add_row(
            str(n), *row, f"{np.sqrt(np.mean(norms[n - 1] ** 2)):.3f}", f"{run.log_det[0, n - 1]:.2f}"
        )
    return table


def _monte_carlo_report(result: SurveyMonteCarlo, json_path: Path | None, figures: Path | None) -> None:
    from oceanloc.report.figures import survey as survey_figures

    scen = result.scenario
    label = site_planner_label(scen.planner)
    epochs = sorted({n for n in (*_REPORT_EPOCHS, scen.epochs) if n <= scen.epochs})
    table = Table(title=f"{scen.name}: {result.runs} runs, planner {label}, seed {result.seed}")
    table.add_column("epoch n", justify="right")
    for m in range(scen.n_transponders):
        table.add_column(f"RMSEE m={m + 1} (m)", justify="right")
    for col in ("log det mean", "log det std", "mean NEES"):
        table.add_column(col, justify="right")
    for n in epochs:
        table.add_row(
            str(n), *(f"{v:.3f}" for v in result.rmsee_m[n - 1]), f"{result.log_det.mean[n - 1]:.2f}",
            f"{result.log_det.std[n - 1]:.2f}", f"{result.nees[:, n - 1].mean():.2f}",
        )  # fmt: skip
    console.print(table)
    c = result.nees_final
    console.print(
        f"NEES at n = {scen.epochs}: mean {c.mean:.2f} (chi-square {c.dof}: band {c.mean_band[0]:.2f}-"
        f"{c.mean_band[1]:.2f}, {'inside' if c.mean_within_band else 'OUTSIDE'}), KS p = {c.p_value:.3f}; "
        f"planning {result.plan_time_s * 1e3:.2f} ms per run and epoch (batched); "
        f"{100 * result.converged_fraction:.2f} % of MAP solves converged"
    )
    if figures:
        out = ensure_dir(figures)
        survey_figures.logdet_rmse_figure({0: result}, 0, out / f"{scen.name}_logdet_rmse.png", scen.name)
        survey_figures.nees_figure(result.nees[:, -1], c.dof, out / f"{scen.name}_nees.png", scen.name)
        survey_figures.trajectories_figure(
            {label: result.sample_run(0)}, out / f"{scen.name}_trajectory_run0.png",
            f"{scen.name}: run 0", ellipses=True,
        )  # fmt: skip
        console.print(f"wrote figures to {out}")
    if json_path:
        write_json(
            json_path,
            {
                "scenario": scen.name,
                "planner": site_planner_name(scen.planner),
                "runs": result.runs,
                "seed": result.seed,
                "rmsee_m": result.rmsee_m,
                "logdet_mean": result.log_det.mean,
                "logdet_std": result.log_det.std,
                "nees": {"mean": c.mean, "dof": c.dof, "p_value": c.p_value},
                "plan_time_s": result.plan_time_s,
                "converged_fraction": result.converged_fraction,
            },
        )


def _triple(v: np.ndarray) -> str:
    return ", ".join(f"{x:.2f}" for x in v)
