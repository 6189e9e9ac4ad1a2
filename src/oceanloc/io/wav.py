"""Read hydrophone recordings from WAV files of any common sample format.

8-bit unsigned, 16-, 24- and 32-bit signed integer PCM and 32- or 64-bit IEEE float, mono or multi-channel
(including WAVE_FORMAT_EXTENSIBLE headers), through :func:`scipy.io.wavfile.read`. Samples are returned as
floats scaled to ``[-1, 1)`` (full scale of the integer format; float files as stored), so recordings of
different formats can be correlated directly. Unreadable files, truncated files (the data ends before
the size the header announces, or inside a sample frame, or the header itself is cut) and recordings that
cannot be compared (different sample rates) raise :class:`oceanloc.errors.DataError` naming the files:
a truncated recording is never returned as if it were complete.

:func:`write_wav` writes 16-bit PCM; :func:`example_recordings` gives the paths of the sample pair shipped
in ``oceanloc/data/tdoa_sweep`` (made by :func:`oceanloc.sim.flock.write_example_recordings`).
"""

from __future__ import annotations

import re
import struct
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import ConfigError, DataError

EXAMPLE_FOLDER = "tdoa_sweep"
EXAMPLE_FILES: tuple[str, str] = ("hydrophone_a.wav", "hydrophone_b.wav")

_INT_SCALE = {np.dtype(np.int16): 2.0**15, np.dtype(np.int32): 2.0**31, np.dtype(np.int64): 2.0**63}


@dataclass(frozen=True, slots=True, kw_only=True)
class Recording:
    """A recording read from a WAV file.

    Attributes
    ----------
    samples : (n,) or (n, channels) float
        Samples scaled to full scale ``[-1, 1)``.
    sample_rate_hz : float
    source : str
        File name, for messages.
    sample_format : str
        Stored format: ``uint8``, ``int16``, ``int32`` (24- and 32-bit PCM; scipy left-justifies 24-bit
        samples into 32 bits), ``float32`` or ``float64``.
    """

    samples: FloatArray
    sample_rate_hz: float
    source: str
    sample_format: str

    @property
    def n_channels(self) -> int:
        return 1 if self.samples.ndim == 1 else int(self.samples.shape[1])

    @property
    def duration_s(self) -> float:
        return self.samples.shape[0] / self.sample_rate_hz

    def channel(self, index: int = 0) -> FloatArray:
        """One channel as ``(n,)``; DataError if it does not exist."""
        if not 0 <= index < self.n_channels:
            raise DataError(f"{self.source}: has {self.n_channels} channel(s), channel {index} requested")
        return self.samples if self.samples.ndim == 1 else self.samples[:, index]


def read_wav(path: str | Path) -> Recording:
    """Read a WAV file into a :class:`Recording` of floats in ``[-1, 1)``.

    Raises
    ------
    DataError
        If the file is missing, not a WAV file, truncated, empty, or holds non-finite samples.
    """
    p = Path(path)
    try:
        size = p.stat().st_size
        with warnings.catch_warnings(record=True) as caught:
            import scipy.io.wavfile

            warnings.simplefilter("always", scipy.io.wavfile.WavFileWarning)
            rate, data = scipy.io.wavfile.read(p)
    except FileNotFoundError:
        raise DataError(f"{p}: file not found") from None
    except struct.error:
        raise DataError(f"{p}: truncated WAV file: the header ends after {size} bytes") from None
    except Exception as exc:  # scipy raises assorted types (ValueError, UnboundLocalError) on bad headers
        text = str(exc)
        if "Unexpected end of file" in text:
            raise DataError(f"{p}: truncated WAV file: the header ends after {size} bytes") from None
        if "multiple of element size" in text:
            raise DataError(
                f"{p}: truncated WAV file: the data ends inside a sample frame ({size} bytes)"
            ) from None
        raise DataError(f"{p}: not a readable WAV file ({exc})") from None
    for w in caught:
        if "Reached EOF prematurely" in str(w.message):
            expected = re.search(r"expected (\d+) bytes", str(w.message))
            announced = f", the header announces {expected[1]}" if expected else ""
            raise DataError(
                f"{p}: truncated WAV file: {size} bytes{announced} ({data.shape[0]} sample frames present); "
                "the recording was cut off"
            )
    if data.shape[0] == 0:
        raise DataError(f"{p}: holds no samples")
    if rate <= 0:
        raise DataError(f"{p}: invalid sample rate {rate}")
    fmt = data.dtype
    if fmt == np.uint8:
        samples = (data.astype(float) - 128.0) / 128.0
    elif fmt in _INT_SCALE:
        samples = data.astype(float) / _INT_SCALE[fmt]
    elif fmt.kind == "f":
        samples = data.astype(float)
    else:
        raise DataError(f"{p}: unsupported sample format {fmt}")
    if not np.all(np.isfinite(samples)):
        raise DataError(f"{p}: holds non-finite samples (NaN or inf)")
    return Recording(samples=samples, sample_rate_hz=float(rate), source=str(p), sample_format=str(fmt))


def common_sample_rate(*recordings: Recording) -> float:
    """The sample rate shared by all recordings; DataError naming each file and rate if they differ."""
    rates = {r.sample_rate_hz for r in recordings}
    if len(rates) != 1:
        listing = ", ".join(f"{r.source} at {r.sample_rate_hz:g} Hz" for r in recordings)
        raise DataError(
            f"recordings have different sample rates ({listing}); resample them to one rate first"
        )
    return rates.pop()


def write_wav(path: str | Path, samples: FloatArray, sample_rate_hz: int) -> Path:
    """Write samples in ``[-1, 1]`` (clipped) as 16-bit PCM, ``(n,)`` mono or ``(n, channels)``."""
    import scipy.io.wavfile

    p = Path(path)
    pcm = np.round(np.clip(np.asarray(samples, dtype=float), -1.0, 1.0 - 2.0**-15) * 2.0**15).astype(np.int16)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        scipy.io.wavfile.write(p, int(sample_rate_hz), pcm)
    except OSError as exc:
        raise ConfigError(f"{p}: cannot write WAV ({exc.strerror or exc})") from None
    return p


def example_recordings() -> tuple[Path, Path]:
    """Paths of the two sample hydrophone recordings shipped with oceanloc (see their README)."""
    from importlib import resources

    folder = resources.files("oceanloc.data").joinpath(EXAMPLE_FOLDER)
    a, b = (Path(str(folder.joinpath(name))) for name in EXAMPLE_FILES)
    return a, b
