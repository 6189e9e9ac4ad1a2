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
  signals.

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

DelayMethod: TypeAlias = Literal["xcorr", "gcc-phat"]
DELAY_METHODS: tuple[str, ...] = ("xcorr", "gcc-phat")
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
    """

    delay_s: float
    delay_samples: float
    method: str
    first: str
    peak_ratio: float
    sample_rate_hz: float
    lags_s: FloatArray
    correlation: FloatArray

    def to_record(self) -> dict[str, Any]:
        """The delay and its confidence (the correlation curve is left to the figure)."""
        return {
            "delay_s": float(self.delay_s),
            "delay_samples": float(self.delay_samples),
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


def _cross_spectrum(
    a: FloatArray, b: FloatArray, method: str, sample_rate_hz: float, band_hz: tuple[float, float] | None
) -> tuple[np.ndarray, int]:
    import scipy.fft

    n_fft = scipy.fft.next_fast_len(a.size + b.size - 1, real=True)
    spec = scipy.fft.rfft(a, n_fft) * np.conj(scipy.fft.rfft(b, n_fft))
    if method == "gcc-phat":
        mag = np.abs(spec)
        spec = spec / np.maximum(mag, 1e-12 * mag.max())
    if band_hz is not None:
        freqs = scipy.fft.rfftfreq(n_fft, 1.0 / sample_rate_hz)
        spec = np.where((freqs >= band_hz[0]) & (freqs <= band_hz[1]), spec, 0.0)
    return spec, n_fft


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
    method: DelayMethod = "gcc-phat",
    max_delay_s: float | None = None,
    band_hz: tuple[float, float] | None = None,
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
        recording must last at least twice that (a DataError otherwise).
    band_hz : (low, high), optional
        Use only this frequency band (e.g. the sweep's band), removing out-of-band noise.
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
    if band_hz is not None and not 0 <= band_hz[0] < band_hz[1]:
        raise ConfigError(f"band must be 0 <= low < high, got {band_hz}")
    if not np.any(x) or not np.any(y):
        raise DataError("a recording is silent (all samples zero): no delay can be estimated")
    spec, n_fft = _cross_spectrum(x, y, method, sample_rate_hz, band_hz)
    corr = scipy.fft.irfft(spec, n_fft)
    # The analytic correlation, whose magnitude is the envelope, from the one-sided spectrum.
    one_sided = np.zeros(n_fft, dtype=complex)
    one_sided[: spec.size] = spec * _one_sided_weights(spec.size, n_fft)
    analytic = np.abs(scipy.fft.ifft(one_sided))
    # Lags -(n_b - 1) .. n_a - 1; negative lags sit at the end of the circular result.
    lags = np.concatenate([np.arange(-(y.size - 1), 0), np.arange(0, x.size)])
    values = np.concatenate([corr[n_fft - (y.size - 1) :], corr[: x.size]])
    envelope = np.concatenate([analytic[n_fft - (y.size - 1) :], analytic[: x.size]])
    window = np.ones(lags.size, dtype=bool)
    if max_delay_s is not None:
        if not max_delay_s > 0:
            raise ConfigError(f"max delay must be positive, got {max_delay_s}")
        window = np.abs(lags) <= max_delay_s * sample_rate_hz
        if window.sum() < 3:
            raise ConfigError(f"max delay {max_delay_s} s is shorter than a sample at {sample_rate_hz:g} Hz")
        shortest = min(x.size, y.size) / sample_rate_hz
        if shortest < 2.0 * max_delay_s:
            # At a lag near the recording's length the two overlap by a few samples: no delay there is
            # measured, so a search that reaches it is not answered.
            raise DataError(
                f"recordings of {x.size / sample_rate_hz:.6g} s and {y.size / sample_rate_hz:.6g} s are too "
                f"short for a delay search of +-{max_delay_s:g} s: each must last at least "
                f"{2.0 * max_delay_s:g} s (twice the search window); record longer or search a shorter delay"
            )
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
    )


def estimate_recording_delay(
    first: str | Path,
    second: str | Path,
    *,
    channel: int = 0,
    method: DelayMethod = "gcc-phat",
    max_delay_s: float | None = None,
    band_hz: tuple[float, float] | None = None,
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
