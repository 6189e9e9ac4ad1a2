"""Time delay by cross-correlation and GCC-PHAT (thesis Figs. 16-17)."""

import numpy as np
import pytest
import scipy.fft
import scipy.signal

from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.time_delay import estimate_delay

FS = 16000.0


def _sweep(duration_s=0.5, f0=200.0, f1=6000.0):
    t = np.arange(int(duration_s * FS)) / FS
    return scipy.signal.chirp(t, f0, t[-1], f1) * np.hanning(t.size)


def _delayed(sig, delay_samples, n):
    # Exact fractional delay of a band-limited signal: a linear phase in the frequency domain.
    n_fft = scipy.fft.next_fast_len(n)
    f = np.fft.rfftfreq(n_fft)
    return np.fft.irfft(np.fft.rfft(sig, n_fft) * np.exp(-2j * np.pi * f * delay_samples), n_fft)[:n]


def _pair(delay_samples, snr_db, rng, start=4000.0):
    sweep = _sweep()
    n = 3 * sweep.size
    b = _delayed(sweep, start, n)
    a = _delayed(sweep, start + delay_samples, n)
    noise_sd = np.sqrt(np.mean(sweep**2) / 10 ** (snr_db / 10))
    return a + noise_sd * rng.standard_normal(n), b + noise_sd * rng.standard_normal(n)


@pytest.mark.parametrize("method", ["xcorr", "gcc-phat"])
def test_up_sweep_delay_within_a_tenth_of_a_sample_at_10_db(method):
    rng = np.random.default_rng(0)
    for delay in rng.uniform(-300, 300, 6):
        a, b = _pair(delay, 10.0, rng)
        est = estimate_delay(a, b, FS, method=method)
        assert abs(est.delay_samples - delay) < 0.1, (method, delay, est.delay_samples)
        assert est.delay_s == pytest.approx(est.delay_samples / FS)
        assert est.first == ("B" if delay > 0 else "A")
        assert est.peak_ratio > 2


def test_sign_convention_a_lags_b():
    rng = np.random.default_rng(1)
    a, b = _pair(120.0, 30.0, rng)  # a is b delayed: A heard the sweep 120 samples after B
    est = estimate_delay(a, b, FS, method="xcorr")
    assert est.delay_samples == pytest.approx(120.0, abs=0.05)
    assert est.first == "B"
    swapped = estimate_delay(b, a, FS, method="xcorr")
    assert swapped.delay_samples == pytest.approx(-120.0, abs=0.05) and swapped.first == "A"


def test_sinc_refinement_beats_parabola_on_fractional_delays():
    rng = np.random.default_rng(2)
    errs = {"sinc": [], "parabolic": []}
    for delay in np.arange(10.05, 11.0, 0.1):
        a, b = _pair(delay, 40.0, rng)
        for interp in errs:
            errs[interp].append(
                abs(estimate_delay(a, b, FS, method="gcc-phat", interpolation=interp).delay_samples - delay)
            )
    assert max(errs["sinc"]) < 0.02
    assert max(errs["sinc"]) < max(errs["parabolic"])


def test_max_delay_window_and_band():
    rng = np.random.default_rng(3)
    a, b = _pair(-50.0, 10.0, rng)
    est = estimate_delay(a, b, FS, max_delay_s=100 / FS, band_hz=(200.0, 6000.0))
    assert est.delay_samples == pytest.approx(-50.0, abs=0.1)
    assert np.all(np.abs(est.lags_s) <= 100 / FS + 1e-12)
    assert np.max(np.abs(est.correlation)) == pytest.approx(1.0)


def test_periodic_signal_has_low_peak_ratio():
    t = np.arange(8000) / FS
    tone = np.sin(2 * np.pi * 500 * t)
    est = estimate_delay(np.roll(tone, 7), tone, FS, method="xcorr")
    assert est.peak_ratio < 1.2  # every period of a tone correlates equally: ambiguous


