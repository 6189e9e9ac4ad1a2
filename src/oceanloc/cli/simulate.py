"""``oceanloc simulate``: the command group; each simulation registers its command from its own module."""

from __future__ import annotations

import typer

from oceanloc.cli import root

app = typer.Typer(help="Simulate surveys and data.", no_args_is_help=True)
root.app.add_typer(app, name="simulate")
