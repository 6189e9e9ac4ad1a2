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
        ("dt_s = 0.1", "dt_s = -0.1", r"\[scenario\] field 'dt_s': must be > 0"),
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
