import json
from pathlib import Path

from typer.testing import CliRunner

from oceanloc.cli.app import app, main
from oceanloc.io.gnssa import lajolla_paths

KEYS = {
    "file",
    "n_m",
    "e_m",
    "u_m",
    "sigma_n_m",
    "sigma_e_m",
    "sigma_u_m",
    "sound_speed_mps",
    "pings_used",
    "pings_excluded",
    "residual_rms_m",
    "gradient_e_per_km",
    "gradient_n_per_km",
    "refraction_ppm",
    "sigma_path_m",
    "beta_m",
}


def test_localize_gnssa_json_shape_figures_and_spread(tmp_path: Path):
    paths = [str(p) for p in lajolla_paths()[3:5]]
    out = tmp_path / "r.json"
    res = CliRunner().invoke(
        app, ["localize", "gnssa", *paths, "--json", str(out), "--figures", str(tmp_path / "fig")]
    )
    assert res.exit_code == 0, res.output
    assert "Spread across 2 surveys" in res.output
    data = json.loads(out.read_text())
    assert set(data) == {"surveys", "spread"}
    assert [s["file"] for s in data["surveys"]] == ["gnssa_data_20211210", "gnssa_data_20220321"]
    assert all(set(s) == KEYS for s in data["surveys"])
    assert set(data["spread"]) == {"std_n_m", "std_e_m", "std_u_m"}
    assert data["surveys"][0]["pings_used"] + data["surveys"][0]["pings_excluded"] == 64
    assert (tmp_path / "fig" / "gnssa_data_20211210_residuals.png").stat().st_size > 10_000
    assert (tmp_path / "fig" / "gnssa_spread.png").exists()


def test_sound_speed_override_and_unknown_file_errors(tmp_path: Path, capsys):
    paths = [str(p) for p in lajolla_paths()[3:4]]
    res = CliRunner().invoke(
        app, ["localize", "gnssa", *paths, "--sound-speed", "1500", "--fixed-sound-speed"]
    )
    assert res.exit_code == 0 and "1500.0" in res.output, res.output
    other = tmp_path / "mine.txt"
    other.write_text(Path(paths[0]).read_text())
    code = None
    try:
        main(["localize", "gnssa", str(other)])
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    assert "no published sound speed" in " ".join(capsys.readouterr().err.split())
