"""Truncated WAV files and recordings too short for the delay search are reported, not answered."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.io.wavfile

from oceanloc.errors import DataError
from oceanloc.estimation.time_delay import estimate_delay
from oceanloc.io.wav import read_wav

RATE = 8000


def _sweep(n: int, delay: int = 0) -> np.ndarray:
    t = np.arange(n) / RATE
    x = np.sin(2 * np.pi * (500 + 1500 * t) * t) * np.exp(-(((t - 0.05) / 0.02) ** 2))
    return np.roll(x, delay)


@pytest.fixture
def full(tmp_path: Path) -> bytes:
    path = tmp_path / "full.wav"
    scipy.io.wavfile.write(path, RATE, (0.5 * _sweep(1000) * 2**15).astype(np.int16))
    return path.read_bytes()  # 44-byte header + 2000 bytes of samples


@pytest.mark.parametrize(
    ("cut", "message"),
    [
        (1944, r"truncated WAV file: 1944 bytes, the header announces 2044 \(950 sample frames present\)"),
        (60, r"truncated WAV file: 60 bytes, the header announces 2044 \(8 sample frames present\)"),
        (44, r"truncated WAV file: 44 bytes, the header announces 2044 \(0 sample frames present\)"),
        (2043, r"truncated WAV file: 2043 bytes, the header announces 2044 \(999 sample frames present\)"),
        (40, r"truncated WAV file: the header ends after 40 bytes"),
        (36, r"truncated WAV file: the header ends after 36 bytes"),
        (20, r"truncated WAV file: the header ends after 20 bytes"),
        (12, r"truncated WAV file: the header ends after 12 bytes"),
        (4, r"truncated WAV file: the header ends after 4 bytes"),
    ],
)
def test_a_truncated_wav_is_a_data_error_naming_the_file(tmp_path: Path, full: bytes, cut: int, message: str):
    path = tmp_path / "cut.wav"
    path.write_bytes(full[:cut])
    with pytest.raises(DataError, match=rf"cut\.wav: {message}"):
        read_wav(path)


def test_the_complete_file_still_reads(tmp_path: Path, full: bytes):
    path = tmp_path / "ok.wav"
    path.write_bytes(full)
    assert read_wav(path).samples.shape == (1000,)


@pytest.mark.parametrize(
    ("n", "max_delay_s", "ok"),
    [(1000, 0.05, True), (1000, 0.0625, True), (1000, 0.07, False), (200, 0.02, False)],
)
def test_recordings_shorter_than_twice_the_delay_search_are_refused(n: int, max_delay_s: float, ok: bool):
    a, b = _sweep(n, 40), _sweep(n)
    if ok:
        est = estimate_delay(a, b, RATE, method="xcorr", max_delay_s=max_delay_s)
        assert est.delay_samples == pytest.approx(40.0, abs=0.05)
        return
    duration = n / RATE
    message = (
        rf"recordings of {duration:g} s and {duration:g} s are too short for a delay search of "
        rf"\+-{max_delay_s:g} s: each must last at least {2 * max_delay_s:g} s"
    )
    with pytest.raises(DataError, match=message):
        estimate_delay(a, b, RATE, method="xcorr", max_delay_s=max_delay_s)


def test_tdoa_command_on_a_truncated_file_exits_2_with_one_line(tmp_path: Path, full: bytes):
    good, cut = tmp_path / "a.wav", tmp_path / "b.wav"
    good.write_bytes(full)
    cut.write_bytes(full[:1000])
    res = subprocess.run(
        [sys.executable, "-m", "oceanloc", "tdoa", str(good), str(cut)],
        capture_output=True,
        text=True,
        env=os.environ,
    )
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "b.wav: truncated WAV file: 1000 bytes" in " ".join(res.stderr.split())
    res = subprocess.run(
        [sys.executable, "-m", "oceanloc", "tdoa", str(good), str(good), "--max-delay", "0.1"],
        capture_output=True,
        text=True,
        env=os.environ,
    )
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "too short for a delay search of +-0.1 s" in " ".join(res.stderr.split())


def test_a_two_sample_recording_is_refused_through_the_command(tmp_path: Path):
    """A two-sample WAV once gave a delay with a Cramer-Rao sd of 6e-7 s and exit 0."""
    tiny = tmp_path / "tiny.wav"
    scipy.io.wavfile.write(tiny, RATE, np.array([1000, -1000], dtype=np.int16))
    res = subprocess.run(
        [sys.executable, "-m", "oceanloc", "tdoa", str(tiny), str(tiny)],
        capture_output=True,
        text=True,
        env=os.environ,
    )
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "recordings of 2 and 2 samples are too short for a delay estimate" in " ".join(res.stderr.split())
    lines = res.stderr.splitlines()
    assert [line for line in lines if "error" in line.lower()] == lines[-1:]


@pytest.mark.parametrize(("n", "ok"), [(63, False), (64, True)])
def test_the_shortest_recording_has_64_samples(n: int, ok: bool):
    rng = np.random.default_rng(5)
    a = rng.standard_normal(n)
    if ok:
        assert np.isfinite(estimate_delay(a, np.roll(a, 3), RATE, method="xcorr").delay_samples)
        return
    with pytest.raises(DataError, match=rf"recordings of {n} and {n} samples are too short.*at least 64"):
        estimate_delay(a, np.roll(a, 3), RATE, method="xcorr")


def test_the_unbounded_search_stays_where_the_recordings_overlap_by_half():
    a, b = _sweep(1000, 40), _sweep(1000)
    est = estimate_delay(a, b, RATE, method="xcorr")
    assert est.delay_samples == pytest.approx(40.0, abs=0.05)
    assert np.max(np.abs(est.lags_s)) * RATE <= 500
