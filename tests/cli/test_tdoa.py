"""`oceanloc tdoa A.wav B.wav`."""

import json

import numpy as np
import pytest
import scipy.io.wavfile
import scipy.signal
from typer.testing import CliRunner

from oceanloc.cli.app import app, main

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
    assert set(payload) == {"provenance", "delay_s", "delay_samples", "method", "first", "peak_ratio"}
    assert payload["delay_samples"] == pytest.approx(37.0, abs=0.05)
    assert payload["delay_s"] == pytest.approx(37.0 / FS, abs=1e-5)
    assert payload["first"] == "B" and payload["method"] == method
    assert png.stat().st_size > 1000


def test_tdoa_rejects_mismatched_rates(tmp_path, capsys):
    pa, pb = _write_pair(tmp_path, 5, rate_b=16000)
    with pytest.raises(SystemExit) as info:
        main(["tdoa", str(pa), str(pb)])
    assert info.value.code == 2
    err = " ".join(capsys.readouterr().err.split())  # rich wraps long lines at the console width
    assert "different sample rates" in err and "8000 Hz" in err and "16000 Hz" in err
