"""The ``oceanloc`` command: a thin shell over the library.

Each command group lives in its own module and only parses options, calls library functions and
prints or writes their results. User errors (:class:`oceanloc.errors.OceanlocError`) end with a one-line
message and exit status 2, never a traceback.
"""

from __future__ import annotations

import sys

import click
import typer

from oceanloc import __version__
from oceanloc.cli import reproduce, simulate
from oceanloc.cli import scenarios as scenarios_cmd
from oceanloc.cli._common import err_console
from oceanloc.errors import OceanlocError

app = typer.Typer(
    name="oceanloc",
    help="Surface-based underwater acoustic localization: survey, track, plan.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)
app.add_typer(scenarios_cmd.app, name="scenarios")
app.add_typer(reproduce.app, name="reproduce")
app.add_typer(simulate.app, name="simulate")

# Command modules register their commands on a group (or on ``app``) when imported; one line each.
from oceanloc.cli import commands  # noqa: E402, F401


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


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point."""
    try:
        app(args=argv, standalone_mode=False)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.exceptions.Abort:
        err_console.print("aborted")
        sys.exit(130)
    except click.ClickException as exc:
        exc.show()
        sys.exit(exc.exit_code)
    except OceanlocError as exc:
        err_console.print(f"[bold red]error:[/bold red] {exc}", highlight=False)
        sys.exit(2)
    except KeyboardInterrupt:
        err_console.print("interrupted")
        sys.exit(130)


if __name__ == "__main__":
    main()
