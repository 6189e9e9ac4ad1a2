import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from oceanloc.cli.app import app, main


def test_simulate_then_localize_logs(tmp_path: Path):
    runner = CliRunner()
    res = runner.invoke(app, ["simulate", "logs", "--out", str(tmp_path), "--duration", "900"])
    assert res.exit_code == 0, res.output
    out = tmp_path / "b.json"
    res = runner.invoke(
        app,
        ["localize", "logs", str(tmp_path / "gps.nmea"), str(tmp_path / "ranges.csv"), "--json", str(out)],
    )
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    assert [b["beacon"] for b in data["beacons"]] == [1, 2]
    assert sum(data["qc"].values()) == 10
    truth = json.loads((tmp_path / "truth.json").read_text())
    # one origin rule: simulate logs' truth and localize logs both use the earliest fix
    assert data["origin"]["source"] == "earliest fix"
    assert data["origin"]["lat_deg"] == truth["origin"]["lat_deg"]
    assert "Beacons, ENU from" in res.output and "(earliest fix)" in res.output
    assert [Path(i["path"]).name for i in data["provenance"]["inputs"]] == ["gps.nmea", "ranges.csv"]
    res = runner.invoke(
        app,
        ["localize", "logs", str(tmp_path / "gps.nmea"), str(tmp_path / "ranges.csv"), "--json", str(out),
         "--truth", str(tmp_path / "truth.json")],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    # 900 s of DGPS errors of 1 m correlated over 60 s: each beacon within 2 m of the truth
    assert all(b["error_m"] < 2.0 for b in data["beacons"]), data["beacons"]
    for b, t in zip(data["beacons"], truth["beacons"], strict=True):
        assert b["truth_enu_m"] == pytest.approx([t["e_m"], t["n_m"], t["u_m"]], abs=1e-6)
    args = ["localize", "logs", str(tmp_path / "gps.nmea"), str(tmp_path / "ranges.csv"), "--json", str(out)]
    res = runner.invoke(app, [*args, "--origin", "32.705,-117.236,-1.478"])
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    assert data["origin"] == {"lat_deg": 32.705, "lon_deg": -117.236, "h_m": -1.478, "source": "given"}


def test_localize_noise_prints_eq30_and_the_total_sigma(tmp_path: Path, capsys):
    runner = CliRunner()
    assert (
        runner.invoke(app, ["simulate", "logs", "--out", str(tmp_path), "--duration", "900"]).exit_code == 0
    )
    out = tmp_path / "noise.json"
    args = ["localize", "noise", str(tmp_path / "gps.nmea"), str(tmp_path / "ranges.csv")]
    res = runner.invoke(app, [*args, "--json", str(out), "--figures", str(tmp_path / "fig")])
    assert res.exit_code == 0, res.output
    assert "Range noise on stationary segments" in res.output and "total range" in res.output
    data = json.loads(out.read_text())
    assert [b["beacon"] for b in data["beacons"]] == [1, 2]
    # the simulated USBL sigmas are 62 and 113 mm; one seeded log is within 25 % (SE ~6 % each)
    assert 0.045 < data["beacons"][0]["sigma_m"] < 0.078 and 0.085 < data["beacons"][1]["sigma_m"] < 0.14
    assert abs(data["sigma_total_m"] - np.hypot(data["sigma_usbl_m"], 1.0)) < 1e-12
    assert (tmp_path / "fig" / "range_noise.png").stat().st_size > 10_000
    with pytest.raises(SystemExit) as exc:
        main([*args, "--min-duration", "5000"])
    assert exc.value.code == 2
    assert "no beacon has 10 or more ranges" in " ".join(capsys.readouterr().err.split())
