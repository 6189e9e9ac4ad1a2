"""The ``oceanloc`` command (typer): each command parses its options, calls one library function and hands
the result to :mod:`oceanloc.report` and :mod:`oceanloc.io`.

:mod:`.app` is the console script (usage errors exit 2 with a one-line reason), :mod:`.root` the root app
and its groups, :mod:`.commands` registers every command module; :mod:`._common` and :mod:`._options` hold
the console, progress and output helpers and the shared option parsers.
"""
