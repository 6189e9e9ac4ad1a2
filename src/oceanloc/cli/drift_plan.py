"""``oceanloc drift-plan``: plan a drift/flight route for a scenario or a forecast product and write it out,
for a map (PNG, CSV, GeoJSON, KML) and for the vehicle (QGroundControl ``.plan``, MAVLink mission)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import root
from oceanloc.cli._common import JsonOut, cli_provenance, console, ensure_dir, err_console, escape, write_json
from oceanloc.cli._options import parse_origin
from oceanloc.config.drift import DriftScenario, load_drift_scenario
from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection
from oceanloc.io.missions import drift_mission, qgc_plan, write_qgc_plan, write_waypoints
from oceanloc.io.paths import safe_file_stem, write_path_csv, write_path_geojson, write_path_kml
from oceanloc.io.records import Provenance
from oceanloc.planning.drift_rrt.planner import PLANNER_NAMES

PlannerOption = Annotated[
    str | None,
    typer.Option("--planner", help=f"One of {', '.join(PLANNER_NAMES)} (default: the scenario's)."),
]
FORECAST_BASE = "dillard-drift-forecast"
"""The scenario whose vehicle and planner settings a product given with ``--currents`` uses by default."""


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


def _lonlat(text: str, option: str) -> tuple[float, float]:
    o = parse_origin(text, option)
    return (o.lon_deg, o.lat_deg)


def _window(text: str | None) -> tuple[str, str] | None:
    if text is None:
        return None
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2 or not all(parts):
        raise ConfigError(f"--time-window must be START,END (ISO 8601), got {text!r}")
    return parts[0], parts[1]


def _with_choices(
    sc: DriftScenario, objective: str | None, deadline_h: float | None, propulsion: str | None
) -> DriftScenario:
    changes: dict = {}
    if objective is not None:
        if objective not in ("energy", "time"):
            raise ConfigError(f"--objective must be energy or time, got {objective!r}")
        changes["objective"] = objective
    if deadline_h is not None:
        if deadline_h * 3600.0 > sc.horizon_s + 1e-6:
            raise ConfigError(
                f"--deadline-h {deadline_h:g} is beyond the planning horizon ({sc.horizon_s / 3600:g} h)"
            )
        changes["max_duration_s"] = deadline_h * 3600.0
    if propulsion is not None:
        if propulsion not in ("air", "water"):
            raise ConfigError(f"--propulsion must be air or water, got {propulsion!r}")
        changes["propulsion"] = propulsion
        if propulsion == "water":
            changes["max_leg_m"] = None
    return dataclasses.replace(sc, **changes) if changes else sc


@root.app.command("drift-plan")
def drift_plan(
    scenario: str | None = typer.Option(
        None,
        "--scenario",
        help="Drift scenario file or built-in name (dillard-drift-*); with --currents, its vehicle and "
        f"planner settings (default {FORECAST_BASE}).",
    ),
    currents: Annotated[
        list[Path] | None,
        typer.Option(
            "--currents",
            help="Forecast product: a Copernicus Marine or HYCOM NetCDF file or Zarr store, or a ROMS file; "
            "repeat it for the members of an ensemble. Needs --start and --goal.",
        ),
    ] = None,
    start: str | None = typer.Option(None, "--start", help="LAT,LON of the start (with --currents)."),
    goal: str | None = typer.Option(None, "--goal", help="LAT,LON of the goal (with --currents)."),
    start_time: str | None = typer.Option(
        None, "--start-time", help="ISO 8601 start within the product (default: its first slice)."
    ),
    depth: float | None = typer.Option(
        None, "--depth", min=0.0, max=12_000.0, help="Depth of the level to read, metres (default: surface)."
    ),
    time_window: str | None = typer.Option(
        None, "--time-window", help="START,END (ISO 8601): the product's slices to read."
    ),
    objective: str | None = typer.Option(None, "--objective", help="energy or time (default: scenario's)."),
    deadline_h: float | None = typer.Option(
        None, "--deadline-h", min=0.01, max=720.0, help="Reach the goal within this many hours."
    ),
    propulsion: str | None = typer.Option(
        None, "--propulsion", help="air (a flying drifter) or water (a boat carried by the current)."
    ),
    vehicle: str | None = typer.Option(
        None,
        "--vehicle",
        help="Mission for a boat (ArduPilot Rover: waypoints and holds) or an aquaquad (take-off, "
        "waypoint, land, hold); default: boat in the water, aquaquad in the air.",
    ),
    planner: PlannerOption = None,
    seed: int | None = typer.Option(None, "--seed", min=0, help="Planner seed (default: the scenario's)."),
    iterations: int | None = typer.Option(
        None, "--iterations", min=1, help="Iteration budget of the DR-RRT* planners."
    ),
    out: Annotated[
        Path, typer.Option("--out", help="Folder for the figure, CSV, GeoJSON, KML and missions.")
    ] = Path("out/drift-plan"),
    origin: str | None = typer.Option(
        None,
        "--origin",
        help="LAT,LON[,H] (degrees, degrees, metres; H is ignored) of the local frame's origin, to write "
        "GeoJSON, KML and missions for a scenario in a local frame.",
    ),
    json_path: JsonOut = None,
) -> None:
    """Plan the least-energy (or fastest) drift/flight route of a scenario or a forecast product; print its
    summary and write PNG, CSV and, when georeferenced, GeoJSON, KML, a QGroundControl .plan and a MAVLink
    mission (.waypoints)."""
    from oceanloc.evaluation.drift import plan_scenario
    from oceanloc.report.figures.drift import plan_figure
    from oceanloc.report.tables.drift import ensemble_table, plan_table

    sc = _load(scenario, currents, start, goal, start_time, depth, time_window)
    sc = _with_choices(sc, objective, deadline_h, propulsion)
    if vehicle is not None and vehicle not in ("boat", "aquaquad"):
        raise ConfigError(f"--vehicle must be boat or aquaquad, got {vehicle!r}")
    projection = sc.projection if origin is None else _projection(origin)
    plan = plan_scenario(sc, planner, seed, iterations=iterations)
    console.print(plan_table(plan))
    ens = ensemble_table(plan)
    if ens is not None:
        console.print(ens)
    folder = ensure_dir(out)
    stem = safe_file_stem(f"{sc.name}-{plan.planner}")
    wrote(plan_figure(folder / f"{stem}.png", plan))
    if json_path is not None:
        write_json(json_path, plan, scenario_provenance(sc, plan.seed))
    if plan.result.path is None:
        return
    path = plan.result.path
    wrote(write_path_csv(folder / f"{stem}.csv", path, projection))
    if projection is None:
        err_console.print(
            "no GeoJSON, KML or mission: the scenario is in a local frame; pass --origin LAT,LON to place it"
        )
        return
    wrote(write_path_geojson(folder / f"{stem}.geojson", path, projection, plan.summary()))
    wrote(write_path_kml(folder / f"{stem}.kml", path, projection, sc.name))
    kind = vehicle or ("boat" if sc.propulsion == "water" else "aquaquad")
    items = drift_mission(path, projection, vehicle=kind)  # type: ignore[arg-type]
    qgc = qgc_plan(items, vehicle=kind, cruise_speed_mps=sc.energy.flight_speed_mps)  # type: ignore[arg-type]
    wrote(write_qgc_plan(folder / f"{stem}.plan", qgc))
    wrote(write_waypoints(folder / f"{stem}.waypoints", items))


def _load(
    scenario: str | None,
    currents: list[Path] | None,
    start: str | None,
    goal: str | None,
    start_time: str | None,
    depth: float | None,
    time_window: str | None,
) -> DriftScenario:
    if not currents:
        if scenario is None:
            raise ConfigError("drift-plan needs --scenario or --currents (a forecast product)")
        for name, value in (("--start", start), ("--goal", goal), ("--start-time", start_time)):
            if value is not None:
                raise ConfigError(f"{name} goes with --currents (a scenario file sets its own route)")
        if depth is not None or time_window is not None:
            raise ConfigError("--depth and --time-window go with --currents (a scenario file sets its own)")
        return load_drift_scenario(scenario)
    from oceanloc.config.drift_products import ProductRoute, scenario_on_product

    if start is None or goal is None:
        raise ConfigError("--currents needs --start LAT,LON and --goal LAT,LON")
    base = load_drift_scenario(scenario or FORECAST_BASE)
    route = ProductRoute(
        paths=tuple(currents),
        start_lonlat_deg=_lonlat(start, "--start"),
        goal_lonlat_deg=_lonlat(goal, "--goal"),
        start_time=start_time,
        depth_m=depth,
        time_window=_window(time_window),
    )
    return scenario_on_product(base, route)
