"""``oceanloc simulate logs``: write realistic GPS (NMEA) and USBL (CSV) logs of a pier experiment."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from oceanloc.cli import simulate
from oceanloc.cli._common import console
from oceanloc.geo.enu import enu_to_geodetic
from oceanloc.sim.logs import PIER_ORIGIN, PierLogSettings, simulate_pier_logs


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
        f"{res.n_outliers} multipath outliers, {res.n_corrupt} corrupt lines)",
        highlight=False,
    )
    # The truth in the journal's frame and as latitude/longitude: `localize logs` puts its origin at
    # the first fix, so compare positions there by latitude and longitude.
    origin = f"{PIER_ORIGIN.lat_deg:.3f}, {PIER_ORIGIN.lon_deg:.3f}, {PIER_ORIGIN.h_m:.3f} m"
    for k, b in enumerate(res.beacons_enu_m, start=1):
        lat, lon, h = enu_to_geodetic(b, PIER_ORIGIN)
        console.print(
            f"beacon {k}: E {b[0]:.2f}, N {b[1]:.2f}, U {b[2]:.2f} m from ({origin});"
            f" {lat:.7f}, {lon:.7f}, {h:.2f} m",
            highlight=False,
        )
