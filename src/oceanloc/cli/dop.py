"""``oceanloc dop map`` and ``oceanloc dop place``: dilution of precision (AquaQuad thesis, Chapter IV.A)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from oceanloc.cli import root
from oceanloc.cli._common import console, err_console, progress_bar, write_json
from oceanloc.errors import ConfigError
from oceanloc.planning.dop import MEASUREMENT_KINDS, hdop_map, optimize_placement

app = typer.Typer(
    help="Horizontal dilution of precision: maps and HDOP-optimal node placement.", no_args_is_help=True
)
root.app.add_typer(app, name="dop")

_KIND_HELP = "Measurement: bearing, range or tdoa."
_SIGMA_HELP = "Measurement standard deviation (rad, m or s); 1 gives the geometric HDOP."


def parse_point(text: str, option: str) -> np.ndarray:
    """``"x,y"`` -> ``(2,)``; a ConfigError naming the option otherwise."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ConfigError(f"{option}: expected x,y in metres, got '{text}'") from None
    if len(values) != 2 or not all(np.isfinite(values)):
        raise ConfigError(f"{option}: expected two finite numbers x,y, got '{text}'")
    return np.array(values)


def _check_kind(kind: str) -> None:
    if kind not in MEASUREMENT_KINDS:
        raise ConfigError(f"--kind must be one of {', '.join(MEASUREMENT_KINDS)}; got '{kind}'")


@app.command("map")
def dop_map(
    kind: str = typer.Option("tdoa", "--kind", help=_KIND_HELP),
    nodes: Annotated[
        list[str] | None,
        typer.Option("--node", help="A fixed node x,y (m); repeat (default: 100,0 and 0,100)."),
    ] = None,
    target: str = typer.Option("0,0", "--target", help="Target position x,y (m)."),
    x_range: str = typer.Option("-300,300", "--x-range", help="Grid east range min,max (m)."),
    y_range: str = typer.Option("-300,300", "--y-range", help="Grid north range min,max (m)."),
    resolution: float = typer.Option(5.0, "--resolution", help="Grid spacing (m)."),
    sigma: float = typer.Option(1.0, "--sigma", help=_SIGMA_HELP),
    sound_speed: float = typer.Option(1500.0, "--sound-speed", help="Sound speed for TDOA (m/s)."),
    png: Annotated[Path | None, typer.Option("--png", help="Write the map as a PNG figure.")] = None,
    netcdf: Annotated[Path | None, typer.Option("--netcdf", help="Write the map as NetCDF (xarray).")] = None,
) -> None:
    """HDOP as one more node moves over a grid around fixed nodes and a target (thesis Figs. 32, 48)."""
    from oceanloc.report.figures import flock as flock_figures

    _check_kind(kind)
    if not sigma > 0:
        raise ConfigError(f"--sigma must be positive, got {sigma}")
    fixed = np.array([parse_point(n, "--node") for n in (nodes or ["100,0", "0,100"])])
    xr_ = parse_point(x_range, "--x-range")
    yr_ = parse_point(y_range, "--y-range")
    tgt = parse_point(target, "--target")
    with progress_bar(1, "HDOP map") as advance:
        dop = hdop_map(
            fixed,
            tgt,
            kind,  # type: ignore[arg-type]
            x_range_m=(xr_[0], xr_[1]),
            y_range_m=(yr_[0], yr_[1]),
            resolution_m=resolution,
            sigma=sigma,
            sound_speed_mps=sound_speed,
        )
        advance(1)
    finite = np.isfinite(dop.hdop)
    table = Table(title=f"{kind} HDOP map: {dop.x_m.size} x {dop.y_m.size} cells")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    if finite.any():
        iy, ix = np.unravel_index(np.argmin(np.where(finite, dop.hdop, np.inf)), dop.hdop.shape)
        table.add_row("minimum HDOP", f"{dop.hdop[iy, ix]:.4g}")
        table.add_row("moving node at the minimum (m)", f"({dop.x_m[ix]:.1f}, {dop.y_m[iy]:.1f})")
        table.add_row("median HDOP", f"{np.median(dop.hdop[finite]):.4g}")
    table.add_row("singular cells", f"{100 * (1 - finite.mean()):.2f} %")
    console.print(table)
    if png is not None:
        err_console.print(f"wrote {flock_figures.hdop_map_figure(dop, png)}")
    if netcdf is not None:
        try:
            netcdf.parent.mkdir(parents=True, exist_ok=True)
            dop.to_dataset().to_netcdf(netcdf, engine="netcdf4")
        except OSError as exc:
            raise ConfigError(f"{netcdf}: cannot write NetCDF ({exc})") from None
        err_console.print(f"wrote {netcdf}")


