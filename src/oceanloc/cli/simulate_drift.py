"""``oceanloc simulate drift-follow`` and ``drift-swap``: following drift plans in a true current (V.D)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import simulate
from oceanloc.cli._common import (
    FiguresOut,
    JsonOut,
    Scheduler,
    Workers,
    console,
    ensure_dir,
    progress_bar,
    write_json,
)
from oceanloc.cli.drift_plan import PlannerOption, scenario_provenance, wrote
from oceanloc.config.drift import load_drift_scenario
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.evaluation.path_following import drift_follow_study, drift_swap_study
from oceanloc.io.records import write_netcdf

NetcdfOut = Annotated[
    Path | None, typer.Option("--netcdf", help="Write the per-run outcomes as NetCDF (CF) to this file.")
]


@simulate.app.command("drift-follow")
def drift_follow(
    scenario: str = typer.Option(
        "dillard-drift-fixed", "--scenario", help="Drift scenario file or built-in name."
    ),
    runs: int | None = typer.Option(
        None, "--runs", min=1, help="Monte Carlo runs (default: the scenario's)."
    ),
    seed: int | None = typer.Option(
        None, "--seed", min=0, help="Master seed of the runs (default: the scenario's [following] seed)."
    ),
    planner: PlannerOption = None,
    json_path: JsonOut = None,
    netcdf: NetcdfOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Follow a plan with watch circles in a perturbed current; arrival rate, extra energy, replans."""
    from oceanloc.report.figures.drift import following_study_figure
    from oceanloc.report.tables.drift import following_table

    sc = load_drift_scenario(scenario)
    n = runs or sc.following.runs
    with open_executor(scheduler, workers) as executor, progress_bar(n, "following runs") as advance:
        study = drift_follow_study(sc, n, seed, planner=planner, executor=executor, progress=advance)
    console.print(following_table(study))
    prov = scenario_provenance(sc, study.seed)
    if json_path is not None:
        write_json(json_path, study, prov)
    if netcdf is not None:
        wrote(write_netcdf(netcdf, study.to_dataset(), prov))
    if figures is not None:
        wrote(following_study_figure(ensure_dir(figures), study))


@simulate.app.command("drift-swap")
def drift_swap(
    scenario: str = typer.Option(
        "dillard-drift-swap", "--scenario", help="Drift scenario file or built-in name."
    ),
    seed: int | None = typer.Option(None, "--seed", min=0, help="Planner seed (default: the scenario's)."),
    planner: PlannerOption = None,
    json_path: JsonOut = None,
    figures: FiguresOut = None,
) -> None:
    """Two drifters swap positions (thesis Figs. 68-71): both plans, then both followed in a true current."""
    from oceanloc.report.figures.drift import swap_figures
    from oceanloc.report.tables.drift import swap_notes, swap_table

    sc = load_drift_scenario(scenario)
    study = drift_swap_study(sc, seed, planner=planner)
    console.print(swap_table(study))
    for line in swap_notes(study):
        console.print(line, highlight=False)
    if json_path is not None:
        write_json(json_path, study, scenario_provenance(sc, study.seed))
    if figures is not None:
        for out in swap_figures(ensure_dir(figures), study):
            wrote(out)
