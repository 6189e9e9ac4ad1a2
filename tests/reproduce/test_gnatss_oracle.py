"""GNATSS (the community's GNSS-A package) as the oracle, run in its own environment (``make gnatss``).

Synthetic three-transponder surveys with a known truth are written in GNATSS's formats; GNATSS's solver
runs on them as a subprocess and its own output files are read back with oceanloc's readers.

- Same settings (GNATSS's fixed harmonic-mean speeds, weights, common shift and residual limits, two
  runs with ``--remove-outliers`` as its documentation prescribes): oceanloc's positions agree with
  GNATSS's within 1 mm per axis, its residuals, outliers and deletions with GNATSS's files.
- Defaults (each package's own; the array's common shift): with an unmodelled sound-speed drift (3e-4
  of the speed over the survey plus a sinusoid), oceanloc's error of the array centre is at most a
  quarter of GNATSS's (1.6 cm against 30 cm); without the drift both are about 2 cm, and oceanloc's
  error is explained by its sigmas (within 3 sigma per axis).
"""

from __future__ import annotations

import json
import os
import subprocess

import numpy as np
import pytest
import yaml

from oceanloc.estimation.gnatss_compat import GnatssSettings
from oceanloc.field.gnatss_input import load_gnatss_input, localize_gnatss_input
from oceanloc.io.gnatss import (
    read_gnatss_config,
    read_pos_freed_trans_twtt,
    read_pxp_tt,
    read_sound_speed_profile,
    write_gnatss_config,
)
from oceanloc.reproduce.gnatss_oracle import gnatss_python, run_gnatss
from oceanloc.sim.gnatss_survey import ArraySurveySpec, write_gnatss_survey

pytestmark = pytest.mark.skipif(
    gnatss_python() is None,
    reason="gnatss is not installed (`make gnatss` builds .venv-gnatss): oracle tests skip",
)


def _enu_of_gnatss(run, data) -> np.ndarray:
    import pymap3d

    o = data.config.array_center
    x, y, z = run.position_xyz_m.T
    return np.stack(pymap3d.ecef2enu(x, y, z, o.lat_deg, o.lon_deg, o.h_m), axis=-1)


@pytest.fixture(scope="module")
def same(tmp_path_factory: pytest.TempPathFactory):
    folder = tmp_path_factory.mktemp("gnatss_same")
    truth, files = write_gnatss_survey(ArraySurveySpec(n_pings=500, residual_limit_cm=20.0, seed=21), folder)
    first = run_gnatss(files.config, folder / "gnatss-output")
    second = run_gnatss(files.config, folder / "gnatss-output", remove_outliers=True)
    data = load_gnatss_input(files.config)
    ours1 = localize_gnatss_input(data, method="gnatss", settings=GnatssSettings.from_config(data.config, 1))
    ours = localize_gnatss_input(data, method="gnatss")
    return truth, files, data, first, second, ours1, ours


def test_same_settings_positions_agree_within_1_mm(same):
    truth, _, data, _, second, _, ours = same
    diff = ours.positions_enu_m - _enu_of_gnatss(second, data)
    assert np.max(np.abs(diff)) < 1e-3  # 1 mm per axis (they agree to about 1e-8 m)
    assert second.iterations == len(ours.iterations)
    # both land within 1 cm of the truth on this survey
    assert np.max(np.abs(ours.positions_enu_m - truth.transponders_enu_m)) < 0.01
    # the oracle reports its solver's wall and CPU time (the benchmark prints both)
    assert second.solve_s > 0.0 and np.isfinite(second.solve_cpu_s) and second.solve_cpu_s > 0.0


def test_gnatss_residual_and_outlier_files_read_back_and_match(same):
    _, _, _, first, second, ours1, ours = same
    # residuals.csv written by GNATSS: its interrogations and one-way centimetres are ours
    mine = ours.epoch_residuals()
    used = np.isin(mine.t_s, second.residuals.t_s)
    assert used.sum() == second.residuals.t_s.size
    assert np.max(np.abs(mine.residual_cm[used] - second.residuals.residual_cm)) < 1e-3  # cm
    # outliers.csv of the first run = the interrogations our first round flagged
    assert first.outliers is not None and first.outliers.t_s.size >= 1
    assert np.array_equal(np.sort(first.outliers.t_s), np.sort(ours1.extra["outlier_t_s"]))
    # deletions.csv written by GNATSS's second run = the windows we applied
    assert np.array_equal(np.sort(second.deletions[:, 0]), np.sort(ours.deletions[:, 0]))


