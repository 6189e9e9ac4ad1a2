"""GNATSS (the community's GNSS-A package) as the oracle, run in its own environment (``make gnatss``).

Synthetic three-transponder surveys with a known truth are written in GNATSS's formats; GNATSS's solver
runs on them as a subprocess and its own output files are read back with oceanloc's readers.

- Same settings (GNATSS's fixed harmonic-mean speeds, weights, common shift and residual limits, two
  runs with ``--remove-outliers`` as its documentation prescribes): oceanloc's positions agree with
  GNATSS's within 1 mm per axis, its residuals, outliers and deletions with GNATSS's files.
- Defaults (each package's own; the array's common shift), a seeded Monte Carlo (GNATSS runs once for
  all of them): on surveys ray traced through the profile without a drift, oceanloc's mean squared
  centre error is no larger than GNATSS's (4.3 against 22.5 mm RMS) with sigmas that explain it; on
  surveys made with GNATSS's own straight-ray model, not worse within 2 Monte Carlo SE; with an
  unmodelled sound-speed drift at most a quarter of GNATSS's (about 8 mm against 36 cm).
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
from oceanloc.reproduce.gnatss_oracle import gnatss_python, run_gnatss, run_gnatss_many
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


MC_SEEDS = tuple(range(12))  # seeded Monte Carlo (slow): twelve surveys of 300 interrogations per case
MC_PINGS = 300
RAY, DRIFT, STRAIGHT = (0.0, True), (3e-4, True), (0.0, False)  # (sound-speed drift, ray traced)


def _defaults_mc(
    tmp_path_factory: pytest.TempPathFactory, cases: tuple[tuple[float, bool], ...], seeds: tuple[int, ...]
):
    """Array-centre errors (m, ENU) of both packages' defaults over the seeds, per case (drift, ray
    traced), and oceanloc's sigmas. Ray traced: the travel times are ray traced through the profile (a
    stratified ocean: GNATSS's straight ray at the vertical harmonic-mean speed is then off by about
    1.2 cm in depth); otherwise GNATSS's own straight-ray model. GNATSS solves all the surveys in one
    subprocess (its imports are paid once)."""
    runs_in = []
    for drift, ray in cases:
        for seed in seeds:
            folder = tmp_path_factory.mktemp(f"gnatss_mc_{drift:g}_{int(ray)}_{seed}")
            spec = ArraySurveySpec(
                n_pings=MC_PINGS, array_radius_m=600.0, track_radius_m=(20.0, 700.0), track_period_s=4500.0,
                sound_speed_drift=drift, residual_limit_cm=10000.0, internal_delays_s=(0.2, 2.2, 4.2),
                seed=seed, ray_traced=ray,
            )  # fmt: skip
            truth, files = write_gnatss_survey(spec, folder)
            cfg = yaml.safe_load(files.config.read_text())
            cfg["solver"]["distance_limit"] = 1000.0  # the platform loops out to 700 m: keep its pings
            write_gnatss_config(files.config, cfg)
            runs_in.append(((drift, ray), truth, files, folder / "gnatss-output"))
    assert read_gnatss_config(runs_in[0][2].config).distance_limit_m == 1000.0
    runs = run_gnatss_many([c[2].config for c in runs_in], [c[3] for c in runs_in])
    errors: dict[tuple[float, bool], tuple[list, list, list]] = {c: ([], [], []) for c in cases}
    for (case, truth, files, _), gn in zip(runs_in, runs, strict=True):
        data = load_gnatss_input(files.config)
        ours = localize_gnatss_input(data, method="oceanloc", solution="common_shift")
        centre = truth.transponders_enu_m.mean(axis=0)
        errors[case][0].append(ours.centre_enu_m - centre)
        errors[case][1].append(_enu_of_gnatss(gn, data).mean(axis=0) - centre)
        errors[case][2].append(ours.sigma_enu_m[0])
    return {c: tuple(np.asarray(x) for x in v) for c, v in errors.items()}


@pytest.fixture(scope="module")
def defaults_mc(tmp_path_factory: pytest.TempPathFactory):
    return _defaults_mc(tmp_path_factory, (RAY, DRIFT, STRAIGHT), MC_SEEDS)


def _mc_summary(ours: np.ndarray, gnatss: np.ndarray) -> tuple[float, float, float, float]:
    """RMS 3-D centre error of each package (m), and the mean and Monte Carlo standard error (m^2) of
    the per-seed difference of squared errors ``|e_ours|^2 - |e_gnatss|^2`` (paired: same surveys)."""
    a, b = np.sum(ours**2, axis=1), np.sum(gnatss**2, axis=1)
    d = a - b
    return (
        float(np.sqrt(a.mean())),
        float(np.sqrt(b.mean())),
        float(d.mean()),
        float(d.std(ddof=1) / np.sqrt(d.size)),
    )


def _sigmas_explain(ours: np.ndarray, sigma: np.ndarray) -> None:
    """oceanloc's sigmas explain its errors: every axis of every seed within 3 sigma, and the sum of the
    squared normalized errors inside the two-sided 99 % chi-square band on ``3 x seeds`` degrees of
    freedom (too large: optimistic sigmas; too small: inflated ones)."""
    from scipy.stats import chi2

    assert np.all(np.abs(ours) < 3.0 * sigma), np.abs(ours) / sigma
    nees = float(np.sum((ours / sigma) ** 2))
    dof = ours.size
    assert chi2.ppf(0.005, dof) < nees < chi2.ppf(0.995, dof), (nees, dof)


@pytest.mark.slow
def test_defaults_no_drift_no_worse_than_gnatss(defaults_mc):
    """Without a drift (ray-traced surveys): oceanloc's mean squared centre error is no larger than
    GNATSS's (the paired mean difference of squared errors is negative), and its sigmas explain its
    errors. Measured (12 seeds x 300 pings): RMS oceanloc 4.3 mm, GNATSS 22.5 mm, difference -487 mm^2,
    Monte Carlo SE 134 mm^2 (3.6 SE better); oceanloc's mean error 0.5/0.3/0.6 mm (E/N/U), GNATSS's
    vertical -14.3 mm (its straight ray); oceanloc's sum of squared normalized errors 31 on 36 dof. The
    model selection drops the gradient, the knots' variation and the scale on all twelve surveys
    (largest statistic 0.9 of its threshold); the serial-correlation test flags one (seed 1, p 0.008),
    which keeps the GNSS common-mode term. The rule was developed on seeds 100-111; a 1 % chi-square
    test, the first choice, gave 11.6 mm here (seed 5 kept a spurious gradient and was 3.7 cm off), so
    the criterion became BIC, then checked on the held-out seeds 200-211: RMS 3.2 mm against 21.7 mm."""
    ours, gnatss, sigma = defaults_mc[RAY]
    rms_o, rms_g, excess, se = _mc_summary(ours, gnatss)
    assert excess <= 0.0 and rms_o <= rms_g, (rms_o, rms_g, excess, se)
    assert rms_o < 0.01 and rms_g < 0.04
    _sigmas_explain(ours, sigma)


@pytest.mark.slow
def test_defaults_on_gnatss_own_model_not_significantly_worse(defaults_mc):
    """Surveys made with GNATSS's own model (straight ray at each transponder's harmonic-mean speed, an
    approximation of the ray-traced ocean): oceanloc's ray-traced model is then the wrong one, 13 to
    15 mm shallower on average, a depth offset no parameter test can see and its sigmas do not hold.
    Still no worse than GNATSS within 2 Monte Carlo SE. Measured (12 seeds): RMS oceanloc 16.2 mm,
    GNATSS 17.4 mm, difference -39 +- 136 mm^2 (held-out seeds 200-211: 13.5 against 18.4 mm)."""
    ours, gnatss, sigma = defaults_mc[STRAIGHT]
    rms_o, rms_g, excess, se = _mc_summary(ours, gnatss)
    assert excess < 2.0 * se, (rms_o, rms_g, excess, se)
    assert np.all(np.abs(ours[:, :2]) < 3.0 * sigma[:, :2])  # horizontally its sigmas still hold
    assert 0.01 < float(np.mean(ours[:, 2])) < 0.02  # the model difference, vertical


def _check_drift_margin(ours: np.ndarray, gnatss: np.ndarray, sigma: np.ndarray) -> None:
    """An unmodelled drift (3e-4 of the speed over the survey plus a sinusoid) biases GNATSS's fixed-speed
    depth by decimetres; oceanloc estimates the speed. Margin: oceanloc's RMS error at most a quarter of
    GNATSS's, and GNATSS's excess of squared error above 5 Monte Carlo standard errors. Measured (12
    seeds x 300 pings): RMS oceanloc 7.8 mm, GNATSS 361 mm; excess 0.130 m^2, SE 0.0007 m^2; the knots
    are kept on every survey (statistics 8800 to 9700 against a threshold of 34), the gradient on none."""
    rms_o, rms_g, excess, se = _mc_summary(ours, gnatss)
    assert rms_o < 0.25 * rms_g, (rms_o, rms_g)
    assert -excess > 5.0 * se, (excess, se)
    assert np.all(np.abs(gnatss[:, 2]) > 0.1)  # every seed: GNATSS's depth decimetres off
    assert np.all(np.abs(ours) < 3.0 * sigma)


@pytest.mark.slow
def test_defaults_with_drift_better_than_gnatss_by_a_margin(defaults_mc):
    ours, gnatss, sigma = defaults_mc[DRIFT]
    _check_drift_margin(ours, gnatss, sigma)
    _sigmas_explain(ours, sigma)


def test_defaults_with_drift_better_than_gnatss_cheap(tmp_path_factory: pytest.TempPathFactory):
    """The drift margin of the slow Monte Carlo on three of its surveys (one GNATSS process)."""
    _check_drift_margin(*_defaults_mc(tmp_path_factory, (DRIFT,), MC_SEEDS[:3])[DRIFT])
