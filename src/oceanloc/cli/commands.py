"""Imports every command module so that each registers its commands on the root app or a group.

One import per module; keep them sorted so that merges stay trivial.
"""

from __future__ import annotations

import oceanloc.cli.dop
import oceanloc.cli.reproduce_dillard
import oceanloc.cli.tdoa  # noqa: F401
