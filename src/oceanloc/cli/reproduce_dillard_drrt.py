"""``oceanloc reproduce dillard-drrt``: Table 4 of the AquaQuad thesis, with oceanloc's planner beside it."""

from __future__ import annotations

import typer

from oceanloc.cli import reproduce
from oceanloc.cli._common import (
    FiguresOut,
    JsonOut,
    Scheduler,
    Workers,
    console,
    ensure_dir,
    err_console,
    progress_bar,
    write_json,
)
from oceanloc.cli.drift_plan import scenario_provenance, wrote
from oceanloc.cli.simulate_drift import NetcdfOut
from oceanloc.config.drift import load_drift_scenario
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.io.records import write_netcdf
from oceanloc.reproduce.dillard_drrt import SCENARIO, planned_runs, reproduce_dillard_drrt, sample_plans


@reproduce.app.command("dillard-drrt")
def dillard_drrt(
    runs: int = typer.Option(
        1000,
        "--runs",
        min=1,
        help="Runs per planner on the fixed field, and per planner across the random fields.",
    ),
    seed: int = typer.Option(2014, "--seed", min=0, help="Master seed."),
    fields: int | None = typer.Option(
        None,
        "--fields",
        min=0,
        help="Random obstacle fields (the thesis' generator); default one per 50 runs, at most 20; 0 skips.",
    ),
    iterations: int = typer.Option(
        25_000, "--iterations", min=1, help="Iterations of the optimality-seeking mode."
    ),
    reference_spacing: float = typer.Option(
        50.0, "--reference-spacing", min=10.0, help="Lattice spacing (m) of the best-achievable reference."
    ),
    json_path: JsonOut = None,
    netcdf: NetcdfOut = None,
    figures: FiguresOut = None,
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """DR-RRT* Monte Carlo (thesis Table 4): single-solution, optimality-seeking and oceanloc's planner.

    Every planner makes --runs runs on the fixed field and --runs runs spread over the
    random fields (one best-achievable lattice per field, one field per 50 runs by default).
    Compute times are wall-clock per run inside its worker; with several workers sharing the
    cores they run longer than alone (use --workers 1, or make bench).
    """
    from oceanloc.report.figures.drift import dillard_drrt_figures
    from oceanloc.report.tables.drift import dillard_fields_table, dillard_notes, dillard_table

    total = planned_runs(runs, fields)
    with open_executor(scheduler, workers) as executor, progress_bar(total, "planner runs") as advance:
        report = reproduce_dillard_drrt(
            runs, seed, fields=fields, iterations=iterations, reference_spacing_m=reference_spacing,
            executor=executor, progress=advance, note=lambda text: err_console.print(text, highlight=False),
        )  # fmt: skip
    console.print(dillard_table(report))
    for line in dillard_notes(report):
        console.print(line, highlight=False)
    if (table := dillard_fields_table(report)) is not None:
        console.print(table)
    prov = scenario_provenance(load_drift_scenario(SCENARIO), seed)
    if json_path is not None:
        write_json(json_path, report, prov)
    if netcdf is not None:
        wrote(write_netcdf(netcdf, report.to_dataset(), prov))
    if figures is not None:
        for out in dillard_drrt_figures(ensure_dir(figures), report, sample_plans(seed, iterations)):
            wrote(out)
