import json

import pytest
from typer.testing import CliRunner

from oceanloc.cli.app import app, main

runner = CliRunner()


def test_drift_plan_writes_figure_csv_and_geojson(tmp_path):
    result = runner.invoke(
        app,
        [
            "drift-plan",
            "--scenario",
            "dillard-drift-fixed",
            "--planner",
            "thesis-single",
            "--out",
            str(tmp_path),
            "--origin",
            "-117.2,32.7",
        ],
    )
    assert result.exit_code == 0, result.output
    assert "flight energy" in result.output and "2000" in result.output and "convention" in result.output
    stem = tmp_path / "dillard-drift-fixed-thesis-single"
    assert stem.with_suffix(".png").exists() and stem.with_suffix(".csv").exists()
    data = json.loads(stem.with_suffix(".geojson").read_text())
    assert data["properties"]["planner"] == "thesis-single"


def test_drift_plan_oceanloc_in_international_units(tmp_path):
    result = runner.invoke(
        app, ["drift-plan", "--scenario", "dillard-drift-continuous", "--out", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    assert "1852" in result.output and "international" in result.output and "exact" in result.output
    assert "no GeoJSON" in result.output


def test_reproduce_dillard_drrt_json(tmp_path):
    out = tmp_path / "r.json"
    result = runner.invoke(
        app,
        [
            "reproduce",
            "dillard-drrt",
            "--runs",
            "2",
            "--fields",
            "0",
            "--iterations",
            "1500",
            "--reference-spacing",
            "200",
            "--workers",
            "1",
            "--json",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    assert "thesis Table 4" in result.output and "38.69" in result.output
    payload = json.loads(out.read_text())
    assert {"provenance", "direct_flight_wh", "planners", "best_achievable_wh", "runs"} <= set(payload)
    assert payload["provenance"]["oceanloc_version"] and "dillard-drrt" in payload["provenance"]["command"]
    assert payload["direct_flight_wh"] == pytest.approx(49.497, abs=1e-3)


def test_simulate_drift_follow_and_swap(tmp_path):
    result = runner.invoke(
        app,
        [
            "simulate",
            "drift-follow",
            "--runs",
            "2",
            "--workers",
            "1",
            "--figures",
            str(tmp_path),
            "--json",
            str(tmp_path / "f.json"),
        ],
    )
    assert result.exit_code == 0, result.output
    assert "arrival rate" in result.output
    assert json.loads((tmp_path / "f.json").read_text())["runs"] == 2
    result = runner.invoke(app, ["simulate", "drift-swap", "--figures", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "closest approach" in result.output
    assert (tmp_path / "dillard-drift-swap-plans.png").exists()


def test_bad_scenario_is_one_line_with_status_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[scenario]\nname = "x"\n[currents]\nkind = "tidal"\n'
        "[route]\nstart_m = [0.0, 0.0]\ngoal_m = [1.0, 1.0]\n"
    )
    with pytest.raises(SystemExit) as info:
        main(["drift-plan", "--scenario", str(bad), "--out", str(tmp_path)])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "error:" in err and "kind" in err and "Traceback" not in err


def test_drift_plan_on_the_netcdf_product_writes_lonlat_geojson(tmp_path):
    result = runner.invoke(
        app, ["drift-plan", "--scenario", "dillard-drift-gyre-netcdf", "--out", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    assert "dillard-drift-gyre.nc" in result.output
    data = json.loads((tmp_path / "dillard-drift-gyre-netcdf-oceanloc.geojson").read_text())
    lon, lat = data["features"][0]["geometry"]["coordinates"][0]
    assert -117.7 < lon < -117.4 and 32.5 < lat < 32.7
