"""`oceanloc tdoa A.wav B.wav` and `oceanloc tdoa --example`."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.io.wavfile
import scipy.signal
from typer.testing import CliRunner

from oceanloc.cli.app import app, main
from oceanloc.io.records import file_sha256

FS = 8000


def _write_pair(tmp_path, delay, rate_b=FS):
    t = np.arange(int(0.25 * FS)) / FS
    sweep = scipy.signal.chirp(t, 100, t[-1], 3000) * np.hanning(t.size)
    a, b = np.zeros(3 * t.size), np.zeros(3 * t.size)
    a[1000 + delay : 1000 + delay + t.size] = sweep
    b[1000 : 1000 + t.size] = sweep
    pa, pb = tmp_path / "A.wav", tmp_path / "B.wav"
    scipy.io.wavfile.write(pa, FS, (0.5 * a * 32767).astype(np.int16))
    scipy.io.wavfile.write(pb, rate_b, (0.5 * b).astype(np.float32))
    return pa, pb


@pytest.mark.parametrize("method", ["xcorr", "gcc-phat"])
def test_tdoa_json_shape_and_sign(tmp_path, method):
    pa, pb = _write_pair(tmp_path, 37)
    out, png = tmp_path / "t.json", tmp_path / "c.png"
    result = CliRunner().invoke(
        app, ["tdoa", str(pa), str(pb), "--method", method, "--json", str(out), "--png", str(png)]
    )
    assert result.exit_code == 0, result.output
    payload = json.loads(out.read_text())
    assert {"provenance", "delay_s", "delay_samples", "method", "first", "peak_ratio"} <= set(payload)
    assert payload["delay_samples"] == pytest.approx(37.0, abs=0.05)
    assert payload["delay_s"] == pytest.approx(37.0 / FS, abs=1e-5)
    assert payload["first"] == "B" and payload["method"] == method and payload["sample_rate_hz"] == FS
    inputs = payload["provenance"]["inputs"]
    assert [i["sha256"] for i in inputs] == [file_sha256(pa), file_sha256(pb)]
    assert png.stat().st_size > 1000


def test_tdoa_rejects_mismatched_rates(tmp_path, capsys):
    pa, pb = _write_pair(tmp_path, 5, rate_b=16000)
    with pytest.raises(SystemExit) as info:
        main(["tdoa", str(pa), str(pb)])
    assert info.value.code == 2
    err = " ".join(capsys.readouterr().err.split())  # rich wraps long lines at the console width
    assert "different sample rates" in err and "8000 Hz" in err and "16000 Hz" in err


def _run(*args):
    return subprocess.run(
        [sys.executable, "-m", "oceanloc", "tdoa", *args], capture_output=True, text=True, env=os.environ
    )


def test_example_through_the_installed_command(tmp_path):
    proc = _run("--example", "--json", str(tmp_path / "e.json"))
    assert proc.returncode == 0, proc.stderr
    assert "hydrophone_a.wav" in proc.stderr and "hydrophone_b.wav" in proc.stdout
    payload = json.loads((tmp_path / "e.json").read_text())
    # The shipped pair: A hears the sweep 1.2345 ms after B (20 dB SNR, an echo in A): within 0.1 sample.
    assert payload["delay_s"] == pytest.approx(1.2345e-3, abs=0.1 / 16000) and payload["first"] == "B"


def test_no_files_is_a_usage_error():
    proc = _run()
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "give two WAV files A and B, or --example" in proc.stderr


def test_tdoa_prints_the_cramer_rao_sd_and_rejects_short_recordings(tmp_path):
    pa, pb = _write_pair(tmp_path, 37)
    out = tmp_path / "t.json"
    result = CliRunner().invoke(app, ["tdoa", str(pa), str(pb), "--json", str(out)])
    assert result.exit_code == 0, result.output
    assert "delay sd, Cramer-Rao bound (s)" in result.output and "band used (Hz)" in result.output
    payload = json.loads(out.read_text())
    assert 0 < payload["delay_sd_samples"] < 0.05 and payload["method"] == "gcc-ml"
    proc = subprocess.run(
        [sys.executable, "-m", "oceanloc", "tdoa", str(pa), str(pb), "--max-delay", "10"],
        capture_output=True,
        text=True,
        env=os.environ,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    lines = [line for line in proc.stderr.splitlines() if "too short" in line]
    assert len(lines) == 1 and "delay search of +-10 s" in lines[0]
