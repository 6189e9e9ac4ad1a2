"""``oceanloc simulate survey`` and ``oceanloc demo``: closed-loop transponder surveys on any scenario."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import root, simulate
from oceanloc.cli._common import (
    FiguresOut,
    JsonOut,
    NetcdfOut,
    Scheduler,
    Seed,
    Workers,
    cli_provenance,
    console,
    ensure_dir,
    escape,
    progress_bar,
    write_json,
    write_netcdf,
)
from oceanloc.config.survey import SurveyScenario, load_survey_scenario
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.evaluation.survey import single_survey, survey_monte_carlo
from oceanloc.io.records import Provenance
from oceanloc.report.tables import survey as survey_tables


@simulate.app.command("survey")
def survey_command(
    scenario: str = typer.Option(
        ..., "--scenario", help="Scenario TOML file, or a built-in name (oceanloc scenarios list)."
    ),
    runs: int | None = typer.Option(
        None, "--runs", min=1, help="Runs (default: the scenario's; 1: one survey)."
    ),
    planner: str | None = typer.Option(
        None, "--planner", help="Override the planner: k0 (random yaw), k1..k10, greedy, random-disk."
    ),
    horizon: int | None = typer.Option(None, "--horizon", min=1, help="Override the look-ahead steps k."),
    epochs: int | None = typer.Option(None, "--epochs", min=1, help="Override the number of epochs N."),
    seed: Seed = None,
    json_path: JsonOut = None,
    netcdf: NetcdfOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Simulate a transponder survey: one run prints each transponder's truth, estimate, error and 95 %
    ellipse; many runs print the Monte Carlo metrics (RMSEE, log det Y_n, NEES by epoch, planning time)."""
    from oceanloc.report.figures import survey as survey_figures

    scen = load_survey_scenario(scenario).with_overrides(planner=planner, horizon=horizon, epochs=epochs)
    n_runs = scen.runs if runs is None else runs
    scen.check_runs(n_runs)
    seed = scen.seed if seed is None else seed
    if n_runs == 1:
        _single_run(scen, seed, json_path, figures)
        return
    with open_executor(scheduler, workers) as executor, progress_bar(n_runs, "Monte Carlo runs") as advance:
        result = survey_monte_carlo(scen, n_runs, seed, executor=executor, progress=advance)
    console.print(survey_tables.monte_carlo_table(result))
    console.print(survey_tables.monte_carlo_summary(result))
    prov = _provenance(scen, seed)
    if json_path:
        write_json(json_path, result.to_record(), prov)
    if netcdf:
        write_netcdf(netcdf, result.to_dataset(), prov)
    if figures:
        paths = survey_figures.monte_carlo_figures(result, ensure_dir(figures))
        console.print(f"wrote {len(paths)} figures to {escape(str(figures))}")


@root.app.command("demo")
def demo_command(
    out: Annotated[Path, typer.Option("--out", help="Folder for the trajectory figure.")] = Path(
        "oceanloc-demo"
    ),
    seed: Seed = None,
) -> None:
    """The built-in four-transponder survey (journal Table IV), k = 2 look-ahead planner, 50 epochs."""
    scen = load_survey_scenario("garcia2019-m4").with_overrides(planner="k2")
    console.print(
        f"[bold]{scen.name}[/bold]: {escape(scen.description)}; planner k = 2, {scen.epochs} epochs"
    )
    _single_run(scen, scen.seed if seed is None else seed, None, out)


def _single_run(scen: SurveyScenario, seed: int, json_path: Path | None, figures: Path | None) -> None:
    from oceanloc.report.figures import survey as survey_figures

    survey = single_survey(scen, seed)
    console.print(survey_tables.single_survey_table(survey))
    console.print(survey_tables.single_survey_epoch_table(survey))
    console.print(survey_tables.single_survey_summary(survey))
    if figures:
        for path in survey_figures.single_survey_figures(survey, ensure_dir(figures)):
            console.print(f"wrote {escape(str(path))}")
    if json_path:
        write_json(json_path, survey.to_record(), _provenance(scen, seed))


def _provenance(scen: SurveyScenario, seed: int) -> Provenance:
    return cli_provenance(seed=seed, scenario=scen.name, scenario_toml=scen.toml_text or None)
