import json

import pytest
from typer.testing import CliRunner

from oceanloc.cli.app import app, main


def test_demo_prints_the_table_and_writes_the_trajectory(tmp_path):
    result = CliRunner().invoke(app, ["demo", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "after 50 epochs" in result.output and "Error and D-optimal value by epoch" in result.output
    assert "NEES at n = 50" in result.output
    assert (tmp_path / "garcia2019-m4_trajectory.png").stat().st_size > 10_000


def test_simulate_survey_monte_carlo_json(tmp_path):
    out = tmp_path / "mc.json"
    args = [
        "simulate",
        "survey",
        "--scenario",
        "garcia2019-m1",
        "--runs",
        "4",
        "--epochs",
        "8",
        "--workers",
        "1",
    ]
    result = CliRunner().invoke(app, [*args, "--horizon", "2", "--json", str(out)])
    assert result.exit_code == 0, result.output
    record = json.loads(out.read_text())
    assert record["planner"] == "k2" and record["runs"] == 4 and len(record["rmsee_m"]) == 8
    assert record["nees"]["dof"] == 3


def test_simulate_survey_single_run_json(tmp_path):
    out = tmp_path / "one.json"
    args = ["simulate", "survey", "--scenario", "garcia2018-greedy-m4", "--runs", "1", "--epochs", "5"]
    result = CliRunner().invoke(app, [*args, "--json", str(out)])
    assert result.exit_code == 0, result.output
    record = json.loads(out.read_text())
    assert len(record["transponders"]) == 4 and record["planner"] == "greedy"


def test_bad_planner_and_bad_file_are_one_line_errors(tmp_path, capsys):
    for argv in (
        ["simulate", "survey", "--scenario", "garcia2019-m1", "--planner", "best"],
        ["simulate", "survey", "--scenario", str(tmp_path / "missing.toml")],
    ):
        try:
            main(argv)
        except SystemExit as exc:
            assert exc.code == 2
        err = capsys.readouterr().err
        assert "error:" in err and "Traceback" not in err


def test_reproduce_garcia2019_small(tmp_path):
    args = ["reproduce", "garcia2019", "--runs", "3", "--workers", "1", "--seed", "5", "--horizons", "0,2"]
    result = CliRunner().invoke(app, [*args, "--json", str(tmp_path / "g.json"), "--figures", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "Table III" in result.output and "Acceptance checks" in result.output
    names = {p.name for p in tmp_path.glob("*.png")}
    assert {
        "fig1_estimates_en.png",
        "fig2_nees_n4.png",
        "fig3_m1_logdet_rmse.png",
        "fig8_trajectories_m4.png",
    } <= names
    assert len(names) == 8


def _oceanloc(*args):
    import os
    import subprocess
    import sys

    return subprocess.run(
        [sys.executable, "-m", "oceanloc", *args], capture_output=True, text=True, env=os.environ, timeout=120
    )


@pytest.mark.parametrize(
    ("args", "reason"),
    [
        (
            ("simulate", "survey", "--scenario", "garcia2019-m1", "--planner", "best"),
            "unknown planner 'best'",
        ),
        (("scenarios", "show", "nope"), "'nope' is neither a scenario file nor a built-in scenario"),
        (("reproduce", "garcia2019", "--horizons", "0,x"), "--horizons must be comma-separated integers"),
    ],
)
def test_usage_errors_of_the_survey_commands_exit_2_with_one_line(args, reason):
    proc = _oceanloc(*args)
    assert proc.returncode == 2, proc.stderr
    assert reason in " ".join(proc.stderr.split()) and "Traceback" not in proc.stderr
    assert proc.stderr.count("error:") == 1 and proc.stderr.startswith("error:")  # one reason


def test_simulate_survey_netcdf_and_json_carry_the_scenario_hash(tmp_path):
    import hashlib

    import xarray as xr

    from oceanloc.config.survey import load_survey_scenario

    args = [
        "simulate",
        "survey",
        "--scenario",
        "garcia2019-m1",
        "--runs",
        "3",
        "--epochs",
        "4",
        "--workers",
        "1",
    ]
    nc, js = tmp_path / "mc.nc", tmp_path / "mc.json"
    result = CliRunner().invoke(app, [*args, "--planner", "k0", "--netcdf", str(nc), "--json", str(js)])
    assert result.exit_code == 0, result.output
    digest = hashlib.sha256(load_survey_scenario("garcia2019-m1").toml_text.encode()).hexdigest()
    record = json.loads(js.read_text())
    assert record["provenance"]["scenario"] == "garcia2019-m1"
    assert record["provenance"]["scenario_sha256"] == digest
    assert len(record["consistency_by_epoch"]["mean_nees"]) == 4
    with xr.open_dataset(nc) as ds:
        assert dict(ds.sizes) == {"epoch": 4, "transponder": 1, "run": 3}
        assert ds.attrs["scenario_sha256"] == digest and ds["rmsee"].attrs["units"] == "m"
        assert ds.attrs["planner"] == "k0"


def test_scenarios_list_shows_every_kind():
    result = CliRunner().invoke(app, ["scenarios", "list"])
    assert result.exit_code == 0, result.output
    for name in ("garcia2019-m4", "dillard-lab-tdoa", "dillard-drift-swap"):
        assert name in result.output


def test_reproduce_garcia2018_prints_what_does_not_reproduce(tmp_path):
    args = [
        "reproduce",
        "garcia2018-greedy",
        "--runs",
        "3",
        "--workers",
        "1",
        "--json",
        str(tmp_path / "g.json"),
    ]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "Which thesis tables and figures reproduce" in result.output
    assert "works" not in result.output
    record = json.loads((tmp_path / "g.json").read_text())
    missing = [v["item"] for v in record["verdicts"] if v["status"] == "does not reproduce"]
    assert record["reproduced"] is (not missing)
    if missing:
        assert "Does not reproduce:" in result.output
    assert record["provenance"]["scenario"] == "garcia2018-greedy-m1 + garcia2018-greedy-m4"
