"""Flock scenarios: the built-in TOMLs and validation messages that name file, table and field."""

import numpy as np
import pytest

from oceanloc.config.flock import builtin_flock_scenarios, load_flock_scenario, motion_model
from oceanloc.config.survey import builtin_survey_scenarios
from oceanloc.errors import ConfigError

BASE = """
[scenario]
name = "t"
dt_s = 0.1
duration_s = 10.0
[nodes]
layout = "fixed"
positions_m = [0.0, 0.0, 10.0, 0.0, 0.0, 10.0]
[target]
motion = "straight"
start_m = [1.0, 2.0]
velocity_mps = [0.5, 0.0]
[measurement]
kind = "tdoa"
sigma_true = 1e-4
[filters]
initial_state = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
initial_sigma = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0]
process_noise = [1e-5, 1e-5, 1e-6, 1e-6, 1e-6, 1e-6]
measurement_sigma = 1e-4
"""


def test_builtin_scenarios_hold_the_thesis_readings():
    assert builtin_flock_scenarios() == ["dillard-filters", "dillard-lab-tdoa"]
    assert not any(n.startswith("dillard-") for n in builtin_survey_scenarios())
    sc = load_flock_scenario("dillard-filters")
    assert sc.epochs == 70000 and sc.kind == "bearing" and sc.nodes.count == 4
    np.testing.assert_allclose(np.diag(sc.filters.process_noise), 1e-6 * np.array([10, 10, 1, 1, 1, 1]))
    assert sc.filters.measurement_sigma == 1e-3
    assert (sc.filters.ukf_alpha, sc.filters.ukf_beta, sc.filters.ukf_kappa) == (1e-3, 2.0, 0.0)
    np.testing.assert_allclose(sc.filters.initial_state, [100, 100, 20, 20, 0, 0])
    lab = load_flock_scenario("dillard-lab-tdoa")
    assert lab.kind == "tdoa" and lab.nodes.layout == "y" and lab.sound_speed_mps == 1500.0
    np.testing.assert_allclose(lab.target.start_m, [1.2551, 0.9699])
    # The noise reading reproduces the thesis' mean |noise| of 0.0011 s: E|N(0, s^2)| = s sqrt(2 / pi).
    assert lab.sigma_true * np.sqrt(2 / np.pi) == pytest.approx(0.0011, abs=0.00005)


def test_file_scenario_and_motion_models(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(BASE)
    sc = load_flock_scenario(path)
    assert sc.nodes.count == 3 and sc.epochs == 100
    np.testing.assert_allclose(sc.nodes.positions_m, [[0, 0], [10, 0], [0, 10]])
    listing = motion_model("listing", 0.5, np.eye(6))
    np.testing.assert_allclose(
        listing.propagate(np.array([1.0, 2.0, 2.0, 4.0, 9.0, 9.0])), [2, 4, 2, 4, 9, 9]
    )
    ca = motion_model("constant-acceleration", 0.5, np.eye(6))
    assert ca.transition[2, 4] == 0.5


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ('kind = "tdoa"', 'kind = "doppler"', r"\[measurement\] field 'kind': must be one of"),
        ("dt_s = 0.1", "dt_s = -0.1", r"\[scenario\] field 'dt_s': must be >= 1e-06"),
        ("positions_m = [0.0, 0.0, 10.0, 0.0, 0.0, 10.0]", "positions_m = [0.0, 0.0, 1.0]", "positions_m"),
        ("initial_sigma = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0]", "initial_sigma = [1.0, 1.0]", "initial_sigma"),
        ('motion = "straight"', 'motion = "straight"\nspeed = 3', r"\[target\] field 'speed': unknown field"),
    ],
)
def test_errors_name_the_field(tmp_path, old, new, message):
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace(old, new))
    with pytest.raises(ConfigError, match=message):
        load_flock_scenario(path)


def test_unknown_builtin():
    with pytest.raises(ConfigError, match="dillard-filters"):
        load_flock_scenario("no-such-flock")