@app.command("place")
def dop_place(
    kind: str = typer.Option("bearing", "--kind", help=_KIND_HELP),
    n_nodes: int = typer.Option(8, "--nodes", min=1, help="Number of nodes to place."),
    target: str = typer.Option("0,0", "--target", help="Target position x,y (m)."),
    min_standoff: float = typer.Option(50.0, "--min-standoff", help="Closest allowed node range (m)."),
    max_standoff: float = typer.Option(500.0, "--max-standoff", help="Farthest allowed node range (m)."),
    fixed: Annotated[
        list[str] | None, typer.Option("--fixed-node", help="A node already in place x,y (m); repeat.")
    ] = None,
    sigma: float = typer.Option(1.0, "--sigma", help=_SIGMA_HELP),
    starts: int = typer.Option(16, "--starts", min=1, help="Local optimizations (multi-start)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the random starts."),
    png: Annotated[Path | None, typer.Option("--png", help="Write the placement as a PNG figure.")] = None,
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the placement as JSON.")] = None,
) -> None:
    """HDOP-optimal placement of nodes around a target within stand-off ranges (thesis Figs. 34-35)."""
    from oceanloc.report.figures import flock as flock_figures

    _check_kind(kind)
    if not sigma > 0:
        raise ConfigError(f"--sigma must be positive, got {sigma}")
    tgt = parse_point(target, "--target")
    fixed_nodes = np.array([parse_point(f, "--fixed-node") for f in fixed]) if fixed else None
    with progress_bar(starts, "multi-start optimization") as advance:
        res = optimize_placement(
            n_nodes,
            kind,  # type: ignore[arg-type]
            target_m=tgt,
            min_standoff_m=min_standoff,
            max_standoff_m=max_standoff,
            sigma=sigma,
            fixed_nodes_m=fixed_nodes,
            starts=starts,
            rng=np.random.default_rng(seed),
            progress=advance,
        )
    table = Table(title=f"{kind} HDOP-optimal placement of {n_nodes} node(s)")
    for col in ("node", "east (m)", "north (m)", "range (m)", "bearing (deg)"):
        table.add_column(col, justify="right")
    for i, p in enumerate(res.nodes_m):
        d = p - tgt
        table.add_row(
            str(i + 1),
            f"{p[0]:.2f}",
            f"{p[1]:.2f}",
            f"{np.hypot(*d):.2f}",
            f"{np.degrees(np.arctan2(d[1], d[0])):.1f}",
        )
    console.print(table)
    console.print(
        f"HDOP {res.hdop:.5g}; evenly spaced ring {res.ring_hdop:.5g} ({100 * res.gap:.2f} % worse); "
        f"local solutions from {starts} starts: {res.start_hdop.min():.5g} .. {res.start_hdop.max():.5g}"
    )
    if png is not None:
        err_console.print(f"wrote {flock_figures.placement_figure(res, tgt, kind, png)}")
    if json_path is not None:
        write_json(
            json_path,
            {
                "kind": kind,
                "target_m": tgt,
                "nodes_m": res.nodes_m,
                "hdop": res.hdop,
                "ring_nodes_m": res.ring_nodes_m,
                "ring_hdop": res.ring_hdop,
                "ring_gap": res.gap,
                "start_hdop": res.start_hdop,
            },
        )
