"""Shared test configuration: a non-interactive matplotlib backend, deterministic hypothesis runs."""

import matplotlib
from hypothesis import settings

matplotlib.use("Agg")

# Property tests draw the same examples on every run (and record nothing between runs), so the suite is
# deterministic; a failure found while developing is pinned with @example.
settings.register_profile("oceanloc", derandomize=True, database=None, deadline=None, print_blob=True)
settings.load_profile("oceanloc")
