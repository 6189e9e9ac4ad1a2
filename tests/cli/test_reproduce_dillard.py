"""`oceanloc reproduce dillard-filters` and `dillard-lab-tdoa` on shortened runs."""

import json

from typer.testing import CliRunner

from oceanloc.cli.app import app


def test_dillard_filters_command(tmp_path):
    out, figs = tmp_path / "t2.json", tmp_path / "figs"
    args = [
        "reproduce",
        "dillard-filters",
        "--runs",
        "2",
        "--duration",
        "1",
        "--workers",
        "1",
        "--no-controls",
    ]
    result = CliRunner().invoke(app, [*args, "--json", str(out), "--figures", str(figs)])
    assert result.exit_code == 0, result.output
    assert "Table 2" in result.output and "765.7431" in result.output
    payload = json.loads(out.read_text())
    assert payload["runs"] == 2 and set(payload["filters"]) == {"ekf", "ukf"}
    names = sorted(p.name for p in figs.glob("*.png"))
    assert names == [
        "fig25_geometry.png",
        "fig26_ekf_track.png",
        "fig27_ekf_residuals.png",
        "fig28_ukf_track.png",
        "fig29_ukf_residuals.png",
        "rmse_vs_pcrlb.png",
    ]


def test_dillard_lab_tdoa_command(tmp_path, monkeypatch):
    scenario = tmp_path / "lab.toml"
    from oceanloc.config.builtin import builtin_folder

    text = builtin_folder("flock").joinpath("dillard-lab-tdoa.toml").read_text()
    scenario.write_text(text.replace("duration_s = 120.0", "duration_s = 4.0"))
    figs = tmp_path / "lab"
    args = ["reproduce", "dillard-lab-tdoa", "--runs", "2", "--workers", "1", "--scenario", str(scenario)]
    result = CliRunner().invoke(app, [*args, "--figures", str(figs), "--json", str(tmp_path / "lab.json")])
    assert result.exit_code == 0, result.output
    assert "corr(residual, HDOP)" in result.output
    assert len(list(figs.glob("*.png"))) == 3
    assert json.loads((tmp_path / "lab.json").read_text())["runs"] == 2
