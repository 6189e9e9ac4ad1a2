"""``oceanloc drift-plan``: plan a drift/flight route for any scenario file and write it out."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from oceanloc.cli import root
from oceanloc.cli._common import console, ensure_dir, err_console
from oceanloc.config.drift import load_drift_scenario, problem_from_scenario
from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection
from oceanloc.io.paths import write_path_csv, write_path_geojson
from oceanloc.planning.drift_rrt.planner import PLANNER_NAMES, make_planner, parse_planner_name
from oceanloc.planning.drift_rrt.problem import PlanBudget
from oceanloc.planning.drift_rrt.thesis import ThesisOptions, plan_thesis


def _origin(text: str | None) -> LocalProjection | None:
    if text is None:
        return None
    try:
        lon, lat = (float(v) for v in text.split(","))
    except ValueError:
        raise ConfigError(f"--origin must be LON,LAT in degrees, got '{text}'") from None
    return LocalProjection(lat0_deg=lat, lon0_deg=lon)


@root.app.command("drift-plan")
def drift_plan(
    scenario: str = typer.Option(
        ..., "--scenario", help="Drift scenario file or built-in name (dillard-drift-*)."
    ),
    planner: str | None = typer.Option(
        None, "--planner", help=f"One of {', '.join(PLANNER_NAMES)} (default: the scenario's)."
    ),
    seed: int | None = typer.Option(None, "--seed", min=0, help="Planner seed (default: the scenario's)."),
    iterations: int | None = typer.Option(
        None, "--iterations", min=1, help="Iteration budget of the DR-RRT* planners."
    ),
    out: Annotated[Path, typer.Option("--out", help="Folder for the figure, CSV and GeoJSON.")] = Path(
        "out/drift-plan"
    ),
    origin: str | None = typer.Option(
        None, "--origin", help="LON,LAT of the local frame's origin, to write GeoJSON."
    ),
) -> None:
    """Plan the least-energy drift/flight route of a scenario; print its summary, write PNG, CSV, GeoJSON."""
    from oceanloc.report.figures.drift import paths_figure, tree_figure

    sc = load_drift_scenario(scenario)
    name = sc.planner if planner is None else parse_planner_name(planner, "--planner")
    problem = problem_from_scenario(sc)
    rng = np.random.default_rng(sc.seed if seed is None else seed)
    if name.startswith("thesis"):
        if problem.hdop is None:
            raise ConfigError(f"{scenario}: the DR-RRT* planners need an [hdop] table (flock geometry)")
        mode = "single" if name == "thesis-single" else "optimality-seeking"
        budget = PlanBudget(max_iterations=iterations) if iterations else None
        result = plan_thesis(problem, rng, budget, ThesisOptions(mode=mode, keep_tree=True))  # type: ignore[arg-type]
    else:
        result = make_planner(name)(problem, rng)
    energy = problem.energy
    table = Table(title=f"{sc.name}: {name}", show_header=False)
    table.add_row("status", f"{result.status.value} - {result.message}")
    table.add_row("currents", sc.currents_description)
    table.add_row(
        "start -> goal (m)",
        f"{problem.start_m.tolist()} -> {problem.goal_m.tolist()} (within {problem.goal_tolerance_m:g} m)",
    )
    if result.path is not None:
        path = result.path
        account = path.energy(energy)
        table.add_row("flights", f"{path.hops_m().shape[0]} ({path.flight_distance_m:.0f} m flown)")
        table.add_row(
            "flight energy",
            f"{result.flight_energy_wh:.2f} Wh (direct flight {result.direct_flight_wh:.2f} Wh, "
            f"saving {100 * result.saving:.1f}%)",
        )
        table.add_row(
            "duration", f"{account.duration_s / 3600:.2f} h (drift {path.drift_time_s / 3600:.2f} h)"
        )
        table.add_row(
            "energy balance (IV.14)",
            f"solar +{account.solar_wh:.1f} Wh, loads -{account.loads_wh:.1f} Wh, "
            f"flight -{account.flight_wh:.1f} Wh: net {account.net_wh:+.1f} Wh",
        )
    table.add_row("compute", f"{1e3 * result.compute_s:.1f} ms")
    table.add_row("units", energy.convention)
    console.print(table)
    folder = ensure_dir(out)
    stem = f"{sc.name}-{name}"
    if result.tree is not None:
        fig = tree_figure(folder / f"{stem}.png", problem, result.tree, result.path, f"{sc.name}: {name}")
    else:
        fig = paths_figure(
            folder / f"{stem}.png",
            problem,
            {name: result.path} if result.path is not None else {},
            f"{sc.name}: {name}",
        )
    err_console.print(f"wrote {fig}")
    if result.path is None:
        return
    projection = _origin(origin) or sc.projection
    err_console.print(f"wrote {write_path_csv(folder / f'{stem}.csv', result.path, projection)}")
    if projection is not None:
        props = {
            "scenario": sc.name,
            "planner": name,
            "status": result.status.value,
            "flight_energy_wh": result.flight_energy_wh,
            "units": energy.convention,
        }
        err_console.print(
            f"wrote {write_path_geojson(folder / f'{stem}.geojson', result.path, projection, props)}"
        )
    else:
        err_console.print(
            "no GeoJSON: the scenario is in a local frame; pass --origin LON,LAT to georeference it"
        )
