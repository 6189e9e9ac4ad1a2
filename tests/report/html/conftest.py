"""Records of every kind a report reads, made once per session by the real commands (small settings)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from oceanloc.cli.app import app
from oceanloc.config.survey import PlannerSettings
from oceanloc.field.survey.journal import Journal, append_gps_log, append_range_log
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.io.nmea import read_nmea
from oceanloc.io.usbl import read_usbl
from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

JOURNAL_SETTINGS = JournalSettings(planner=PlannerSettings(kind="greedy", max_distance_m=4.0), beacons=(1, 2))

COMMANDS = {
    "survey": ["simulate", "survey", "--scenario", "garcia2019-m4", "--runs", "1", "--epochs", "40"],
    "montecarlo": [
        "simulate",
        "survey",
        "--scenario",
        "garcia2019-m4",
        "--runs",
        "4",
        "--epochs",
        "12",
        "--workers",
        "1",
    ],
    "gnssa": ["localize", "gnssa"],
    "gnssa-array": ["localize", "gnssa", "--format", "gnatss"],
    "reproduction": ["reproduce", "garcia2019", "--runs", "3", "--workers", "1"],
    "drift": ["drift-plan", "--scenario", "dillard-drift-continuous"],
}


def make_journal(folder: Path, duration_s: float = 600.0) -> Path:
    """A started journal holding simulated pier logs (two beacons, both estimated)."""
    logs = simulate_pier_logs(folder, PierLogSettings(duration_s=duration_s), np.random.default_rng(3))
    path = folder / "survey.db"
    with Journal.start(path, JOURNAL_SETTINGS.to_meta()) as j:
        append_gps_log(j, read_nmea(logs.nmea_path), logs.nmea_path)
        append_range_log(j, read_usbl(logs.ranges_path, beacons=(1, 2)), logs.ranges_path)
    return path


@pytest.fixture(scope="session")
def sources(tmp_path_factory) -> dict[str, Path]:
    """kind -> source file, for every kind of report."""
    folder = tmp_path_factory.mktemp("report-sources")
    out = {"journal": make_journal(folder)}
    runner = CliRunner()
    for kind, args in COMMANDS.items():
        path = folder / f"{kind}.json"
        extra = ["--out", str(folder / "drift-out")] if kind == "drift" else []
        res = runner.invoke(app, [*args, "--json", str(path), *extra])
        assert res.exit_code == 0, res.output
        out[kind] = path
    return out


@pytest.fixture(scope="session")
def reports(sources) -> dict:
    """kind -> its :class:`Report` (built once: a journal's report re-estimates the beacons)."""
    from oceanloc.report.html.sources import load_report

    return {kind: load_report(path) for kind, path in sources.items()}
