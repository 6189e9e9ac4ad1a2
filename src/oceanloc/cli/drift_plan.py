"""``oceanloc drift-plan``: plan a drift/flight route for any scenario file and write it out."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import root
from oceanloc.cli._common import JsonOut, cli_provenance, console, ensure_dir, err_console, escape, write_json
from oceanloc.cli._options import parse_origin
from oceanloc.config.drift import DriftScenario, load_drift_scenario
from oceanloc.evaluation.drift import plan_scenario
from oceanloc.geo.projection import LocalProjection
from oceanloc.io.paths import safe_file_stem, write_path_csv, write_path_geojson
from oceanloc.io.records import Provenance
from oceanloc.planning.drift_rrt.planner import PLANNER_NAMES

PlannerOption = Annotated[
    str | None,
    typer.Option("--planner", help=f"One of {', '.join(PLANNER_NAMES)} (default: the scenario's)."),
]


def scenario_provenance(scenario: DriftScenario, seed: int | None) -> Provenance:
    """Provenance of a drift command: the scenario's name, the hash of its TOML text, its data files."""
    return cli_provenance(
        seed=seed, scenario=scenario.name, scenario_toml=scenario.toml_text, inputs=scenario.data_files
    )


def wrote(path: Path) -> None:
    """Say on stderr that a file was written (its name escaped)."""
    err_console.print(f"wrote {escape(str(path))}", highlight=False)


def _projection(origin: str) -> LocalProjection:
    o = parse_origin(origin)
    return LocalProjection(lat0_deg=o.lat_deg, lon0_deg=o.lon_deg)


@root.app.command("drift-plan")
def drift_plan(
    scenario: str = typer.Option(
        ..., "--scenario", help="Drift scenario file or built-in name (dillard-drift-*)."
    ),
    planner: PlannerOption = None,
    seed: int | None = typer.Option(None, "--seed", min=0, help="Planner seed (default: the scenario's)."),
    iterations: int | None = typer.Option(
        None, "--iterations", min=1, help="Iteration budget of the DR-RRT* planners."
    ),
    out: Annotated[Path, typer.Option("--out", help="Folder for the figure, CSV and GeoJSON.")] = Path(
        "out/drift-plan"
    ),
    origin: str | None = typer.Option(
        None,
        "--origin",
        help="LAT,LON[,H] (degrees, degrees, metres; H is ignored) of the local frame's origin, to write "
        "GeoJSON for a scenario in a local frame.",
    ),
    json_path: JsonOut = None,
) -> None:
    """Plan the least-energy drift/flight route of a scenario; print its summary, write PNG, CSV, GeoJSON."""
    from oceanloc.report.figures.drift import plan_figure
    from oceanloc.report.tables.drift import plan_table

    sc = load_drift_scenario(scenario)
    projection = sc.projection if origin is None else _projection(origin)
    plan = plan_scenario(sc, planner, seed, iterations=iterations)
    console.print(plan_table(plan))
    folder = ensure_dir(out)
    stem = safe_file_stem(f"{sc.name}-{plan.planner}")
    wrote(plan_figure(folder / f"{stem}.png", plan))
    if json_path is not None:
        write_json(json_path, plan, scenario_provenance(sc, plan.seed))
    if plan.result.path is None:
        return
    wrote(write_path_csv(folder / f"{stem}.csv", plan.result.path, projection))
    if projection is None:
        err_console.print("no GeoJSON: the scenario is in a local frame; pass --origin LAT,LON to place it")
        return
    props = plan.summary()
    wrote(write_path_geojson(folder / f"{stem}.geojson", plan.result.path, projection, props))
