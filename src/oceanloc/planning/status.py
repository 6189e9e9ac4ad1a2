"""Outcome of a planner call, shared by every planner (OMPL's ``PlannerStatus`` vocabulary)."""

from __future__ import annotations

import enum


class PlanStatus(enum.Enum):
    """Outcome of a planner call.

    What "solved" means is the planner's: the measurement-site planners return EXACT when they found the
    global optimum of their planning problem; the drift planners when a path reaches the goal disk.
    """

    EXACT = "exact"
    """The planning problem was solved as posed."""
    APPROXIMATE = "approximate"
    """A usable plan that does not meet the request (e.g. a drift path ending as close to the goal as the
    planner got)."""
    FAILED = "failed"
    """No plan at all (for example an invalid start)."""
