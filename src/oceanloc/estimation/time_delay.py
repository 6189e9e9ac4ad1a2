"""Time delay between two recordings of one signal: cross-correlation and GCC-PHAT with sub-sample peaks.

The AquaQuad thesis (Chapter II.E.3, Figures 16-17) obtains a TDOA by cross-correlating the recordings of
two hydrophones of an up-sweep; the lag of the correlation peak is the time difference, its sign telling
which sensor heard the signal first.

Sign convention (the same as the TDOA model, eq. II.7, with ``i = A`` and ``j = B``)::

    delay_s = (arrival time at A) - (arrival time at B)

so ``delay_s > 0`` means the signal reached **B first** (A lags B): ``a(t) ~ b(t - delay)``.

Methods:

- ``xcorr``: plain cross-correlation ``c(tau) = sum_t a(t + tau) b(t)`` (matched filtering of one recording by
  the other), best in white noise for a known broadband signal;
- ``gcc-phat``: generalized cross-correlation with the phase transform (Knapp and Carter 1976), the
  cross-spectrum divided by its magnitude; a sharper peak, robust to reverberation and to coloured
  signals;
- ``gcc-ml``: the maximum-likelihood weighting of Hannan and Thomson (Knapp and Carter 1976, eq. 19), PHAT
  times ``|gamma|^2 / (1 - |gamma|^2) = SNR^2 / (1 + 2 SNR)`` with the SNR measured per bin (below); it
  reaches the Cramer-Rao bound when the SNR estimate is right.

Signal band (``band_hz="auto"``, the default): GCC-PHAT gives every frequency the same weight, so over the
whole band it whitens the noise outside the signal's band up to the signal's level (at 48 kHz a
0.5-6 kHz sweep leaves 77 % of the band noise only, and the PHAT peak wanders by tenths of a sample while
plain cross-correlation stays within hundredths). The band is therefore found from the recordings: the
geometric mean ``|A(f)| |B(f)|`` of the two spectra, averaged over ``M`` neighbouring bins, is compared with
its noise floor (a low percentile over all bins); bins more than a few standard errors of the average
above the floor hold signal. Both methods then use only those bins (PHAT whitens within the band only). If
no bin stands out (a signal covering the whole band, or noise only), the whole band is used.

Precision: ``delay_sd_s`` is the Cramer-Rao bound of the delay for two channels with equal, independent
noise (Knapp and Carter 1976, eq. 29; Carter 1987, "Coherence and time delay estimation")::

    var(tau) >= [ 2 T  integral (2 pi f)^2  SNR(f)^2 / (1 + 2 SNR(f))  df ]^-1

with ``T`` the recording length and ``SNR(f) = S(f) / N(f)`` measured from the recordings (``N`` the
noise floor, ``S`` the smoothed power above it, in the detected band). It assumes a single clean arrival: it
is the bound, not a guarantee (an echo or a wrong peak is not in it).

Both are computed through the FFT (zero-padded, no circular wrap). The integer-lag peak is refined to a
fraction of a sample by maximizing the band-limited (Fourier) interpolation of the correlation between the
neighbouring samples, which is exact for band-limited signals (a parabola through three samples is
biased for narrow peaks); ``interpolation="parabolic"`` is available for comparison.

Confidence: ``peak_ratio`` is the correlation envelope's peak over its largest value outside the main lobe
(the region around the peak above half its height) within the search window; near 1 the delay is
ambiguous (a periodic signal, noise only, strong multipath), large values mean one clear arrival.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, TypeAlias

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.io.wav import common_sample_rate, read_wav

DelayMethod: TypeAlias = Literal["xcorr", "gcc-phat", "gcc-ml"]
DELAY_METHODS: tuple[str, ...] = ("xcorr", "gcc-phat", "gcc-ml")
Interpolation: TypeAlias = Literal["sinc", "parabolic", "none"]


@dataclass(frozen=True, slots=True, kw_only=True)
class DelayEstimate:
    """Time delay between recordings A and B.

    Attributes
    ----------
    delay_s : float
        Arrival at A minus arrival at B, seconds (> 0: B heard the signal first).
    delay_samples : float
        The same in samples (fractional).
    method : str
        ``xcorr`` or ``gcc-phat``.
    first : str
        ``"A"`` or ``"B"``: which recording heard the signal first (``"A"`` also for a zero delay).
    peak_ratio : float
        Envelope peak of the correlation over its largest value outside the main lobe (1: ambiguous).
    sample_rate_hz : float
    lags_s : (L,) float
        Lags of the correlation returned for plotting, seconds.
    correlation : (L,) float
        The correlation at those lags, normalized to a peak of 1 in magnitude.
    delay_sd_s : float
        Cramer-Rao bound of the delay's standard deviation from the measured SNR and band (module
        docstring), seconds; ``inf`` when no signal stands above the noise floor.
    band_hz : (float, float)
        The lowest and highest frequency used (the detected band for ``band_hz="auto"``).
    """

    delay_s: float
    delay_samples: float
    method: str
    first: str
    peak_ratio: float
    sample_rate_hz: float
    lags_s: FloatArray
    correlation: FloatArray
    delay_sd_s: float = float("nan")
    band_hz: tuple[float, float] = (0.0, 0.0)

    @property
    def delay_sd_samples(self) -> float:
        return self.delay_sd_s * self.sample_rate_hz

    def to_record(self) -> dict[str, Any]:
        """The delay and its confidence (the correlation curve is left to the figure)."""
        return {
            "delay_s": float(self.delay_s),
            "delay_samples": float(self.delay_samples),
            "delay_sd_s": _finite_or_none(self.delay_sd_s),
            "delay_sd_samples": _finite_or_none(self.delay_sd_samples),
            "delay_sd_method": "Cramer-Rao bound from the measured SNR and band (Knapp and Carter 1976)",
            "band_hz": [float(self.band_hz[0]), float(self.band_hz[1])],
            "method": self.method,
            "first": self.first,
            "peak_ratio": float(self.peak_ratio),
            "sample_rate_hz": float(self.sample_rate_hz),
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class RecordingDelay:
    """The delay between two WAV recordings and what was read.

    Attributes
    ----------
    estimate : DelayEstimate
    sources : (str, str)
        The files A and B.
    formats : (str, str)
        Their stored sample formats.
    channel : int
        The channel correlated.
    """

    estimate: DelayEstimate
    sources: tuple[str, str]
    formats: tuple[str, str]
    channel: int

    @property
    def first_source(self) -> str:
        """The file that heard the signal first."""
        return self.sources[0] if self.estimate.first == "A" else self.sources[1]

    def to_record(self) -> dict[str, Any]:
        return {
            **self.estimate.to_record(),
            "recording_a": self.sources[0],
            "recording_b": self.sources[1],
            "formats": list(self.formats),
            "channel": self.channel,
        }


BandSpec: TypeAlias = tuple[float, float] | Literal["auto"] | None

MIN_RECORDING_SAMPLES = 64
"""Shortest recording a delay is estimated from: the band detection smooths over 8 bins and takes the
noise floor as a percentile over all bins, which needs a few dozen bins at least."""
_FLOOR_PERCENTILE = 10.0
"""Noise floor of the smoothed spectrum: this percentile over all bins (a signal may fill up to ~85 %)."""
_BAND_SIGMAS = 5.0
"""A bin holds signal when its smoothed power exceeds the floor by this many standard errors."""


def _finite_or_none(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


@dataclass(frozen=True, slots=True)
class _Band:
    mask: np.ndarray  # (bins,) bool: bins used
    snr: FloatArray  # (bins,) measured S/N per bin (0 outside the signal)
    detected: bool


def _detect_band(spec_a: np.ndarray, spec_b: np.ndarray, n_fft: int) -> _Band:
    """Bins whose smoothed ``|A||B|`` stands above the noise floor (module docstring), and their SNR."""
    power = np.abs(spec_a) * np.abs(spec_b)
    bins = power.size
    width = int(max(8, min(256, bins // 64)))
    smooth = np.convolve(power, np.ones(width) / width, mode="same")
    floor = float(np.percentile(smooth, _FLOOR_PERCENTILE))
    # |A||B| of noise has a relative sd of ~0.8; zero padding correlates neighbouring bins (n_fft / n).
    rel_se = 0.8 / np.sqrt(max(width * bins / n_fft * 0.5, 1.0))
    above = smooth > floor * (1.0 + _BAND_SIGMAS * rel_se)
    if floor <= 0 or above.sum() < 3 or above.mean() > 0.9:
        return _Band(mask=np.ones(bins, dtype=bool), snr=np.zeros(bins), detected=False)
    # The floor percentile sits below the mean noise level: rescale it (mean / 10th pct of the smoothed
    # noise, for its relative standard error).
    noise = floor * (1.0 + 1.2816 * rel_se)
    snr = np.where(above, np.maximum(smooth - noise, 0.0) / noise, 0.0)
    return _Band(mask=above, snr=snr, detected=True)


def _delay_crlb_s(snr: FloatArray, freqs_hz: FloatArray, n_samples: int, n_fft: int) -> float:
    """Knapp-Carter bound: ``[2 T int (2 pi f)^2 SNR^2 / (1 + 2 SNR) df]^-1/2`` on the rfft grid, s."""
    # T df = (n / fs) (fs / n_fft) per zero-padded bin.
    info = 2.0 * np.sum((2 * np.pi * freqs_hz) ** 2 * snr**2 / (1.0 + 2.0 * snr)) * n_samples / n_fft
    return float(1.0 / np.sqrt(info)) if info > 0 else float("inf")


def _cross_spectrum(
    a: FloatArray, b: FloatArray, method: str, sample_rate_hz: float, band_hz: BandSpec
) -> tuple[np.ndarray, int, float, tuple[float, float]]:
    """Weighted cross-spectrum, FFT length, the delay's Cramer-Rao sd (s) and the band used (Hz)."""
    import scipy.fft

    n_fft = scipy.fft.next_fast_len(a.size + b.size - 1, real=True)
    fa, fb = scipy.fft.rfft(a, n_fft), scipy.fft.rfft(b, n_fft)
    spec = fa * np.conj(fb)
    freqs = scipy.fft.rfftfreq(n_fft, 1.0 / sample_rate_hz)
    band = _detect_band(fa, fb, n_fft)
    if band_hz == "auto":
        mask = band.mask
    elif band_hz is not None:
        mask = (freqs >= band_hz[0]) & (freqs <= band_hz[1])
    else:
        mask = np.ones(freqs.size, dtype=bool)
    if method in ("gcc-phat", "gcc-ml"):
        mag = np.abs(spec)
        spec = spec / np.maximum(mag, 1e-12 * mag.max())
    if method == "gcc-ml":  # Hannan-Thomson: PHAT times |gamma|^2 / (1 - |gamma|^2) = SNR^2 / (1 + 2 SNR)
        snr = band.snr if band.detected else np.ones(freqs.size)
        spec = spec * snr**2 / (1.0 + 2.0 * snr)
    spec = np.where(mask, spec, 0.0)
    sd = _delay_crlb_s(np.where(mask, band.snr, 0.0), freqs, max(a.size, b.size), n_fft)
    used = freqs[mask] if mask.any() else freqs[:1]
    return spec, n_fft, sd, (float(used.min()), float(used.max()))


