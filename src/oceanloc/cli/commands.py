"""Which command module registers which command, so the command line imports only what it runs.

:data:`COMMAND_MODULES` maps a command (``survey``) or a group's subcommand (``survey run``) to the
modules (in :mod:`oceanloc.cli`) that register it; :func:`modules_for` picks them from a command line and
:func:`load` imports them. A command line naming no known command (``--help``, a typo) loads all, so
the root help lists everything and click's "No such command" is unchanged. ``tests/cli/test_commands.py``
checks the table against the commands the modules register.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence

ALL_MODULES: tuple[str, ...] = (
    "scenarios",
    "replay",
    "reproduce",
    "simulate",
    "dop",
    "drift_plan",
    "localize",
    "report",
    "reproduce_dillard",
    "reproduce_dillard_drrt",
    "reproduce_garcia",
    "simulate_drift",
    "simulate_logs",
    "simulate_survey",
    "survey_journal",
    "survey_run",
    "tdoa",
)
"""Every command module, in the order that gives the help's order of commands."""

_SURVEY_JOURNAL = ("survey_journal",)
_REPRODUCE = ("reproduce", "reproduce_dillard", "reproduce_dillard_drrt", "reproduce_garcia")
_SIMULATE = ("simulate", "simulate_drift", "simulate_logs", "simulate_survey")

COMMAND_MODULES: dict[str, tuple[str, ...]] = {
    "demo": ("simulate", "simulate_survey"),
    "dop": ("dop",),
    "drift-plan": ("drift_plan",),
    "localize": ("localize",),
    "replay": ("replay",),
    "report": ("report",),
    "reproduce": _REPRODUCE,
    "scenarios": ("scenarios",),
    "simulate": _SIMULATE,
    "survey": ("survey_journal", "survey_run"),
    "survey add": _SURVEY_JOURNAL,
    "survey check": _SURVEY_JOURNAL,
    "survey export": _SURVEY_JOURNAL,
    "survey next": _SURVEY_JOURNAL,
    "survey run": ("survey_journal", "survey_run"),
    "survey start": _SURVEY_JOURNAL,
    "survey status": _SURVEY_JOURNAL,
    "tdoa": ("tdoa",),
}
"""Command, or ``group subcommand``, to the modules that register it (a group: all its subcommands')."""


def modules_for(argv: Sequence[str]) -> tuple[str, ...]:
    """The modules a command line needs: none for ``--version``; those of its ``group subcommand`` if
    listed, else of its command, else (no command, ``--help``, an unknown name) all of them."""
    if list(argv[:1]) == ["--version"]:
        return ()
    words: list[str] = []
    for arg in argv:
        if arg.startswith("-") or len(words) == 2:
            break
        words.append(arg)
    if len(words) == 2 and " ".join(words) in COMMAND_MODULES:
        return COMMAND_MODULES[" ".join(words)]
    if words and words[0] in COMMAND_MODULES:
        return COMMAND_MODULES[words[0]]
    return ALL_MODULES


def load(modules: Sequence[str] = ALL_MODULES) -> None:
    """Import command modules (each registers its commands on import; importing twice is a no-op)."""
    for name in modules:
        importlib.import_module(f"oceanloc.cli.{name}")
