"""``oceanloc survey run`` usage errors, through a subprocess of the installed package: a one-line reason
naming the option, exit status 2, no traceback, and the journal untouched."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "oceanloc", "survey", *args], capture_output=True, text=True, env=os.environ,
        timeout=60,
    )  # fmt: skip


@pytest.fixture
def journal(tmp_path: Path) -> Path:
    path = tmp_path / "j.db"
    assert _run("start", str(path), "--beacon", "1").returncode == 0
    return path


SOURCES = ("--position", "udp://127.0.0.1:10110", "--ranges", "udp://127.0.0.1:10111")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ((*SOURCES,), "survey run needs a stop rule: --goal METRES, --max-time SECONDS or --max-sites N"),
        ((*SOURCES, "--goal", "0"), "goal_m must be a positive number, got 0.0"),
        ((*SOURCES, "--max-time", "60"), "survey run needs --vehicle SPEC to command, or --dry-run"),
        (("--position", "ftp://x", "--ranges", "udp://127.0.0.1:1", "--goal", "1", "--dry-run"), "ftp"),
        (
            ("--position", "mavlink", "--ranges", "udp://127.0.0.1:1", "--goal", "1", "--dry-run"),
            "--position mavlink needs --vehicle",
        ),
        ((*SOURCES, "--goal", "1", "--timeouts", "1,2"), "--timeouts"),
        ((*SOURCES, "--goal", "1", "--fence-radius", "-3"), "geofence radius must be a positive number"),
        ((*SOURCES, "--goal", "1", "--return-to", "95,0"), "--return-to"),
        ((*SOURCES, "--goal", "1", "--dry-run", "--json-lines", "/nonexistent/dir/e.jsonl"), "--json-lines"),
        ((*SOURCES, "--goal", "1", "--fence", "/nonexistent.geojson"), "nonexistent.geojson"),
    ],
)
def test_usage_errors_are_one_line_with_the_option(journal: Path, extra: tuple, message: str):
    before = journal.read_bytes()
    proc = _run("run", str(journal), *extra)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    assert message in " ".join(proc.stderr.split()), proc.stderr
    assert journal.read_bytes() == before


def test_a_journal_never_started_is_named(tmp_path: Path):
    proc = _run("run", str(tmp_path / "none.db"), *SOURCES, "--goal", "1", "--dry-run")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "no survey journal here (start one with `oceanloc survey start`)" in " ".join(proc.stderr.split())
    assert not (tmp_path / "none.db").exists()
