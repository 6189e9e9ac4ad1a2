"""Scenario and option values past their physical range are refused with one line, before any work."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from oceanloc.config.catalog import load_scenario
from oceanloc.config.drift import load_drift_scenario
from oceanloc.config.flock import load_flock_scenario
from oceanloc.config.survey import MAX_RESULT_BYTES, load_survey_scenario
from oceanloc.config.toml_fields import MAX_TOML_DEPTH
from oceanloc.errors import ConfigError


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "oceanloc", *args], capture_output=True, text=True, env=os.environ, cwd=cwd
    )


def _one_line_error(res: subprocess.CompletedProcess, *parts: str) -> None:
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr + res.stdout
    for part in parts:
        assert part in lines[0], (part, lines[0])


@pytest.mark.parametrize(
    ("runs", "gib"),
    [("1000000000", "2.17e+04 GiB"), ("5000000", "108 GiB")],
)
def test_too_many_runs_are_refused_with_a_memory_estimate(tmp_path: Path, runs: str, gib: str):
    res = _cli("simulate", "survey", "--scenario", "garcia2019-m4", "--runs", runs, cwd=tmp_path)
    # 50 epochs, 4 transponders: 8 B * 51 * (5 + 4 * 13) = 23256 B per run
    _one_line_error(res, f"--runs {runs}:", gib, "limit 4 GiB", f"use --runs {MAX_RESULT_BYTES // 23256} or")


def test_a_huge_epoch_override_is_refused_even_for_one_run(tmp_path: Path):
    res = _cli(
        "simulate",
        "survey",
        "--scenario",
        "garcia2019-m1",
        "--runs",
        "1",
        "--epochs",
        "1000000000",
        cwd=tmp_path,
    )
    _one_line_error(res, "--runs 1:", "GiB of results", "fewer --epochs")


def test_bytes_per_run_follows_the_scenario():
    s = load_survey_scenario("garcia2019-m4")
    assert s.bytes_per_run() == 8 * (s.epochs + 1) * (5 + 4 * 13)
    s.check_runs(1000)  # 23 MB: fine
    with pytest.raises(ConfigError, match="use --runs 10 or fewer"):
        s.check_runs(11, max_bytes=10 * s.bytes_per_run())


@pytest.mark.parametrize("duration", ["nan", "-5", "0", "1e12", "inf"])
def test_simulate_logs_refuses_an_absurd_duration(tmp_path: Path, duration: str):
    res = _cli("simulate", "logs", "--out", "o", "--duration", duration, cwd=tmp_path)
    _one_line_error(res, "duration", "s is not in (400, 604800] s")
    assert not (tmp_path / "o" / "gps.nmea").exists()


def _deep_tables(n: int) -> str:
    return "[" + ".".join(["x"] * n) + "]\n"


def _deep_arrays(n: int) -> str:
    return "a = " + "[" * n + "]" * n + "\n"


@pytest.mark.parametrize(
    "loader", [load_survey_scenario, load_flock_scenario, load_drift_scenario, load_scenario]
)
@pytest.mark.parametrize("text", [_deep_tables(500), _deep_arrays(500), _deep_tables(MAX_TOML_DEPTH + 1)])
def test_toml_nested_too_deep_is_refused_by_every_loader(tmp_path: Path, loader, text: str):
    path = tmp_path / "deep.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=r"deep.toml: .*nested (too )?deep"):
        loader(path)


@pytest.mark.parametrize("command", [["simulate", "survey"], ["simulate", "drift-swap"]])
def test_toml_nested_500_deep_through_the_command(tmp_path: Path, command: list[str]):
    (tmp_path / "deep.toml").write_text(_deep_tables(500))
    res = _cli(*command, "--scenario", "deep.toml", cwd=tmp_path)
    _one_line_error(res, "deep.toml:", "nested deeper than 16 levels")