def _one_sided_weights(n_bins: int, n_fft: int) -> FloatArray:
    """Weights folding the negative frequencies of a real signal's spectrum onto the positive ones."""
    weights = np.full(n_bins, 2.0)
    weights[0] = 1.0
    if n_fft % 2 == 0:
        weights[-1] = 1.0
    return weights


def _correlation_at(spec: np.ndarray, weights: FloatArray, n_fft: int, lag: float) -> float:
    """Band-limited interpolation of ``irfft(spec)`` at a fractional lag (samples)."""
    phase = np.exp((2j * np.pi * lag / n_fft) * np.arange(spec.size))
    return float(np.sum(weights * np.real(spec * phase)) / n_fft)


def estimate_delay(
    a: ArrayLike,
    b: ArrayLike,
    sample_rate_hz: float,
    *,
    method: DelayMethod = "gcc-ml",
    max_delay_s: float | None = None,
    band_hz: BandSpec = "auto",
    interpolation: Interpolation = "sinc",
    plot_lags_s: float | None = None,
) -> DelayEstimate:
    """Delay of recording ``a`` relative to ``b`` by cross-correlation or GCC-PHAT.

    Parameters
    ----------
    a, b : (n_a,), (n_b,) float
        The two recordings, same sample rate, starting at the same instant.
    sample_rate_hz : float
    method : {"xcorr", "gcc-phat"}
    max_delay_s : float, optional
        Search only ``|delay| <= max_delay_s`` (e.g. the node separation over the sound speed). Each
        recording must last at least twice that (a DataError otherwise). Without it, the search covers
        the delays at which the recordings overlap by at least half the shorter one. Either way each
        recording must hold at least ``MIN_RECORDING_SAMPLES`` samples: below that neither the band nor
        the noise floor (hence the Cramer-Rao sd) can be estimated.
    band_hz : (low, high), "auto" or None
        Use only this frequency band (e.g. the sweep's band), removing out-of-band noise; ``"auto"``
        (default) detects the signal's band from the recordings (module docstring), ``None`` uses all.
    interpolation : {"sinc", "parabolic", "none"}
        Sub-sample refinement of the peak.
    plot_lags_s : float, optional
        Half-width of the correlation window returned for plotting (default: the search window, at most
        0.05 s around the peak if the search is unbounded).

    Returns
    -------
    DelayEstimate
    """
    import scipy.fft

    x = np.asarray(a, dtype=float)
    y = np.asarray(b, dtype=float)
    if x.ndim != 1 or y.ndim != 1 or x.size < 2 or y.size < 2:
        raise DataError(f"recordings must be 1-D with at least 2 samples; got shapes {x.shape} and {y.shape}")
    if not np.all(np.isfinite(x)) or not np.all(np.isfinite(y)):
        raise DataError("recordings hold non-finite samples")
    if not sample_rate_hz > 0:
        raise ConfigError(f"sample rate must be positive, got {sample_rate_hz}")
    if method not in DELAY_METHODS:
        raise ConfigError(f"method must be one of {', '.join(DELAY_METHODS)}; got {method!r}")
    if isinstance(band_hz, str) and band_hz != "auto":
        raise ConfigError(f"band must be 'auto' or (low, high) in Hz, got {band_hz!r}")
    if isinstance(band_hz, tuple | list) and not 0 <= band_hz[0] < band_hz[1]:
        raise ConfigError(f"band must be 0 <= low < high, got {band_hz}")
    if not np.any(x) or not np.any(y):
        raise DataError("a recording is silent (all samples zero): no delay can be estimated")
    if min(x.size, y.size) < MIN_RECORDING_SAMPLES:
        raise DataError(
            f"recordings of {x.size} and {y.size} samples are too short for a delay estimate: each must "
            f"hold at least {MIN_RECORDING_SAMPLES} samples ({MIN_RECORDING_SAMPLES / sample_rate_hz:.6g} s "
            f"at {sample_rate_hz:g} Hz), and twice the delay searched"
        )
    if max_delay_s is not None:
        if not max_delay_s > 0:
            raise ConfigError(f"max delay must be positive, got {max_delay_s}")
        if min(x.size, y.size) / sample_rate_hz < 2.0 * max_delay_s:
            # At a lag near the recording's length the two overlap by a few samples: no delay there is
            # measured, so a search that reaches it is not answered.
            raise DataError(
                f"recordings of {x.size / sample_rate_hz:.6g} s and {y.size / sample_rate_hz:.6g} s are too "
                f"short for a delay search of +-{max_delay_s:g} s: each must last at least "
                f"{2.0 * max_delay_s:g} s (twice the search window); record longer or search a shorter delay"
            )
    spec, n_fft, sd_s, used_band = _cross_spectrum(x, y, method, sample_rate_hz, band_hz)
    corr = scipy.fft.irfft(spec, n_fft)
    # The analytic correlation, whose magnitude is the envelope, from the one-sided spectrum.
    one_sided = np.zeros(n_fft, dtype=complex)
    one_sided[: spec.size] = spec * _one_sided_weights(spec.size, n_fft)
    analytic = np.abs(scipy.fft.ifft(one_sided))
    # Lags -(n_b - 1) .. n_a - 1; negative lags sit at the end of the circular result.
    lags = np.concatenate([np.arange(-(y.size - 1), 0), np.arange(0, x.size)])
    values = np.concatenate([corr[n_fft - (y.size - 1) :], corr[: x.size]])
    envelope = np.concatenate([analytic[n_fft - (y.size - 1) :], analytic[: x.size]])
    # Unbounded search: the lags at which the recordings still overlap by half the shorter one, so that
    # the rule for a bounded search (each recording at least twice the window) holds here too.
    window = np.abs(lags) <= min(x.size, y.size) // 2
    if max_delay_s is not None:
        window = np.abs(lags) <= max_delay_s * sample_rate_hz
        if window.sum() < 3:
            raise ConfigError(f"max delay {max_delay_s} s is shorter than a sample at {sample_rate_hz:g} Hz")
    search = np.where(window, values, -np.inf)
    i = int(np.argmax(search))
    peak = float(lags[i])
    if interpolation == "sinc":
        weights = _one_sided_weights(spec.size, n_fft)
        from scipy.optimize import minimize_scalar

        res = minimize_scalar(
            lambda t: -_correlation_at(spec, weights, n_fft, t),
            bounds=(peak - 1.0, peak + 1.0),
            method="bounded",
            options={"xatol": 1e-6},
        )
        peak = float(res.x)
    elif interpolation == "parabolic" and 0 < i < lags.size - 1:
        y0, y1, y2 = values[i - 1], values[i], values[i + 1]
        denom = y0 - 2 * y1 + y2
        if denom < 0:
            peak += 0.5 * (y0 - y2) / denom
    elif interpolation not in ("sinc", "parabolic", "none"):
        raise ConfigError(f"interpolation must be sinc, parabolic or none; got {interpolation!r}")
    ratio = _peak_ratio(envelope, window, i)
    half = plot_lags_s if plot_lags_s is not None else (max_delay_s or 0.05)
    show = np.abs(lags - lags[i]) <= half * sample_rate_hz if max_delay_s is None else window
    scale = np.max(np.abs(values[show])) or 1.0
    delay_s = peak / sample_rate_hz
    return DelayEstimate(
        delay_s=delay_s,
        delay_samples=peak,
        method=method,
        first="B" if delay_s > 0 else "A",
        peak_ratio=ratio,
        sample_rate_hz=float(sample_rate_hz),
        lags_s=lags[show] / sample_rate_hz,
        correlation=values[show] / scale,
        delay_sd_s=sd_s,
        band_hz=used_band,
    )


