"""`oceanloc dop map` and `oceanloc dop place`."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
from typer.testing import CliRunner

from oceanloc.cli.app import app, main


def test_dop_map_writes_png_netcdf_and_json(tmp_path):
    png, nc, js = tmp_path / "map.png", tmp_path / "map.nc", tmp_path / "map.json"
    args = ["dop", "map", "--kind", "bearing", "--node", "100,0", "--node", "0,100", "--resolution", "20"]
    result = CliRunner().invoke(app, [*args, "--png", str(png), "--netcdf", str(nc), "--json", str(js)])
    assert result.exit_code == 0, result.output
    assert "minimum HDOP (m/rad)" in result.output
    assert png.stat().st_size > 1000
    with xr.open_dataset(nc) as ds:
        assert ds["hdop"].shape == (31, 31) and ds["hdop"].attrs["units"] == "m rad-1"
        assert ds.attrs["measurement"] == "bearing" and ds.attrs["Conventions"].startswith("CF")
    record = json.loads(js.read_text())
    assert record["grid_x_m"] == [-300.0, 300.0, 31] and record["fixed_nodes_m"] == [
        [100.0, 0.0],
        [0.0, 100.0],
    ]


def test_dop_place_json_bearings_clockwise_from_north(tmp_path):
    out = tmp_path / "p.json"
    result = CliRunner().invoke(
        app,
        [
            "dop",
            "place",
            "--kind",
            "range",
            "--nodes",
            "4",
            "--starts",
            "3",
            "--target",
            "10,20",
            "--json",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    payload = json.loads(out.read_text())
    assert payload["hdop"] == pytest.approx(1.0, rel=1e-6)  # four ranges at right angles, sigma = 1
    nodes = np.array(payload["nodes_m"])
    assert nodes.shape == (4, 2)
    d = nodes - [10.0, 20.0]
    # Clockwise from north: east of the target is 90 deg, north 0 deg.
    np.testing.assert_allclose(
        np.radians(payload["node_bearing_deg"]), np.arctan2(d[:, 0], d[:, 1]) % (2 * np.pi)
    )
    assert "cw from N" in result.output and "0.00 % worse" in " ".join(result.output.split())


def test_dop_place_lists_the_fixed_node():
    args = ["dop", "place", "--nodes", "2", "--fixed-node", "0,100", "--starts", "2"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    row = next(line for line in result.output.splitlines() if "fixed 1" in line)
    assert "100.00" in row and row.split("│")[-2].strip() == "0.0"  # due north of the target


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["dop", "map", "--kind", "doppler"], "--kind must list names from bearing, range, tdoa"),
        (["dop", "map", "--node", "1;2"], "--node: expected E,N"),
        (["dop", "map", "--sigma", "0"], "sigma must be positive"),
        (["dop", "place", "--min-standoff", "10", "--max-standoff", "5"], "stand-off"),
    ],
)
def test_user_errors_are_one_line(capsys, args, message):
    with pytest.raises(SystemExit) as info:
        main(args)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_bad_kind_through_the_installed_command():
    proc = subprocess.run(
        [sys.executable, "-m", "oceanloc", "dop", "place", "--kind", "sonar"],
        capture_output=True,
        text=True,
        env=os.environ,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "--kind must list names from bearing, range, tdoa" in proc.stderr
