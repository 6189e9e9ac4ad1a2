import json
import os
import subprocess
import sys

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
            "32.7,-117.2",
            "--json",
            str(tmp_path / "plan.json"),
        ],
    )
    assert result.exit_code == 0, result.output
    assert "flight energy (Wh)" in result.output and "2000" in result.output and "convention" in result.output
    stem = tmp_path / "dillard-drift-fixed-thesis-single"
    assert stem.with_suffix(".png").exists() and stem.with_suffix(".csv").exists()
    data = json.loads(stem.with_suffix(".geojson").read_text())
    assert data["properties"]["planner"] == "thesis-single"
    # --origin is LAT,LON like every other command: the start (-4 km, +4 km) lies NW of 32.7 N, 117.2 W.
    lon, lat = data["features"][0]["geometry"]["coordinates"][0]
    assert -117.25 < lon < -117.2 and 32.7 < lat < 32.75
    record = json.loads((tmp_path / "plan.json").read_text())
    prov = record["provenance"]
    assert prov["scenario"] == "dillard-drift-fixed" and len(prov["scenario_sha256"]) == 64
    assert record["planner"] == "thesis-single" and record["result"]["status"] == "exact"
    assert len(record["result"]["path"]["x_m"]) == len(record["result"]["path"]["flight"]) + 1


def test_drift_plan_oceanloc_in_international_units(tmp_path):
    result = runner.invoke(
        app, ["drift-plan", "--scenario", "dillard-drift-continuous", "--out", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    assert "1852" in result.output and "international" in result.output and "exact" in result.output
    assert "no GeoJSON" in result.output and "--origin LAT,LON" in result.output


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
            "--netcdf",
            str(tmp_path / "r.nc"),
        ],
    )
    assert result.exit_code == 0, result.output
    assert "thesis Table 4" in result.output and "38.69" in result.output
    payload = json.loads(out.read_text())
    assert {"provenance", "direct_flight_wh", "planners", "best_achievable_wh", "runs"} <= set(payload)
    assert payload["provenance"]["oceanloc_version"] and "dillard-drrt" in payload["provenance"]["command"]
    assert payload["provenance"]["scenario"] == "dillard-drift-fixed" and payload["runs"] == 2
    import xarray as xr

    with xr.open_dataset(tmp_path / "r.nc") as ds:
        assert dict(ds.sizes) == {"planner": 3, "run": 2, "problem_index": 1}
        assert ds["flight_energy"].attrs["units"] == "W h" and ds.attrs["Conventions"].startswith("CF-")
        assert ds.attrs["scenario"] == "dillard-drift-fixed" and "scenario_sha256" in ds.attrs
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
            "--netcdf",
            str(tmp_path / "f.nc"),
        ],
    )
    assert result.exit_code == 0, result.output
    assert "arrival rate (%)" in result.output
    record = json.loads((tmp_path / "f.json").read_text())
    assert record["runs"] == 2 and record["provenance"]["scenario"] == "dillard-drift-fixed"
    assert (tmp_path / "f.nc").exists() and (tmp_path / "dillard-drift-fixed-following.png").exists()
    result = runner.invoke(
        app, ["simulate", "drift-swap", "--figures", str(tmp_path), "--json", str(tmp_path / "s.json")]
    )
    assert result.exit_code == 0, result.output
    assert "closest approach" in result.output
    assert (tmp_path / "dillard-drift-swap-plans.png").exists()
    assert json.loads((tmp_path / "s.json").read_text())["provenance"]["scenario"] == "dillard-drift-swap"


def test_bad_scenario_is_one_line_with_status_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[scenario]\nname = "x"\n[currents]\nkind = "whirlpool"\n'
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


@pytest.mark.parametrize(
    ("args", "reason"),
    [
        (["drift-plan", "--scenario", "dillard-drift-fixed", "--origin", "-117.2,32.7"], "LAT -117.2"),
        (["drift-plan", "--scenario", "dillard-drift-fixed", "--planner", "rrt"], "--planner must be one of"),
        (["simulate", "drift-follow", "--planner", "astar", "--runs", "1"], "--planner must be one of"),
        (["reproduce", "dillard-drrt", "--runs", "0"], "--runs"),
    ],
)
def test_usage_errors_exit_2_with_one_line(args, reason, tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "oceanloc",
            *args,
            *(["--out", str(tmp_path)] if args[0] == "drift-plan" else []),
        ],
        capture_output=True,
        text=True,
        env=os.environ,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    assert reason in proc.stderr and "Traceback" not in proc.stderr


def test_a_scenario_name_with_markup_is_printed_as_written(tmp_path):
    text = tmp_path / "x.toml"
    text.write_text(
        '[scenario]\nname = "odd[/x]"\n[currents]\nkind = "uniform"\nvelocity_mps = [0.5, 0.0]\n'
        "[map]\nbounds_m = [-500.0, 4000.0, -500.0, 2500.0]\n"
        "[route]\nstart_m = [0.0, 0.0]\ngoal_m = [3000.0, 1200.0]\n"
    )
    result = runner.invoke(app, ["drift-plan", "--scenario", str(text), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "odd[/x]: oceanloc" in result.output
    # The file names stay in the output folder.
    assert (tmp_path / "odd__x_-oceanloc.png").exists() and not (tmp_path / "odd[").exists()
