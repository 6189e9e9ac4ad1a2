"""Usage mistakes through a real subprocess of the installed ``oceanloc`` script: exit status 2, the
usage and a one-line reason on stderr, never a traceback (typer carries its own copy of click, whose
exceptions an in-process runner would hide)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest


def _script() -> list[str]:
    beside = Path(sys.executable).with_name("oceanloc")
    if beside.exists():
        return [str(beside)]
    found = shutil.which("oceanloc")
    return [found] if found else [sys.executable, "-m", "oceanloc"]


def _run(*args: str, entry: list[str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*(entry or _script()), *args],
        capture_output=True,
        text=True,
        env={**os.environ, "COLUMNS": "100"},
        timeout=120,
        stdin=subprocess.DEVNULL,
    )


MISTAKES = {
    "unknown option": (["--no-such-option"], "No such option: --no-such-option"),
    "unknown command": (["no-such-command"], "No such command 'no-such-command'"),
    "bad value": (["simulate", "survey", "--runs", "0"], "Invalid value for '--runs'"),
    "not a number": (["simulate", "survey", "--runs", "many"], "Invalid value for '--runs'"),
    "missing argument": (["scenarios", "show"], "Missing argument"),
    "unknown sub-option": (["survey", "status", "x.db", "--bogus"], "No such option: --bogus"),
}


@pytest.mark.parametrize("case", sorted(MISTAKES))
def test_usage_mistakes_exit_2_with_a_one_line_reason(case):
    args, reason = MISTAKES[case]
    result = _run(*args)
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "Traceback" not in result.stderr + result.stdout
    errors = [line for line in result.stderr.splitlines() if line.startswith("Error:")]
    assert len(errors) == 1 and reason in errors[0], result.stderr
    assert "Usage: oceanloc" in result.stderr


def test_no_arguments_prints_the_help_and_exits_2():
    result = _run()
    assert result.returncode == 2
    assert "Traceback" not in result.stderr + result.stdout
    shown = result.stdout + result.stderr
    assert "Usage: oceanloc" in shown and "simulate" in shown


def test_python_dash_m_is_the_same_command():
    result = _run("--no-such-option", entry=[sys.executable, "-m", "oceanloc"])
    assert result.returncode == 2 and "No such option" in result.stderr
    assert _run("--version", entry=[sys.executable, "-m", "oceanloc"]).stdout.startswith("oceanloc ")


def test_user_error_is_one_escaped_line(tmp_path):
    # A file name with rich markup in it must print as written, and not crash the error path.
    missing = tmp_path / "[/x] [sensor].toml"
    result = _run("simulate", "survey", "--scenario", str(missing))
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "[/x] [sensor].toml" in lines[0], result.stderr
