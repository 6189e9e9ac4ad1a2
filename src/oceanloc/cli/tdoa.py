"""``oceanloc tdoa A.wav B.wav``: time difference of arrival between two hydrophone recordings."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from oceanloc.cli import root
from oceanloc.cli._common import console, err_console, progress_bar, write_json
from oceanloc.cli.dop import parse_point
from oceanloc.errors import ConfigError
from oceanloc.estimation.time_delay import DELAY_METHODS, estimate_delay
from oceanloc.io.wav import common_sample_rate, read_wav


@root.app.command("tdoa")
def tdoa(
    first: Annotated[Path, typer.Argument(help="Recording A (WAV).")],
    second: Annotated[Path, typer.Argument(help="Recording B (WAV), same sample rate.")],
    method: str = typer.Option("gcc-phat", "--method", help="xcorr or gcc-phat."),
    max_delay: float | None = typer.Option(None, "--max-delay", help="Search |delay| <= this (s)."),
    band: str | None = typer.Option(None, "--band", help="Use only this band low,high (Hz)."),
    channel: int = typer.Option(0, "--channel", min=0, help="Channel of multi-channel files."),
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the result as JSON.")] = None,
    png: Annotated[
        Path | None, typer.Option("--png", help="Write the correlation figure (thesis Fig. 17).")
    ] = None,
) -> None:
    """Delay of A relative to B (arrival at A minus arrival at B; > 0: B heard the signal first).

    Cross-correlation or GCC-PHAT with band-limited sub-sample interpolation of the peak; the peak ratio
    (main correlation peak over the largest value outside its main lobe) says how unambiguous it is.
    """
    from oceanloc.report.figures import flock as flock_figures

    if method not in DELAY_METHODS:
        raise ConfigError(f"--method must be one of {', '.join(DELAY_METHODS)}; got '{method}'")
    band_hz = None
    if band is not None:
        lo_hi = parse_point(band, "--band")
        band_hz = (float(lo_hi[0]), float(lo_hi[1]))
    with progress_bar(3, "reading and correlating") as advance:
        rec_a = read_wav(first)
        advance(1)
        rec_b = read_wav(second)
        advance(1)
        rate = common_sample_rate(rec_a, rec_b)
        est = estimate_delay(
            rec_a.channel(channel),
            rec_b.channel(channel),
            rate,
            method=method,  # type: ignore[arg-type]
            max_delay_s=max_delay,
            band_hz=band_hz,
        )
        advance(1)
    table = Table(title=f"TDOA {first.name} (A) - {second.name} (B), {method}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("delay (s)", f"{est.delay_s:.9f}")
    table.add_row("delay (samples)", f"{est.delay_samples:.4f}")
    table.add_row("heard first", f"{est.first} ({first.name if est.first == 'A' else second.name})")
    table.add_row("peak ratio", f"{est.peak_ratio:.3g}")
    table.add_row("sample rate (Hz)", f"{rate:g}")
    table.add_row("formats", f"{rec_a.sample_format}, {rec_b.sample_format}")
    console.print(table)
    if json_path is not None:
        write_json(
            json_path,
            {
                "delay_s": est.delay_s,
                "delay_samples": est.delay_samples,
                "method": est.method,
                "first": est.first,
                "peak_ratio": est.peak_ratio,
            },
        )
    if png is not None:
        err_console.print(f"wrote {flock_figures.correlation_figure(est, png, (first.name, second.name))}")