def test_bad_inputs():
    with pytest.raises(DataError, match="silent"):
        estimate_delay(np.zeros(100), np.ones(100), FS)
    with pytest.raises(DataError, match="non-finite"):
        estimate_delay(np.array([1.0, np.nan, 2.0]), np.ones(3), FS)
    with pytest.raises(ConfigError, match="method"):
        estimate_delay(np.ones(10), np.ones(10), FS, method="music")
    with pytest.raises(ConfigError, match="max delay"):
        estimate_delay(np.ones(100), np.ones(100), FS, max_delay_s=1e-9)


def _wideband_case(seed):
    """A 0.4 s Hann-tapered 0.5-6 kHz sweep at 48 kHz in white noise at 10 dB SNR, A 1.2345 ms after B."""
    from oceanloc.sim.flock import sweep_recordings

    fs = 48000
    a, b = sweep_recordings(
        sample_rate_hz=fs,
        band_hz=(500.0, 6000.0),
        sweep_s=0.4,
        onset_s=0.05,
        echo_gain=0.0,
        snr_db=10.0,
        seed=seed,
    )
    return a, b, fs, 1.2345e-3 * fs


def test_default_picks_the_signal_band_and_reaches_the_cramer_rao_bound():
    # Over the whole band (77 % of it noise only at 48 kHz) PHAT wanders by tenths of a sample; the
    # default (ML weighting over the detected band) stays within 0.02 samples in every one of 8 draws:
    # 3 x its Cramer-Rao sd (0.0067 samples here), so a draw beyond it has probability 0.27 %.
    err_phat, err_default, sds = [], [], []
    for seed in range(8):
        a, b, fs, true = _wideband_case(seed)
        err_phat.append(estimate_delay(a, b, fs, method="gcc-phat", band_hz=None).delay_samples - true)
        est = estimate_delay(a, b, fs, max_delay_s=0.01)
        err_default.append(est.delay_samples - true)
        sds.append(est.delay_sd_samples)
        assert est.method == "gcc-ml" and 500 < est.band_hz[0] < 1500 and 5000 < est.band_hz[1] < 6000
    assert np.sqrt(np.mean(np.square(err_phat))) > 0.1
    assert np.max(np.abs(err_default)) < 0.02
    sd = float(np.mean(sds))
    assert 0.005 < sd < 0.008 and np.max(np.abs(err_default)) < 3 * sd
    # The bound is honest: the rms error over 8 draws is within the chi-square(8) 99 % range of the sd,
    # sqrt(1.34 / 8) .. sqrt(21.96 / 8) = 0.41 .. 1.66 times it.
    assert 0.41 * sd < np.sqrt(np.mean(np.square(err_default))) < 1.66 * sd
    rec = est.to_record()
    assert (
        rec["delay_sd_samples"] == pytest.approx(est.delay_sd_samples)
        and "Cramer-Rao" in rec["delay_sd_method"]
    )


def test_phat_over_the_detected_band_is_within_two_hundredths():
    errs = []
    for seed in range(8):
        a, b, fs, true = _wideband_case(seed)
        errs.append(estimate_delay(a, b, fs, method="gcc-phat").delay_samples - true)
    # PHAT whitens within the band (no SNR weighting): about twice the bound, rms 0.014 samples.
    assert np.sqrt(np.mean(np.square(errs))) < 0.02


def test_recording_too_short_for_the_delay_search_is_reported():
    rng = np.random.default_rng(0)
    expected = r"too short for a delay search of \+-0.1 s: each must last at least 0.2 s"
    with pytest.raises(DataError, match=expected):
        estimate_delay(rng.standard_normal(800), rng.standard_normal(800), FS, max_delay_s=0.1)
    with pytest.raises(ConfigError, match="band must be 'auto'"):
        estimate_delay(rng.standard_normal(800), rng.standard_normal(800), FS, band_hz="whole")
