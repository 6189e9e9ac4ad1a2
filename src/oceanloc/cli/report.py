"""``oceanloc report``: one offline HTML page (and optionally KML) from a survey journal or a JSON record,
or the live page of a journal being written (``--serve PORT``)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import root
from oceanloc.cli._common import console, err_console, escape
from oceanloc.cli._options import parse_origin
from oceanloc.errors import DataError


@root.app.command("report")
def report(
    source: Annotated[
        Path,
        typer.Argument(
            help="A survey journal (SQLite) or a JSON record of simulate survey, localize gnssa (surveys, "
            "or an array with --format gnatss), reproduce or drift-plan.",
            show_default=False,
        ),
    ],
    html: Annotated[
        Path | None, typer.Option("--html", help="Write the self-contained HTML report here.")
    ] = None,
    kml: Annotated[Path | None, typer.Option("--kml", help="Also write the map layers as KML here.")] = None,
    origin: Annotated[
        str | None, typer.Option(help="LAT,LON[,H] of a local frame's origin (for --kml of local records).")
    ] = None,
    serve: Annotated[
        int | None,
        typer.Option(
            "--serve",
            metavar="PORT",
            help="Serve the live page of the journal on this port (0: any free port) until Ctrl-C or "
            "SIGTERM; it refreshes as records are written. Read-only.",
        ),
    ] = None,
    host: Annotated[
        str, typer.Option(help="Address to serve on (loopback unless --allow-remote).")
    ] = "127.0.0.1",
    allow_remote: Annotated[
        bool, typer.Option("--allow-remote", help="Allow --host to be a non-loopback address.")
    ] = False,
) -> None:
    """Write an offline HTML report (map, time series, checks, provenance) of a journal or record, or
    serve the live page of a journal being written."""
    # imported here: plotly and scipy would slow every other `oceanloc` command's start
    from oceanloc.report.html.kml_layers import report_kml
    from oceanloc.report.html.live import LiveServer
    from oceanloc.report.html.page import render_html
    from oceanloc.report.html.sources import detect_kind, load_report

    if html is None and serve is None:
        raise DataError("nothing to do: give --html PATH (a report file) or --serve PORT (the live page)")
    if kml is not None and html is None:
        raise DataError("--kml PATH goes with --html PATH (the KML holds the report's map layers)")
    for out in (html, kml):
        if out is not None and not out.parent.is_dir():
            raise DataError(f"{out}: folder {out.parent} does not exist")
    server = None
    if serve is not None:  # checked before anything is written
        if detect_kind(source)[0] != "journal":
            raise DataError(f"{source}: --serve needs a survey journal (SQLite), not a JSON record")
        server = LiveServer(source, serve, host, allow_remote=allow_remote)
    if html is not None:
        rep = load_report(source)
        kml_origin = parse_origin(origin) if origin is not None else None
        if kml is not None:  # checked before the HTML is written, so a usage error leaves no half output
            report_kml(rep, kml, kml_origin)
        html.write_text(render_html(rep), encoding="utf-8")
        err_console.print(f"wrote {escape(str(html))} ({rep.kind} report)", highlight=False)
        if kml is not None:
            err_console.print(f"wrote {escape(str(kml))}", highlight=False)
    if server is not None:
        server.start()
        console.print(
            f"live page of {escape(str(source))}: {server.url}  (Ctrl-C to stop)",
            highlight=False,
            soft_wrap=True,
        )
        console.file.flush()
        server.wait()
        err_console.print("stopped serving", highlight=False)
