"""WAV reading in every common sample format, and clear errors."""

import wave

import numpy as np
import pytest
import scipy.io.wavfile

from oceanloc.errors import DataError
from oceanloc.io.wav import common_sample_rate, read_wav

SIGNAL = np.array([0.0, 0.5, -0.5, 0.25, -1.0, 0.999])


def _write_24bit(path, values, rate):
    ints = np.round(values * 2**23).clip(-(2**23), 2**23 - 1).astype(np.int64)
    with wave.open(str(path), "wb") as f:
        f.setnchannels(1)
        f.setsampwidth(3)
        f.setframerate(rate)
        f.writeframes(b"".join(int(v).to_bytes(3, "little", signed=True) for v in ints))


@pytest.mark.parametrize(
    ("dtype", "scale", "offset", "tol"),
    [
        (np.uint8, 127, 128, 1 / 64),
        (np.int16, 2**15 - 1, 0, 1e-4),
        (np.int32, 2**31 - 1, 0, 1e-9),
        (np.float32, 1, 0, 1e-7),
        (np.float64, 1, 0, 0),
    ],
)
def test_formats_read_to_full_scale_floats(tmp_path, dtype, scale, offset, tol):
    path = tmp_path / f"x_{np.dtype(dtype).name}.wav"
    kind = np.dtype(dtype).kind
    data = np.round(SIGNAL * scale + offset).astype(dtype) if kind != "f" else SIGNAL.astype(dtype)
    scipy.io.wavfile.write(path, 48000, data)
    rec = read_wav(path)
    assert rec.sample_rate_hz == 48000 and rec.n_channels == 1
    assert rec.sample_format == np.dtype(dtype).name
    np.testing.assert_allclose(rec.samples, SIGNAL, atol=tol + 1e-12)
    assert rec.duration_s == pytest.approx(6 / 48000)


def test_24_bit_pcm(tmp_path):
    path = tmp_path / "x24.wav"
    _write_24bit(path, SIGNAL, 96000)
    rec = read_wav(path)
    np.testing.assert_allclose(rec.samples, SIGNAL, atol=2**-23)


def test_stereo_channels(tmp_path):
    path = tmp_path / "st.wav"
    scipy.io.wavfile.write(path, 8000, np.stack([SIGNAL, -SIGNAL], axis=1).astype(np.float32))
    rec = read_wav(path)
    assert rec.n_channels == 2
    np.testing.assert_allclose(rec.channel(1), -SIGNAL, atol=1e-7)
    with pytest.raises(DataError, match="2 channel"):
        rec.channel(2)


def test_mismatched_sample_rates_name_both_files(tmp_path):
    a, b = tmp_path / "a.wav", tmp_path / "b.wav"
    scipy.io.wavfile.write(a, 48000, SIGNAL.astype(np.float32))
    scipy.io.wavfile.write(b, 44100, SIGNAL.astype(np.float32))
    with pytest.raises(DataError, match=r"a\.wav at 48000 Hz, .*b\.wav at 44100 Hz"):
        common_sample_rate(read_wav(a), read_wav(b))
    assert common_sample_rate(read_wav(a), read_wav(a)) == 48000


def test_bad_files(tmp_path):
    with pytest.raises(DataError, match="not found"):
        read_wav(tmp_path / "missing.wav")
    junk = tmp_path / "junk.wav"
    junk.write_bytes(b"RIFF\x10\x00\x00\x00WAVEjunkjunk")
    with pytest.raises(DataError, match=r"junk\.wav: not a readable WAV"):
        read_wav(junk)
    nan = tmp_path / "nan.wav"
    scipy.io.wavfile.write(nan, 8000, np.array([0.0, np.nan], dtype=np.float32))
    with pytest.raises(DataError, match="non-finite"):
        read_wav(nan)