def test_gnatss_loaders_read_our_files_as_we_do(same):
    _, files, data, *_ = same
    snippet = (
        "import json, sys, warnings; warnings.simplefilter('ignore')\n"
        "from gnatss.loaders import load_travel_times, load_gps_solutions, load_sound_speed\n"
        "tt = load_travel_times([sys.argv[1]], ['a', 'b', 'c'])\n"
        "pos = load_gps_solutions([sys.argv[2]], from_legacy=True)\n"
        "sv = load_sound_speed([sys.argv[3]])\n"
        "print(json.dumps({'t': tt['time'].tolist(), 'a': tt['a'].tolist(), 'pt': pos['time'].tolist(),\n"
        "  'xx': pos['xx'].tolist(), 'x': pos['x'].tolist(), 'depth': sv['depth'].tolist()}))\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    args = [str(files.pxp_tt), str(files.pos_freed_trans_twtt), str(files.sound_speed)]
    out = subprocess.run(
        [str(gnatss_python()), "-c", snippet, *args],
        capture_output=True,
        text=True,
        env=env,
        check=True,
        timeout=300,
    )
    theirs = json.loads(out.stdout.strip().splitlines()[-1])
    tt = read_pxp_tt(files.pxp_tt, 3)
    pos = read_pos_freed_trans_twtt(files.pos_freed_trans_twtt)
    prof = read_sound_speed_profile(files.sound_speed)
    assert np.array_equal(tt.t_transmit_s, theirs["t"])
    assert np.allclose(np.nan_to_num(tt.twtt_s[:, 0]), theirs["a"], atol=1e-12)
    assert np.allclose(pos.t_s, theirs["pt"], atol=1e-6)
    assert np.allclose(pos.cov_m2[:, 0, 0], theirs["xx"], rtol=1e-9)
    assert np.allclose(pos.xyz_m[:, 0], theirs["x"], atol=1e-6)
    assert np.allclose(prof.depth_m, np.abs(theirs["depth"]))
    assert data.config.ids == ("SYN1-1", "SYN1-2", "SYN1-3")


def _defaults_case(tmp_path_factory: pytest.TempPathFactory, drift: float):
    folder = tmp_path_factory.mktemp(f"gnatss_defaults_{drift:g}")
    spec = ArraySurveySpec(
        n_pings=600, array_radius_m=600.0, track_radius_m=(20.0, 700.0), track_period_s=4500.0,
        sound_speed_drift=drift, residual_limit_cm=10000.0, internal_delays_s=(0.2, 2.2, 4.2), seed=5,
    )  # fmt: skip
    truth, files = write_gnatss_survey(spec, folder)
    cfg = yaml.safe_load(files.config.read_text())
    cfg["solver"]["distance_limit"] = 1000.0  # the platform loops out to 700 m: keep its pings
    write_gnatss_config(files.config, cfg)
    assert read_gnatss_config(files.config).distance_limit_m == 1000.0
    gn = run_gnatss(files.config, folder / "gnatss-output")
    data = load_gnatss_input(files.config)
    ours = localize_gnatss_input(data, method="oceanloc", solution="common_shift")
    gn_err = _enu_of_gnatss(gn, data).mean(axis=0) - truth.transponders_enu_m.mean(axis=0)
    our_err = ours.centre_enu_m - truth.transponders_enu_m.mean(axis=0)
    return gn_err, our_err, ours


@pytest.mark.parametrize("drift", [0.0, 3e-4])
def test_defaults_error_against_truth(tmp_path_factory: pytest.TempPathFactory, drift: float):
    gn_err, our_err, ours = _defaults_case(tmp_path_factory, drift)
    sigma = ours.sigma_enu_m[0]
    assert np.all(np.abs(our_err) < 3.0 * sigma)  # oceanloc's sigmas explain its error
    if drift > 0.0:
        # the unmodelled drift biases GNATSS's depth by decimetres; oceanloc estimates the speed
        assert np.linalg.norm(our_err) < 0.25 * np.linalg.norm(gn_err)
        assert abs(gn_err[2]) > 0.1
    else:
        # GNATSS's fixed speed is exactly right here, but its default limits keep the gross travel times
        # (0.4 % of the replies, 3 m of path): both errors are about 2 cm; oceanloc's is no worse than
        # GNATSS's by more than 1 cm (the scatter of one survey's estimate, its sigma being 2-4 cm)
        assert np.linalg.norm(our_err) < np.linalg.norm(gn_err) + 0.01
