"""``python -m oceanloc``: the same command line as the ``oceanloc`` script."""

from oceanloc.cli.main import main

main()
