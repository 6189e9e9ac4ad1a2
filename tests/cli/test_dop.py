"""`oceanloc dop map` and `oceanloc dop place`."""

import json

import numpy as np
import pytest
import xarray as xr
from typer.testing import CliRunner

from oceanloc.cli.app import app, main


def test_dop_map_writes_png_and_netcdf(tmp_path):
    png, nc = tmp_path / "map.png", tmp_path / "map.nc"
    args = ["dop", "map", "--kind", "bearing", "--node", "100,0", "--node", "0,100", "--resolution", "20"]
    result = CliRunner().invoke(app, [*args, "--png", str(png), "--netcdf", str(nc)])
    assert result.exit_code == 0, result.output
    assert "minimum HDOP" in result.output
    assert png.stat().st_size > 1000
    with xr.open_dataset(nc) as ds:
        assert ds["hdop"].shape == (31, 31)
        assert ds.attrs["measurement"] == "bearing"


def test_dop_place_json(tmp_path):
    out = tmp_path / "p.json"
    result = CliRunner().invoke(
        app, ["dop", "place", "--kind", "range", "--nodes", "4", "--starts", "3", "--json", str(out)]
    )
    assert result.exit_code == 0, result.output
    payload = json.loads(out.read_text())
    assert payload["hdop"] == pytest.approx(1.0, rel=1e-6)  # four ranges at right angles, sigma = 1
    assert np.array(payload["nodes_m"]).shape == (4, 2)
    assert "0.00 % worse" in result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["dop", "map", "--kind", "doppler"], "--kind must be one of"),
        (["dop", "map", "--node", "1;2"], "--node: expected x,y"),
        (["dop", "place", "--min-standoff", "10", "--max-standoff", "5"], "stand-off"),
    ],
)
def test_user_errors_are_one_line(capsys, args, message):
    with pytest.raises(SystemExit) as info:
        main(args)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
