"""``oceanloc reproduce dillard-filters`` and ``oceanloc reproduce dillard-lab-tdoa`` (AquaQuad thesis)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer

from oceanloc.cli import reproduce
from oceanloc.cli._common import (
    JsonOut,
    Scheduler,
    Seed,
    Workers,
    cli_provenance,
    console,
    ensure_dir,
    err_console,
    escape,
    progress_bar,
    write_json,
)
from oceanloc.config.flock import flock_scenario_toml, load_flock_scenario
from oceanloc.evaluation.montecarlo import open_executor
from oceanloc.io import records
from oceanloc.reproduce.dillard_filters import reproduce_dillard_filters
from oceanloc.reproduce.dillard_lab_tdoa import reproduce_dillard_lab_tdoa

_SCENARIO_HELP = "Built-in flock scenario name or TOML file."
NetcdfOut = Annotated[
    Path | None, typer.Option("--netcdf", help="Write the Monte Carlo (dims filter, run, epoch) as NetCDF.")
]
_FIGURES_HELP = "Folder for the PNG figures"


def write_outputs(
    result: Any,
    scenario: str,
    json_path: Path | None,
    netcdf: Path | None,
    figures: Path | None,
    write_figures: Callable[[Any, Path], list[Path]],
) -> None:
    """JSON (``result.to_record()``), NetCDF (``result.monte_carlo.to_dataset()``) and figures, each record
    with the provenance: the scenario's name and TOML hash, the seed and the command line."""
    prov = cli_provenance(
        seed=result.monte_carlo.seed, scenario=scenario, scenario_toml=flock_scenario_toml(scenario)
    )
    if json_path is not None:
        write_json(json_path, result.to_record(), prov)
    if netcdf is not None:
        records.write_netcdf(netcdf, result.monte_carlo.to_dataset(), prov)
        err_console.print(f"wrote {escape(str(netcdf))}", highlight=False)
    if figures is not None:
        written = write_figures(result, ensure_dir(figures))
        err_console.print(f"wrote {len(written)} figures to {escape(str(figures))}", highlight=False)


@reproduce.app.command("dillard-filters")
def dillard_filters(
    runs: int = typer.Option(100, "--runs", min=1, help="Monte Carlo runs."),
    seed: Seed = None,
    json_path: JsonOut = None,
    netcdf: NetcdfOut = None,
    figures: Annotated[Path | None, typer.Option("--figures", help=f"{_FIGURES_HELP} (Figs. 25-29).")] = None,
    scenario: str = typer.Option("dillard-filters", "--scenario", help=_SCENARIO_HELP),
    duration: float | None = typer.Option(None, "--duration", min=0.0, help="Override the duration (s)."),
    controls: bool = typer.Option(
        True, "--controls/--no-controls", help="Also run each filter with the other's motion model."
    ),
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Thesis Table 2: EKF vs UKF bearing-only tracking by four drifting nodes (Chapter III.E).

    With another --scenario: the same Monte Carlo and the checks that do not refer to the thesis' values.
    """
    from oceanloc.report.figures import flock as flock_figures
    from oceanloc.report.tables import flock as flock_tables
    from oceanloc.report.tables.survey import checks_table

    sc = load_flock_scenario(scenario)
    if duration is not None:
        sc = sc.with_overrides(duration_s=duration)
    with open_executor(scheduler, workers) as executor, progress_bar(runs, "Monte Carlo runs") as advance:
        res = reproduce_dillard_filters(
            sc, runs=runs, seed=seed, controls=controls, executor=executor, progress=advance
        )
    console.print(flock_tables.table_2(res))
    console.print(flock_tables.filter_stats_table(res))
    console.print(checks_table(res.checks))
    write_outputs(res, scenario, json_path, netcdf, figures, flock_figures.filter_figures)


@reproduce.app.command("dillard-lab-tdoa")
def dillard_lab_tdoa(
    runs: int = typer.Option(20, "--runs", min=1, help="Monte Carlo runs (random target paths)."),
    seed: Seed = None,
    json_path: JsonOut = None,
    netcdf: Annotated[
        Path | None, typer.Option("--netcdf", help="Write the Monte Carlo (dims run, epoch) as NetCDF.")
    ] = None,
    figures: Annotated[
        Path | None, typer.Option("--figures", help=f"{_FIGURES_HELP} (Figs. 62, 63, 67).")
    ] = None,
    scenario: str = typer.Option("dillard-lab-tdoa", "--scenario", help=_SCENARIO_HELP),
    workers: Workers = None,
    scheduler: Scheduler = None,
) -> None:
    """Thesis lab test: TDOA UKF, three nodes in a Y, random target; residual vs HDOP (Chapter V.C)."""
    from oceanloc.report.figures import flock as flock_figures
    from oceanloc.report.tables import flock as flock_tables
    from oceanloc.report.tables.survey import checks_table

    with open_executor(scheduler, workers) as executor, progress_bar(runs, "Monte Carlo runs") as advance:
        res = reproduce_dillard_lab_tdoa(scenario, runs=runs, seed=seed, executor=executor, progress=advance)
    console.print(flock_tables.lab_table(res))
    console.print(checks_table(res.checks))
    write_outputs(res, scenario, json_path, netcdf, figures, flock_figures.lab_figures)
