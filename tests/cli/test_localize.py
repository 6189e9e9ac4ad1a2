import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from oceanloc.cli.app import app, main
from oceanloc.io.gnssa import lajolla_paths

KEYS = {
    "file",
    "epoch_utc",
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
    "lat_deg",
    "lon_deg",
    "h_m",
    "converged",
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
    assert set(data) == {"provenance", "surveys", "site_velocity", "spread", "pings"}
    pings = data["pings"]
    assert list(pings) == ["t_s", "transponder", "residual_m", "excluded", "reason"]
    n = sum(s["pings_used"] + s["pings_excluded"] for s in data["surveys"])
    assert len(pings["t_s"]) == len(pings["reason"]) == n
    assert sum(pings["excluded"]) == sum(s["pings_excluded"] for s in data["surveys"])
    assert all(bool(r) == x for r, x in zip(pings["reason"], pings["excluded"], strict=True))
    assert [Path(i["path"]).name for i in data["provenance"]["inputs"]] == [Path(p).name for p in paths]
    assert data["site_velocity"]["plate"] == "PCFC" and "Lat0 32.8668" in data["site_velocity"]["reason"]
    assert [s["file"] for s in data["surveys"]] == ["gnssa_data_20211210", "gnssa_data_20220321"]
    assert all(set(s) == KEYS for s in data["surveys"])
    assert {"std_n_m", "std_e_m", "std_u_m", "chi2_n", "sigmas_explain_n", "at_survey_epochs"} <= set(
        data["spread"]
    )
    # the La Jolla files get the Pacific plate's velocity by default; two surveys fit no velocity
    assert data["spread"]["site_velocity"]["source"] == "ITRF2014 PCFC"
    assert data["spread"]["site_velocity"]["e_mm_yr"] == pytest.approx(-44.0, abs=0.1)
    assert "fitted_velocity" not in data["spread"]
    assert data["surveys"][1]["epoch_utc"].startswith("2022-03-21T")
    assert data["surveys"][0]["pings_used"] + data["surveys"][0]["pings_excluded"] == 64
    assert (tmp_path / "fig" / "gnssa_data_20211210_residuals.png").stat().st_size > 10_000
    assert (tmp_path / "fig" / "gnssa_spread.png").exists()


def test_site_velocity_option(tmp_path: Path, capsys):
    paths = [str(p) for p in lajolla_paths()[3:5]]
    out = tmp_path / "r.json"
    res = CliRunner().invoke(
        app, ["localize", "gnssa", *paths, "--site-velocity", "-40,20", "--json", str(out)]
    )
    assert res.exit_code == 0, res.output
    spread = json.loads(out.read_text())["spread"]
    assert spread["site_velocity"] == {"source": "given", "e_mm_yr": -40.0, "n_mm_yr": 20.0, "u_mm_yr": 0.0}
    # 2021-12-10 to 2022-03-21 is 0.28 yr: the north difference shrinks by 20 mm/yr x 0.28 yr = 5.6 mm
    d_raw = spread["at_survey_epochs"]["std_n_m"] * np.sqrt(2)
    assert d_raw - spread["std_n_m"] * np.sqrt(2) == pytest.approx(0.0056, abs=2e-4)
    args = ["localize", "gnssa", *paths, "--site-velocity", "none", "--json", str(out)]
    assert CliRunner().invoke(app, args).exit_code == 0
    assert json.loads(out.read_text())["spread"]["site_velocity"] is None
    for value, message in (("1,x", "'VE,VN[,VU]' in mm/yr"), ("EURX", "'EURX' is none of auto, none")):
        with pytest.raises(SystemExit) as exc:
            main(["localize", "gnssa", paths[0], "--site-velocity", value])
        assert exc.value.code == 2
        err = " ".join(capsys.readouterr().err.split())
        assert message in err and "Traceback" not in err


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


def _moved_header(src: Path, dst: Path, lat: float, lon: float) -> Path:
    """A copy of a La Jolla survey (same file name) whose header puts the site at ``lat, lon``."""
    text = src.read_text().replace("Lat0=32.8668445", f"Lat0={lat}")
    text = text.replace("Lon0=-117.2701205", f"Lon0={lon}")
    dst.mkdir(parents=True, exist_ok=True)
    (dst / src.name).write_text(text)
    return dst / src.name


def test_auto_site_velocity_comes_from_the_header_location_not_the_file_name(tmp_path: Path):
    # Same file names as the packaged La Jolla surveys (which sit on the Pacific plate), but headers in
    # the western North Atlantic (35 N, 70 W): the North American plate's velocity there, about
    # E -13, N +7 mm/yr (ITRF2014 NOAM pole), not the Pacific's -44, +26 mm/yr.
    paths = [str(_moved_header(p, tmp_path / "atl", 35.0, -70.0)) for p in lajolla_paths()[3:5]]
    out = tmp_path / "r.json"
    res = CliRunner().invoke(app, ["localize", "gnssa", *paths, "--json", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    assert data["site_velocity"]["plate"] == "NOAM"
    e, n, _ = data["site_velocity"]["velocity_enu_mm_yr"]
    assert e == pytest.approx(-13.2, abs=0.2) and n == pytest.approx(6.6, abs=0.2)
    assert "is on NOAM" in " ".join(res.output.split())
    # in the mid-Atlantic east of the ridge (35 N, 20 W) no plate of the model applies: as surveyed
    paths = [str(_moved_header(p, tmp_path / "mid", 35.0, -20.0)) for p in lajolla_paths()[3:5]]
    res = CliRunner().invoke(app, ["localize", "gnssa", *paths, "--json", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    assert data["site_velocity"]["source"] is None and data["spread"]["site_velocity"] is None
    assert "compared as surveyed" in data["site_velocity"]["reason"]
