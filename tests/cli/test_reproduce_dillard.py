"""`oceanloc reproduce dillard-filters` and `dillard-lab-tdoa` on shortened runs."""

import json

import xarray as xr
from typer.testing import CliRunner

from oceanloc.cli.app import app
from oceanloc.config.builtin import builtin_folder


def _scenario(tmp_path, name, replacements):
    text = builtin_folder("flock").joinpath(f"{name}.toml").read_text()
    for old, new in replacements:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / f"{name}-short.toml"
    path.write_text(text)
    return path


def test_dillard_filters_command(tmp_path):
    out, nc, figs = tmp_path / "t2.json", tmp_path / "t2.nc", tmp_path / "figs"
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
    result = CliRunner().invoke(app, [*args, "--json", str(out), "--netcdf", str(nc), "--figures", str(figs)])
    assert result.exit_code == 0, result.output
    assert "Table 2: bearing-only" in result.output and "Acceptance checks" in result.output
    payload = json.loads(out.read_text())
    assert payload["runs"] == 2 and set(payload["filters"]) == {"ekf", "ukf"}
    assert payload["table_2"][0]["thesis_ekf"] == 765.7431
    prov = payload["provenance"]
    assert (
        prov["scenario"] == "dillard-filters" and len(prov["scenario_sha256"]) == 64 and prov["seed"] == 2014
    )
    with xr.open_dataset(nc) as ds:
        assert ds.sizes["run"] == 2 and ds.sizes["filter"] == 2 and ds.attrs["scenario"] == "dillard-filters"
    names = sorted(p.name for p in figs.glob("*.png"))
    assert names == [
        "fig25_geometry.png",
        "fig26_ekf_track.png",
        "fig27_ekf_residuals.png",
        "fig28_ukf_track.png",
        "fig29_ukf_residuals.png",
        "rmse_vs_pcrlb.png",
    ]


def test_dillard_filters_on_another_scenario_prints_no_thesis_values(tmp_path):
    path = _scenario(
        tmp_path,
        "dillard-filters",
        [
            ('name = "dillard-filters"', 'name = "my-[ring]"'),
            ("duration_s = 350.0", "duration_s = 1.0"),
            ('kind = "bearing"', 'kind = "range"'),
            ("sigma_true = 0.0316", "sigma_true = 1.0"),
            ("measurement_sigma = 1e-3", "measurement_sigma = 1.0"),
        ],
    )
    args = ["reproduce", "dillard-filters", "--runs", "2", "--workers", "1", "--scenario", str(path)]
    result = CliRunner().invoke(app, [*args, "--json", str(tmp_path / "o.json")])
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "my-[ring]: range-only tracking MSE" in text
    assert "Table 2" not in text and "thesis" not in text and "bearing" not in text.lower()
    prov = json.loads((tmp_path / "o.json").read_text())["provenance"]
    assert prov["scenario"] == str(path) and len(prov["scenario_sha256"]) == 64


def test_dillard_lab_tdoa_command(tmp_path):
    scenario = _scenario(tmp_path, "dillard-lab-tdoa", [("duration_s = 120.0", "duration_s = 4.0")])
    figs = tmp_path / "lab"
    args = ["reproduce", "dillard-lab-tdoa", "--runs", "2", "--workers", "1", "--scenario", str(scenario)]
    outputs = [
        "--figures",
        str(figs),
        "--json",
        str(tmp_path / "lab.json"),
        "--netcdf",
        str(tmp_path / "l.nc"),
    ]
    result = CliRunner().invoke(app, [*args, *outputs])
    assert result.exit_code == 0, result.output
    assert "Lab TDOA UKF test" in result.output and "Acceptance checks" in result.output
    assert len(list(figs.glob("*.png"))) == 3
    assert json.loads((tmp_path / "lab.json").read_text())["runs"] == 2
    with xr.open_dataset(tmp_path / "l.nc") as ds:
        assert ds["residual"].dims == ("run", "epoch")
