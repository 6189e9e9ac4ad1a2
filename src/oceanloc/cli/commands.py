"""Imports every command module so that each registers its commands on the root app or a group.

One import per module; keep them sorted so that merges stay trivial.
"""

from __future__ import annotations

from oceanloc.cli import (
    localize,  # noqa: F401
    simulate_logs,  # noqa: F401
)
