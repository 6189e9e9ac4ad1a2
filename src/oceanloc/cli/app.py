"""The ``oceanloc`` console script: the root app with every command registered, and error handling.

The CLI is a thin shell over the library: command modules only parse options, call library functions
and print or write their results. User errors (:class:`oceanloc.errors.OceanlocError`) end with a
one-line message and exit status 2, never a traceback.
"""

from __future__ import annotations

import sys

import click

from oceanloc.cli import commands  # noqa: F401  (registers every command)
from oceanloc.cli._common import err_console
from oceanloc.cli.root import app
from oceanloc.errors import OceanlocError

__all__ = ["app", "main"]


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
