import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from oceanloc.cli.app import app, main
from oceanloc.io.gnssa import lajolla_paths

_DEC = str(lajolla_paths()[3])  # 2021-12-10: 61 pings, the quickest survey


def test_replay_gnssa_json_and_figures(tmp_path: Path):
    out = tmp_path / "g.json"
    args = ["replay", "gnssa", _DEC, "--runs", "3", "--epochs", "8", "--planners", "recorded,k0,k1,greedy"]
    nc = tmp_path / "g.nc"
    res = CliRunner().invoke(
        app, [*args, "--workers", "1", "--json", str(out), "--figures", str(tmp_path), "--netcdf", str(nc)]
    )
    assert res.exit_code == 0, res.output
    assert "gnssa_data_20211210: 3 runs, seed 2019" in res.output and "Convergence" in res.output
    import xarray as xr

    with xr.open_dataset(nc) as ds:
        assert list(ds["experiment"].values) == ["gnssa_data_20211210"]
        assert ds["rmsee_m"].dims == ("experiment", "planner", "epoch", "transponder")
        assert ds.sizes["run"] == 3 and ds.sizes["epoch"] == 8 and ds.attrs["seed"] == 2019
        assert "gnssa_data_20211210.txt sha256:" in ds.attrs["inputs"]
    rec = json.loads(out.read_text())
    assert rec["runs"] == 3 and rec["planners"] == ["recorded", "k0", "k1", "greedy"]
    survey = rec["surveys"][0]
    assert survey["file"] == "gnssa_data_20211210" and survey["n_records"] == 61
    assert [(r["epoch"], r["planner"]) for r in survey["rows"]][:5] == [
        (3, "recorded"), (3, "k0"), (3, "k1"), (3, "greedy"), (7, "recorded"),
    ]  # fmt: skip
    assert len(survey["rows"]) == 8 and all(r["paper_rmse_m"] is None for r in survey["rows"])
    assert len(survey["planners"]["k1"]["logdet_mean"]) == 8 and len(survey["convergence"]) == 4
    assert survey["convergence"][0]["epochs_to_recorded_logdet"] == 8  # the recorded order itself
    assert survey["settings"]["reach_m"] == pytest.approx(2 * survey["settings"]["speed_mps"])
    for name in ("curves", "tracks"):
        assert (tmp_path / f"gnssa_data_20211210_replay_{name}.png").stat().st_size > 10_000


def test_replay_logs_prints_tables_vii_and_ix_beside_the_paper(tmp_path: Path):
    runner = CliRunner()
    res = runner.invoke(app, ["simulate", "logs", "--out", str(tmp_path), "--duration", "600"])
    assert res.exit_code == 0, res.output
    out = tmp_path / "t.json"
    args = ["replay", "logs", str(tmp_path / "gps.nmea"), str(tmp_path / "ranges.csv"), "--runs", "3"]
    res = runner.invoke(
        app, [*args, "--epochs", "8", "--planners", "k0,k1,greedy", "--workers", "1", "--json", str(out)]
    )
    assert res.exit_code == 0, res.output
    assert "Table VII: one beacon" in res.output and "Table IX: two beacons" in res.output
    rec = json.loads(out.read_text())
    # the journal's beacons, moved from its frame to the earliest fix's: exactly the simulated truth
    truth = {str(b["beacon"]): [b["e_m"], b["n_m"], b["u_m"]] for b in _truth(tmp_path)["beacons"]}
    assert rec["truth_source"] == "journal" and rec["origin"]["source"] == "earliest fix"
    assert rec["truth_enu_m"]["2"] == pytest.approx(truth["2"], abs=1e-6)
    vii, ix = rec["tables"]["VII"], rec["tables"]["IX"]
    assert vii["reference_enu_m"][0] == pytest.approx(truth["1"], abs=1e-6)
    assert len(ix["reference_enu_m"]) == 2
    assert [Path(i["path"]).name for i in rec["provenance"]["inputs"]] == ["gps.nmea", "ranges.csv"]
    row = {(r["epoch"], r["planner"]): r for r in ix["rows"]}
    assert (
        row[(3, "k0")]["paper_logdet_mean"] == -8.36 and row[(3, "k0")]["paper_source"] == "journal Table IX"
    )
    assert (
        row[(7, "greedy")]["paper_rmse_m"] == 6.65
        and row[(7, "greedy")]["paper_source"] == "thesis Table 6.6"
    )
    assert all(r["logdet_z"] is not None for r in vii["rows"]) and vii["convergence"] == []


def _truth(folder: Path) -> dict:
    return json.loads((folder / "truth.json").read_text())


def test_replay_logs_takes_the_truth_file_and_writes_netcdf(tmp_path: Path):
    import xarray as xr

    runner = CliRunner()
    res = runner.invoke(app, ["simulate", "logs", "--out", str(tmp_path), "--duration", "600"])
    assert res.exit_code == 0, res.output
    out, nc = tmp_path / "t.json", tmp_path / "t.nc"
    args = ["replay", "logs", str(tmp_path / "gps.nmea"), str(tmp_path / "ranges.csv"), "--runs", "2"]
    res = runner.invoke(
        app,
        [*args, "--epochs", "5", "--planners", "recorded,k1,random", "--workers", "1", "--json", str(out),
         "--netcdf", str(nc), "--truth", str(tmp_path / "truth.json")],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    rec = json.loads(out.read_text())
    assert rec["truth_source"] == "file truth.json" and rec["planners"] == ["recorded", "k1", "random-disk"]
    assert [Path(i["path"]).name for i in rec["provenance"]["inputs"]][-1] == "truth.json"
    with xr.open_dataset(nc) as ds:
        assert ds.attrs["Conventions"].startswith("CF-")
        assert dict(ds.sizes) == {
            "experiment": 2, "planner": 3, "run": 2, "epoch": 5, "transponder": 2, "axis": 3
        }  # fmt: skip
        assert list(ds["planner_label"].values) == ["recorded order", "k = 1", "random disk"]
        assert ds["error_norm_m"].attrs["units"] == "m" and ds["log_det"].attrs["units"] == "1"
        # Table VII has one beacon: its second transponder is NaN
        assert np.isnan(ds["error_norm_m"].sel(experiment="VII", transponder=2)).all()
        rmsee = np.sqrt((ds["error_norm_m"].sel(experiment="IX") ** 2).mean("run"))
        np.testing.assert_allclose(rmsee, ds["rmsee_m"].sel(experiment="IX"), rtol=1e-9)


def _error(argv, capsys) -> str:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "error:" in err and "Traceback" not in err
    return " ".join(err.split())


def test_bad_input_is_a_one_line_error(tmp_path: Path, capsys):
    empty = tmp_path / "no_pings.txt"
    empty.write_text("# time0_transmit N0 E0 U0 ... TWTT(s)\n# nothing recorded\n")
    assert "no_pings.txt: no valid ping" in _error(
        ["replay", "gnssa", str(empty), "--sound-speed", "1500"], capsys
    )
    msg = _error(["replay", "gnssa", _DEC, "--epochs", "70", "--runs", "2", "--workers", "1"], capsys)
    assert "gnssa_data_20211210: 70 epochs asked for, but only 61 recorded measurements" in msg
    assert "unknown planner 'k9x'" in _error(["replay", "gnssa", _DEC, "--planners", "k1,k9x"], capsys)
    gps = tmp_path / "gps.nmea"
    gps.write_text("")
    assert "gps.nmea" in _error(["replay", "logs", str(gps), str(tmp_path / "ranges.csv")], capsys)
