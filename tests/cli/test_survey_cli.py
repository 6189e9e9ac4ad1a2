import json

from typer.testing import CliRunner

from oceanloc.cli.app import app, main


def test_demo_prints_the_table_and_writes_the_trajectory(tmp_path):
    result = CliRunner().invoke(app, ["demo", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "After 50 epochs" in result.output and "Error and D-optimal value by epoch" in result.output
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
