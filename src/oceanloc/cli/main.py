"""The ``oceanloc`` console script: load the modules of the command given, run it, and handle errors.

User errors (:class:`oceanloc.errors.OceanlocError`) end with a one-line message and exit status 2, never
a traceback. Only the command modules the command line needs are imported
(:func:`oceanloc.cli.commands.modules_for`), so ``oceanloc survey status`` starts without the imports of
the planners, the GNSS-A code or the live survey's links.
"""

from __future__ import annotations

import sys

import click
import typer

from oceanloc.cli import commands
from oceanloc.cli._common import err_console, escape
from oceanloc.cli.root import app
from oceanloc.errors import OceanlocError

__all__ = ["main"]

try:  # typer >= 0.20 carries its own copy of click; older ones raise click's exceptions
    from typer._click import exceptions as _typer_click
except ImportError:  # pragma: no cover - depends on the installed typer
    _typer_click = click.exceptions


def _classes(name: str) -> tuple[type[BaseException], ...]:
    """The exception class ``name`` of click, of typer's copy of click and of typer, where each has it."""
    found = (getattr(m, name, None) for m in (click.exceptions, _typer_click, typer))
    return tuple(dict.fromkeys(c for c in found if isinstance(c, type)))


_EXIT = _classes("Exit")
_ABORT = _classes("Abort")
_NO_ARGS = _classes("NoArgsIsHelpError")
_CLICK_ERRORS = _classes("ClickException")


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point."""
    args = sys.argv[1:] if argv is None else argv
    try:
        commands.load(commands.modules_for(args))
        app(args=args, standalone_mode=False, prog_name="oceanloc")
    except _EXIT as exc:
        sys.exit(exc.exit_code)
    except _ABORT:
        err_console.print("aborted")
        sys.exit(130)
    except _NO_ARGS as exc:
        exc.show()
        sys.exit(2)
    except _CLICK_ERRORS as exc:
        exc.show()
        sys.exit(2 if exc.exit_code == 1 else exc.exit_code)
    except OceanlocError as exc:
        err_console.print(f"[bold red]error:[/bold red] {escape(str(exc))}", highlight=False, soft_wrap=True)
        sys.exit(2)
    except KeyboardInterrupt:
        err_console.print("interrupted")
        sys.exit(130)


if __name__ == "__main__":
    main()
