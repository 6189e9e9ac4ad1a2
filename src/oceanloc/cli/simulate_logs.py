"""``oceanloc simulate logs``: write realistic GPS (NMEA) and USBL (CSV) logs of a pier experiment."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from oceanloc.cli import simulate
from oceanloc.cli._common import console
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs


@simulate.app.command("logs")
def logs(
    out: Annotated[Path, typer.Option(help="Output folder for gps.nmea and ranges.csv.")] = Path("out/logs"),
    duration: Annotated[float, typer.Option(help="Duration, seconds.")] = 1800.0,
    outlier_fraction: Annotated[
        float, typer.Option(help="Fraction of multipath outliers (+5..+30 m).")
    ] = 0.05,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 2018,
) -> None:
    """Simulate the journal's pier experiment (Tables VI, VIII) as log files."""
    res = simulate_pier_logs(
        out,
        PierLogSettings(duration_s=duration, outlier_fraction=outlier_fraction),
        np.random.default_rng(seed),
    )
    console.print(
        f"wrote {res.nmea_path} ({res.n_fixes} fixes) and {res.ranges_path} ({res.n_ranges} ranges, "
        f"{res.n_outliers} multipath outliers, {res.n_corrupt} corrupt lines); beacons (E, N, U) m: "
        + "; ".join(f"{tuple(map(float, b))}" for b in res.beacons_enu_m),
        highlight=False,
    )
