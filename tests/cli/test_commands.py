"""The command table (:data:`oceanloc.cli.commands.COMMAND_MODULES`) against the commands the modules
register: a command line imports the modules it needs, and only those."""

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from oceanloc.cli import commands
from oceanloc.cli.app import app

_GROUPS = {g.name: g.typer_instance for g in app.registered_groups}


def _module_of_group(name: str) -> str:
    """The command module whose ``app`` is the group ``name``."""
    for mod in commands.ALL_MODULES:
        if getattr(importlib.import_module(f"oceanloc.cli.{mod}"), "app", None) is _GROUPS[name]:
            return mod
    raise AssertionError(f"no module defines the group {name}")


def _registered() -> dict[str, set[str]]:
    """Every command line (``name`` or ``group sub``) to the modules that must be loaded for it."""
    out = {}
    for c in app.registered_commands:
        out[c.name] = {c.callback.__module__.rsplit(".", 1)[1]}
    for name, group in _GROUPS.items():
        home = _module_of_group(name)
        subs = {c.name: c.callback.__module__.rsplit(".", 1)[1] for c in group.registered_commands}
        out[name] = {home, *subs.values()}
        out |= {f"{name} {sub}": {home, mod} for sub, mod in subs.items()}
    return out


def test_every_command_line_loads_the_modules_that_register_it():
    registered = _registered()
    assert len(registered) > 30
    for line, needed in registered.items():
        got = set(commands.modules_for([*line.split(), "--help"]))
        assert needed <= got, (line, needed, got)
    assert set(commands.COMMAND_MODULES) <= set(registered)  # no entry for a command that does not exist
    assert set(commands.ALL_MODULES) == {m for mods in registered.values() for m in mods}


def test_unknown_or_no_command_loads_everything_and_version_nothing():
    assert commands.modules_for([]) == commands.ALL_MODULES
    assert commands.modules_for(["--help"]) == commands.ALL_MODULES
    assert commands.modules_for(["surve", "status"]) == commands.ALL_MODULES
    assert commands.modules_for(["survey", "statu"]) == commands.COMMAND_MODULES["survey"]
    assert commands.modules_for(["--version"]) == ()
    assert commands.modules_for(["survey", "status", "j.db"]) == ("survey_journal",)


_PROBE = """
import sys
from oceanloc.cli.main import main
code = 0
try:
    main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
heavy = [m for m in ("oceanloc.field.live_survey", "pymavlink", "oceanloc.estimation.gnssa_array",
                     "oceanloc.planning.drift_rrt", "scipy.optimize") if m in sys.modules]
print("HEAVY", ",".join(heavy), "CODE", code, file=sys.stderr)
"""


@pytest.mark.parametrize(
    ("args", "heavy"),
    [
        (["survey", "status"], ""),
        (["survey", "run", "--help"], "oceanloc.field.live_survey,pymavlink"),
    ],
)
def test_the_command_line_imports_only_its_command(tmp_path: Path, args: list[str], heavy: str):
    journal = tmp_path / "s.db"
    subprocess.run(
        [sys.executable, "-m", "oceanloc", "survey", "start", str(journal)], check=True, capture_output=True
    )
    argv = [*args, str(journal)] if args[-1] != "--help" else args
    run = subprocess.run(
        [sys.executable, "-c", _PROBE, *argv], capture_output=True, text=True, env=os.environ, timeout=60
    )
    assert f"HEAVY {heavy} CODE" in run.stderr, run.stderr
    assert run.stderr.rstrip().endswith("CODE 0"), run.stderr
