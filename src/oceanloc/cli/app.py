"""The root ``oceanloc`` app with every command registered (for in-process use: tests, notebooks), and
the console script's :func:`~oceanloc.cli.main.main`.

The CLI is a thin shell over the library: command modules only parse options, call library functions
and print or write their results. The console script itself (:mod:`oceanloc.cli.main`) imports only the
modules of the command it runs.
"""

from __future__ import annotations

from oceanloc.cli import commands
from oceanloc.cli.main import main
from oceanloc.cli.root import app

commands.load()

__all__ = ["app", "main"]

if __name__ == "__main__":
    main()
