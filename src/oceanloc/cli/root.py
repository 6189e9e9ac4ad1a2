"""The root ``oceanloc`` Typer app and its command groups.

Command modules register their commands here (``@root.app.command(...)``) or on a group
(``@reproduce.app.command(...)``), and each group module adds its group to this app; which module
registers which command is :data:`oceanloc.cli.commands.COMMAND_MODULES`. Nothing here imports a
command module, so the command line starts by importing only the modules of the command it runs.
"""

from __future__ import annotations

import typer

from oceanloc import __version__

app = typer.Typer(
    name="oceanloc",
    help="Surface-based underwater acoustic localization: survey, track, plan.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)


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
