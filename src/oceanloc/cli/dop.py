"""``oceanloc dop map`` and ``oceanloc dop place``: dilution of precision (AquaQuad thesis, Chapter IV.A).

Positions are local ``E,N`` in metres; bearings are printed and written in degrees clockwise from north.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, cast

import numpy as np
import typer

from oceanloc.cli import root
from oceanloc.cli._common import (
    JsonOut,
    cli_provenance,
    console,
    err_console,
    escape,
    progress_bar,
    write_json,
)
from oceanloc.cli._options import parse_choices, parse_floats, parse_point
from oceanloc.errors import ConfigError
from oceanloc.io import records
from oceanloc.planning.dop import MEASUREMENT_KINDS, MeasurementKind, hdop_map, optimize_placement

app = typer.Typer(
    help="Horizontal dilution of precision: maps and HDOP-optimal node placement.", no_args_is_help=True
)
root.app.add_typer(app, name="dop")

_KIND_HELP = "Measurement: bearing, range or tdoa."
_SIGMA_HELP = "Measurement standard deviation (rad, m or s); 1 gives the geometric HDOP."


def parse_kind(text: str) -> MeasurementKind:
    """``--kind``: one of bearing, range, tdoa."""
    kinds = parse_choices(text, "--kind", MEASUREMENT_KINDS)
    if len(kinds) != 1:
        raise ConfigError(f"--kind takes one of {', '.join(MEASUREMENT_KINDS)}; got {text!r}")
    return cast(MeasurementKind, kinds[0])


def _wrote(path: Path) -> None:
    err_console.print(f"wrote {escape(str(path))}", highlight=False)


@app.command("map")
def dop_map(
    kind: str = typer.Option("tdoa", "--kind", help=_KIND_HELP),
    nodes: Annotated[
        list[str] | None,
        typer.Option("--node", help="A fixed node E,N (m); repeat (default: 100,0 and 0,100)."),
    ] = None,
    target: str = typer.Option("0,0", "--target", help="Target position E,N (m)."),
    x_range: str = typer.Option("-300,300", "--x-range", help="Grid east range min,max (m)."),
    y_range: str = typer.Option("-300,300", "--y-range", help="Grid north range min,max (m)."),
    resolution: float = typer.Option(5.0, "--resolution", help="Grid spacing (m)."),
    sigma: float = typer.Option(1.0, "--sigma", help=_SIGMA_HELP),
    sound_speed: float = typer.Option(1500.0, "--sound-speed", help="Sound speed for TDOA (m/s)."),
    png: Annotated[Path | None, typer.Option("--png", help="Write the map as a PNG figure.")] = None,
    netcdf: Annotated[Path | None, typer.Option("--netcdf", help="Write the map as NetCDF (xarray).")] = None,
    json_path: JsonOut = None,
) -> None:
    """HDOP as one more node moves over a grid around fixed nodes and a target (thesis Figs. 32, 48)."""
    from oceanloc.report.figures import flock as flock_figures
    from oceanloc.report.tables.flock import hdop_map_table

    fixed = np.array([parse_point(n, "--node") for n in (nodes or ["100,0", "0,100"])])
    xs, ys = parse_floats(x_range, "--x-range", 2), parse_floats(y_range, "--y-range", 2)
    with progress_bar(1, "HDOP map") as advance:
        dop = hdop_map(
            fixed,
            parse_point(target, "--target"),
            parse_kind(kind),
            x_range_m=(xs[0], xs[1]),
            y_range_m=(ys[0], ys[1]),
            resolution_m=resolution,
            sigma=sigma,
            sound_speed_mps=sound_speed,
        )
        advance(1)
    console.print(hdop_map_table(dop))
    prov = cli_provenance()
    if png is not None:
        _wrote(flock_figures.save(flock_figures.hdop_map_figure(dop), png))
    if netcdf is not None:
        _wrote(records.write_netcdf(netcdf, dop.to_dataset(), prov))
    if json_path is not None:
        write_json(json_path, dop.to_record(), prov)


@app.command("place")
def dop_place(
    kind: str = typer.Option("bearing", "--kind", help=_KIND_HELP),
    n_nodes: int = typer.Option(8, "--nodes", min=1, help="Number of nodes to place."),
    target: str = typer.Option("0,0", "--target", help="Target position E,N (m)."),
    min_standoff: float = typer.Option(50.0, "--min-standoff", help="Closest allowed node range (m)."),
    max_standoff: float = typer.Option(500.0, "--max-standoff", help="Farthest allowed node range (m)."),
    fixed: Annotated[
        list[str] | None, typer.Option("--fixed-node", help="A node already in place E,N (m); repeat.")
    ] = None,
    sigma: float = typer.Option(1.0, "--sigma", help=_SIGMA_HELP),
    starts: int = typer.Option(16, "--starts", min=1, help="Local optimizations (multi-start)."),
    seed: int = typer.Option(0, "--seed", min=0, help="Seed of the random starts."),
    png: Annotated[Path | None, typer.Option("--png", help="Write the placement as a PNG figure.")] = None,
    json_path: JsonOut = None,
) -> None:
    """HDOP-optimal placement of nodes around a target within stand-off ranges (thesis Figs. 34-35).

    The table gives each node's range and true bearing from the target, degrees clockwise from north.
    """
    from oceanloc.report.figures import flock as flock_figures
    from oceanloc.report.tables.flock import placement_summary, placement_table

    fixed_nodes = np.array([parse_point(f, "--fixed-node") for f in fixed]) if fixed else None
    with progress_bar(starts, "multi-start optimization") as advance:
        res = optimize_placement(
            n_nodes,
            parse_kind(kind),
            target_m=parse_point(target, "--target"),
            min_standoff_m=min_standoff,
            max_standoff_m=max_standoff,
            sigma=sigma,
            fixed_nodes_m=fixed_nodes,
            starts=starts,
            rng=np.random.default_rng(seed),
            progress=advance,
        )
    console.print(placement_table(res))
    console.print(placement_summary(res), highlight=False)
    if png is not None:
        _wrote(flock_figures.save(flock_figures.placement_figure(res), png))
    if json_path is not None:
        write_json(json_path, res.to_record(), cli_provenance(seed=seed))
