import json
from pathlib import Path

from typer.testing import CliRunner

from oceanloc.cli.app import app


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
