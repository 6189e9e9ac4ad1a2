"""``oceanloc simulate logs``: write realistic GPS (NMEA) and USBL (CSV) logs of a pier experiment."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from oceanloc.cli import simulate
from oceanloc.cli._common import console, escape
from oceanloc.cli._options import parse_origin
from oceanloc.report.tables.field import truth_table
from oceanloc.sim.logs import PIER_ORIGIN, PierLogSettings, simulate_pier_logs


@simulate.app.command("logs")
def logs(
    out: Annotated[Path, typer.Option(help="Output folder for gps.nmea, ranges.csv and truth.json.")] = Path(
        "out/logs"
    ),
    duration: Annotated[float, typer.Option(help="Duration, seconds.")] = 1800.0,
    outlier_fraction: Annotated[
        float, typer.Option(help="Fraction of multipath outliers (+5..+30 m).")
    ] = 0.05,
    site: Annotated[
        str,
        typer.Option(help="Where the experiment is, LAT,LON[,H] (deg, deg, m); default: the journal's pier."),
    ] = f"{PIER_ORIGIN.lat_deg},{PIER_ORIGIN.lon_deg},{PIER_ORIGIN.h_m}",
    seed: Annotated[int, typer.Option(min=0, help="Random seed.")] = 2018,
) -> None:
    """Simulate the journal's pier experiment (Tables VI, VIII) as log files, with the truth beside them.

    truth.json holds the beacons' true positions in the frame every command uses by default (ENU from
    the earliest GPS fix), as latitude/longitude/height, the site and the seed; give it to
    'oceanloc localize logs --truth' or 'oceanloc replay logs --truth'.
    """
    res = simulate_pier_logs(
        out,
        PierLogSettings(duration_s=duration, outlier_fraction=outlier_fraction),
        np.random.default_rng(seed),
        origin=parse_origin(site, "--site"),
        seed=seed,
    )
    console.print(
        escape(
            f"wrote {res.nmea_path} ({res.n_fixes} fixes), {res.ranges_path} ({res.n_ranges} ranges, "
            f"{res.n_outliers} multipath outliers, {res.n_corrupt} corrupt lines) and {res.truth_path}"
        ),
        highlight=False,
    )
    console.print(truth_table(res.truth))
