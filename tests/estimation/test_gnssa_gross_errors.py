"""GNSS-A under gross travel-time errors on the packaged La Jolla data: the robust pre-screen keeps the
solution within a few centimetres of the clean one, or an error says the survey cannot be solved."""

import dataclasses
import time

import numpy as np
import pytest

from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.gnssa import GnssaOptions, localize_gnssa, robust_first_fit
from oceanloc.io.gnssa import GnssaSurvey, lajolla_paths, published_sound_speed_mps, read_gnssa

FIRST = lajolla_paths()[0]  # 2021-07-23, 555 pings
SMALL = next(p for p in lajolla_paths() if "20211210" in p.name)  # 66 pings, one real gross error


def _with_twtt(survey: GnssaSurvey, twtt: np.ndarray) -> GnssaSurvey:
    return dataclasses.replace(
        survey, twtt_s=twtt, t_receive_s=survey.t_transmit_s + twtt + survey.turnaround_s
    )


def _corrupt(survey: GnssaSurvey, fraction: float, kind: str, seed: int) -> tuple[GnssaSurvey, np.ndarray]:
    """``fraction`` of the pings at an absurd travel time (``absurd``: 1 ms to 50 s; ``late``: 10 to
    500 ms late, 15 to 750 m of path; ``short``: 1 to 50 ms, shorter than any real path)."""
    rng = np.random.default_rng(seed)
    idx = rng.choice(survey.n_pings, round(fraction * survey.n_pings), replace=False)
    twtt = survey.twtt_s.copy()
    if kind == "absurd":
        twtt[idx] = rng.uniform(0.001, 50.0, idx.size)
    elif kind == "late":
        twtt[idx] += rng.uniform(0.01, 0.5, idx.size)
    else:
        twtt[idx] = rng.uniform(0.001, 0.05, idx.size)
    return _with_twtt(survey, twtt), idx


@pytest.fixture(scope="module")
def clean():
    survey = read_gnssa(FIRST)
    options = GnssaOptions(sound_speed_mps=published_sound_speed_mps(FIRST))
    return survey, options, localize_gnssa(survey, options)


@pytest.mark.parametrize(
    ("fraction", "kind", "seed"),
    [(0.25, "absurd", 0), (0.25, "late", 1), (0.1, "short", 2), (0.35, "absurd", 3)],
)
def test_gross_errors_are_excluded_and_the_position_stays_within_centimetres(clean, fraction, kind, seed):
    survey, options, reference = clean
    bad, idx = _corrupt(survey, fraction, kind, seed)
    t0 = time.perf_counter()
    r = localize_gnssa(bad, options)
    elapsed = time.perf_counter() - t0
    # Before the pre-screen, 25 % absurd pings put the transponder 510 m away (exit 0), in 57 s.
    assert np.linalg.norm(r.position_enu_m - reference.position_enu_m) < 0.03
    assert not r.used[idx].any()
    screened = [e for e in r.exclusions if e.reason.startswith("gross error (pre-screen)")]
    assert {e.index for e in screened} == set(idx.tolist())
    assert r.converged and elapsed < 20.0


def test_clean_survey_is_unchanged_by_the_pre_screen(clean):
    survey, options, reference = clean
    off = localize_gnssa(survey, dataclasses.replace(options, prescreen=False))
    np.testing.assert_array_equal(off.position_enu_m, reference.position_enu_m)
    assert not any("pre-screen" in e.reason for e in reference.exclusions)


def test_too_many_gross_errors_is_a_data_error_naming_the_fraction(clean):
    survey, options, _ = clean
    bad, _ = _corrupt(survey, 0.45, "absurd", 4)
    with pytest.raises(DataError, match=r"250 of 555 pings \(45 %\) have travel times no single transponder"):
        localize_gnssa(bad, options)


def test_without_the_pre_screen_leftover_gross_errors_are_an_error_not_a_wrong_answer():
    """The one-at-a-time rule alone stops at max_outlier_fraction with gross pings still used: that is now
    a DataError, not a position tens of metres off with exit 0."""
    survey = read_gnssa(SMALL)
    bad, _ = _corrupt(survey, 0.3, "absurd", 5)
    options = GnssaOptions(sound_speed_mps=published_sound_speed_mps(SMALL), prescreen=False)
    with pytest.raises(DataError, match=r"used pings still have \|residual\| > 5 m .line \d+: [+-]\d"):
        localize_gnssa(bad, options)
    screened = localize_gnssa(bad, dataclasses.replace(options, prescreen=True))
    reference = localize_gnssa(survey, dataclasses.replace(options, prescreen=True))
    assert np.linalg.norm(screened.position_enu_m - reference.position_enu_m) < 0.05


def test_robust_first_fit_ignores_a_third_of_absurd_pings(clean):
    survey, options, reference = clean
    bad, idx = _corrupt(survey, 1 / 3, "absurd", 6)
    surface = float(survey.transmit_enu_m[:, 2].min())
    fit = robust_first_fit(
        bad.transmit_enu_m, bad.receive_enu_m, bad.twtt_s, options.sound_speed_mps, surface
    )
    # Position only, one sound speed: within a metre of the full solution, and a clean-ping scale of cm.
    assert np.linalg.norm(fit.position_enu_m - reference.position_enu_m) < 1.0
    assert fit.sigma_m < 0.5
    assert np.all(np.abs(fit.residual_m[idx] - np.median(fit.residual_m)) > 5.0)


def test_pre_screen_options_are_validated():
    with pytest.raises(ConfigError, match="max_gross_fraction must be in"):
        GnssaOptions(sound_speed_mps=1500.0, max_gross_fraction=0.5)
    with pytest.raises(ConfigError, match="gross_error_m must be a positive number"):
        GnssaOptions(sound_speed_mps=1500.0, gross_error_m=float("nan"))
    with pytest.raises(ConfigError, match="prescreen_sigmas must exceed 1"):
        GnssaOptions(sound_speed_mps=1500.0, prescreen_sigmas=0.5)
