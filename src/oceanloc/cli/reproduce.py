"""``oceanloc reproduce``: the command group; each paper registers its command from its own module."""

from __future__ import annotations

import typer

from oceanloc.cli import root

app = typer.Typer(
    help="Reproduce the papers' tables and figures, with the published values beside ours.",
    no_args_is_help=True,
)
root.app.add_typer(app, name="reproduce")
