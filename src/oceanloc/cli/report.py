"""``oceanloc report``: one offline HTML page (and optionally KML) from a survey journal or a JSON record."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import root
from oceanloc.cli._common import err_console, escape
from oceanloc.cli._options import parse_origin
from oceanloc.errors import DataError


@root.app.command("report")
def report(
    source: Annotated[
        Path,
        typer.Argument(
            help="A survey journal (SQLite) or a JSON record of simulate survey, localize gnssa, reproduce "
            "or drift-plan.",
            show_default=False,
        ),
    ],
    html: Annotated[Path, typer.Option("--html", help="Write the self-contained HTML report here.")],
    kml: Annotated[Path | None, typer.Option("--kml", help="Also write the map layers as KML here.")] = None,
    origin: Annotated[
        str | None, typer.Option(help="LAT,LON[,H] of a local frame's origin (for --kml of local records).")
    ] = None,
) -> None:
    """Write an offline HTML report (map, time series, checks, provenance) of a journal or record."""
    # imported here: plotly and scipy would slow every other `oceanloc` command's start
    from oceanloc.report.html.kml_layers import report_kml
    from oceanloc.report.html.page import render_html
    from oceanloc.report.html.sources import load_report

    for out in (html, kml):
        if out is not None and not out.parent.is_dir():
            raise DataError(f"{out}: folder {out.parent} does not exist")
    rep = load_report(source)
    kml_origin = parse_origin(origin) if origin is not None else None
    if kml is not None:  # checked before the HTML is written, so a usage error leaves no half output
        report_kml(rep, kml, kml_origin)
    html.write_text(render_html(rep), encoding="utf-8")
    err_console.print(f"wrote {escape(str(html))} ({rep.kind} report)", highlight=False)
    if kml is not None:
        err_console.print(f"wrote {escape(str(kml))}", highlight=False)
