"""Imports every command module so that each registers its commands on the root app or a group.

One import per module; keep them sorted so that merges stay trivial.
"""

from __future__ import annotations

from oceanloc.cli import (  # noqa: F401
    dop,
    drift_plan,
    localize,
    replay,
    report,
    reproduce_dillard,
    reproduce_dillard_drrt,
    reproduce_garcia,
    simulate_drift,
    simulate_logs,
    simulate_survey,
    survey_journal,
    survey_run,
    tdoa,
)