# Issue 11, section 2 (flock): hostile values that gave NaN/inf results, LinAlgError or MemoryError.
HOSTILE = [
    # (old text, new text, message naming table, field and range)
    (
        "initial_sigma = [1.0, 1.0,",
        "initial_sigma = [1e160, 1.0,",
        r"\[filters\] field 'initial_sigma': entry 0 must be within \[1e-06, 1e\+06\]",
    ),
    (
        "initial_sigma = [1.0, 1.0,",
        "initial_sigma = [5e-324, 1.0,",
        r"\[filters\] field 'initial_sigma': entry 0 must be within \[1e-06",
    ),
    (
        "initial_sigma = [1.0, 1.0, 1.0,",
        "initial_sigma = [1.0, 1.0, 1e300,",
        r"field 'initial_sigma': entry 2 must be within \[1e-06, 1000\] m, m/s",
    ),
    (
        "velocity_mps = [0.5, 0.0]",
        "velocity_mps = [1e30, 0.0]",
        r"\[target\] field 'velocity_mps': entry 0 must be within \[-100, 100\] m/s",
    ),
    (
        "start_m = [1.0, 2.0]",
        "start_m = [1e300, 2.0]",
        r"\[target\] field 'start_m': entry 0 must be within \[-1e\+06, 1e\+06\] m",
    ),
    ("duration_s = 10.0", "duration_s = 0.0", r"\[scenario\] field 'duration_s': must be >= 0.1"),
    ("duration_s = 10.0", "duration_s = 1e300", r"\[scenario\] field 'duration_s': must be <= 10000000.0"),
    ("dt_s = 0.1", "dt_s = 1e-300", r"\[scenario\] field 'dt_s': must be >= 1e-06"),
    (
        "dt_s = 0.1\nduration_s = 10.0",
        "dt_s = 1e-6\nduration_s = 1e6",
        r"field 'duration_s': 1e\+12 steps of 1e-06 s; at most 10,000,000",
    ),
    (
        "measurement_sigma = 1e-4",
        "measurement_sigma = 5e-324",
        r"\[filters\] field 'measurement_sigma': must be >= 1e-12",
    ),
    ("measurement_sigma = 1e-4", "measurement_sigma = 1e30", r"field 'measurement_sigma': must be <= 1"),
    ("sigma_true = 1e-4", "sigma_true = 1e200", r"\[measurement\] field 'sigma_true': must be <= 1"),
    (
        "process_noise = [1e-5,",
        "process_noise = [1e300,",
        r"\[filters\] field 'process_noise': entry 0 must be within \[0, 1e\+06\]",
    ),
    (
        "process_noise = [1e-5,",
        "process_noise = [-1.0,",
        r"field 'process_noise': entry 0 must be within \[0,",
    ),
    (
        "positions_m = [0.0, 0.0, 10.0, 0.0, 0.0, 10.0]",
        "positions_m = [0.0, 0.0, 0.0, 0.0, 0.0, 10.0]",
        r"field 'positions_m': nodes 0 and 1 are less than 1 mm apart",
    ),
    (
        "positions_m = [0.0, 0.0, 10.0, 0.0, 0.0, 10.0]",
        "positions_m = [0.0, 0.0, 1e300, 0.0, 0.0, 10.0]",
        r"field 'positions_m': entry 2 must be within",
    ),
    (
        "measurement_sigma = 1e-4",
        "measurement_sigma = 1e-4\nukf_beta = 1e300",
        r"field 'ukf_beta': must be <= 100",
    ),
    ('name = "t"', 'name = " "', r"\[scenario\] field 'name': must not be empty"),
]


@pytest.mark.parametrize(("old", "new", "message"), HOSTILE)
def test_hostile_values_name_file_table_field_and_range(tmp_path, old, new, message):
    path = tmp_path / "bad.toml"
    text = BASE.replace(old, new)
    assert text != BASE
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as err:
        load_flock_scenario(path)
    assert str(path) in str(err.value)


RING_100 = """
[nodes]
layout = "ring"
count = 100
radius_m = 100.0
"""


def test_memory_is_estimated_before_allocating(tmp_path):
    # One run of 1e6 steps with 100 TDOA nodes (4950 pairs): 8 B x 1e6 x (2 x 100 + 3 x 4950 + 2 x 6 + 8)
    # = 120.6 GB = 112.3 GiB, checked at load time (the Monte Carlo checks its chunks of runs too).
    text = BASE.replace("dt_s = 0.1\nduration_s = 10.0", "dt_s = 1e-3\nduration_s = 1e3")
    text = text.replace('[nodes]\nlayout = "fixed"\npositions_m = [0.0, 0.0, 10.0, 0.0, 0.0, 10.0]', RING_100)
    path = tmp_path / "big.toml"
    path.write_text(text)
    with pytest.raises(
        ConfigError,
        match=r"big.toml: \[scenario\] field 'dt_s': 1000000 epochs x 1 run\(s\) at once need about"
        r" 112.3 GiB \(limit 8 GiB\); use a longer dt_s",
    ):
        load_flock_scenario(path)
    from oceanloc.config.flock import check_memory

    sc = load_flock_scenario("dillard-filters")
    check_memory(sc)  # the thesis' 70000 epochs x 50 runs at once: 0.9 GB
    with pytest.raises(ConfigError, match="need about"):
        check_memory(sc.with_overrides(runs=1_000_000))


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "initial_sigma = [1.0, 1.0,",
            "initial_sigma = [1e160, 1.0,",
            "field 'initial_sigma': entry 0 must be within",
        ),
        ("dt_s = 0.1\nduration_s = 10.0", "dt_s = 1e-3\nduration_s = 1e3", "need about"),
    ],
)
def test_hostile_scenario_through_the_command(tmp_path, old, new, message):
    import os
    import subprocess
    import sys

    path = tmp_path / "bad.toml"
    text = BASE.replace(old, new) + "[montecarlo]\nruns = 100\n"
    if message == "need about":
        text = text.replace(
            '[nodes]\nlayout = "fixed"\npositions_m = [0.0, 0.0, 10.0, 0.0, 0.0, 10.0]', RING_100
        )
    path.write_text(text)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "oceanloc",
            "reproduce",
            "dillard-filters",
            "--scenario",
            str(path),
            "--runs",
            "1",
        ],
        capture_output=True,
        text=True,
        env=os.environ,
    )
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and message in lines[0] and "bad.toml" in lines[0]
