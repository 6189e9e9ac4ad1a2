"""The root ``oceanloc`` Typer app and its command groups.

Command modules register their commands here (``@root.app.command(...)``) or on a group
(``@reproduce.app.command(...)``); :mod:`oceanloc.cli.commands` imports them all.
"""

from __future__ import annotations

import typer

from oceanloc import __version__
from oceanloc.cli import replay, reproduce, simulate
from oceanloc.cli import scenarios as scenarios_cmd

app = typer.Typer(
    name="oceanloc",
    help="Surface-based underwater acoustic localization: survey, track, plan.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)
app.add_typer(scenarios_cmd.app, name="scenarios")
app.add_typer(replay.app, name="replay")
app.add_typer(reproduce.app, name="reproduce")
app.add_typer(simulate.app, name="simulate")


def _version(value: bool) -> None:
    if value:
        typer.echo(f"oceanloc {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version."
    ),
) -> None:
    """Surface-based underwater acoustic localization: survey, track, plan."""
