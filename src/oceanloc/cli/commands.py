"""Imports every command module so that each registers its commands on its group.

One import per capability; keep them in alphabetical order to make merges trivial.
"""

from __future__ import annotations