def estimate_recording_delay(
    first: str | Path,
    second: str | Path,
    *,
    channel: int = 0,
    method: DelayMethod = "gcc-ml",
    max_delay_s: float | None = None,
    band_hz: BandSpec = "auto",
    progress: Callable[[int], None] | None = None,
) -> RecordingDelay:
    """Read two WAV files (same sample rate) and estimate the delay of ``first`` relative to ``second``.

    ``progress`` is called with 1 after each file is read and after the correlation (3 in all).
    """
    if method not in DELAY_METHODS:
        raise ConfigError(f"method must be one of {', '.join(DELAY_METHODS)}; got {method!r}")
    rec_a = read_wav(first)
    if progress:
        progress(1)
    rec_b = read_wav(second)
    if progress:
        progress(1)
    rate = common_sample_rate(rec_a, rec_b)
    estimate = estimate_delay(
        rec_a.channel(channel),
        rec_b.channel(channel),
        rate,
        method=method,
        max_delay_s=max_delay_s,
        band_hz=band_hz,
    )
    if progress:
        progress(1)
    return RecordingDelay(
        estimate=estimate,
        sources=(rec_a.source, rec_b.source),
        formats=(rec_a.sample_format, rec_b.sample_format),
        channel=channel,
    )


def _peak_ratio(envelope: FloatArray, window: np.ndarray, i: int) -> float:
    """Envelope peak over the largest envelope value outside the main lobe (above half the peak).

    A main lobe covering more than half the search window (a tone, a very narrow band) has no distinct
    arrival: the ratio is 1.
    """
    top = envelope[i]
    low = np.nonzero(envelope <= 0.5 * top)[0]
    left = low[low < i]
    right = low[low > i]
    lo = int(left[-1]) if left.size else 0
    hi = int(right[0]) if right.size else envelope.size - 1
    outside = window.copy()
    outside[lo : hi + 1] = False
    if top <= 0 or hi - lo > 0.5 * window.sum():
        return 1.0
    second = float(np.max(envelope[outside])) if outside.any() else 0.0
    return float(top / second) if second > 0 else float("inf")
