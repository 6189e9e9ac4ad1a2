import numpy as np
import pytest

from oceanloc.config.survey import builtin_survey_scenarios, load_survey_scenario
from oceanloc.errors import ConfigError
from oceanloc.units import DEG

GOOD = """
[scenario]
name = "t"
epochs = 10
[vehicle]
start_enu_m = [0.0, 0.0, 0.0]
start_yaw_deg = 45.0
[sensor]
sigma_range_m = 0.1
[prior]
sigma_enu_m = [10.0, 10.0, 1.0]
[[transponders]]
enu_m = [1.0, 2.0, -3.0]
"""


def _write(tmp_path, text):
    p = tmp_path / "s.toml"
    p.write_text(text)
    return p


def test_builtin_scenarios_match_journal_tables():
    assert set(builtin_survey_scenarios()) >= {
        "garcia2019-m1",
        "garcia2019-m4",
        "garcia2018-greedy-m1",
        "garcia2018-greedy-m4",
    }
    s = load_survey_scenario("garcia2019-m4")
    np.testing.assert_array_equal(s.transponders_enu_m[1], [-2.0, -1.0, -7.0])
    np.testing.assert_array_equal(s.prior_cov_m2, np.diag([1e4, 1e4, 4.0]))
    assert s.start_yaw_rad == pytest.approx(-30 * DEG)
    assert s.max_yaw_rate_rad_s == pytest.approx(30 * DEG)
    assert (s.sigma_range_m, s.epochs, s.speed_mps) == (0.12, 50, 3.0)


def test_minimal_file_gets_defaults(tmp_path):
    s = load_survey_scenario(_write(tmp_path, GOOD))
    assert s.planner.kind == "lookahead" and s.planner.horizon == 1
    assert s.start_yaw_rad == pytest.approx(45 * DEG)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "sigma_range_m = 0.1",
            "sigma_range_m = -0.1",
            r"\[sensor\] field 'sigma_range_m': must be >= 1e-06",
        ),
        ("epochs = 10", "epochs = 'ten'", r"field 'epochs': must be an integer"),
        (
            "enu_m = [1.0, 2.0, -3.0]",
            "enu_m = [1.0, 2.0, 3.0]",
            r"\[transponders\[0\]\] field 'enu_m': transponders lie below",
        ),
        ("enu_m = [1.0, 2.0, -3.0]", "enu_m = [1.0, 2.0]", "must have 3 numbers"),
        (
            "start_yaw_deg = 45.0",
            "start_yaw_deg = 45.0\nsped_mps = 3.0",
            "field 'sped_mps': unknown field",
        ),
        (
            "sigma_enu_m = [10.0, 10.0, 1.0]",
            "sigma_enu_m = [10.0, 0.0, 1.0]",
            r"\[prior\] field 'sigma_enu_m': must hold numbers in \[0.001, 100000\]",
        ),
        ("sigma_enu_m = [10.0, 10.0, 1.0]", "sigma_enu_m = [1e160, 10.0, 1.0]", r"in \[0.001, 100000\]"),
        ("sigma_enu_m = [10.0, 10.0, 1.0]", "sigma_enu_m = [5e-324, 10.0, 1.0]", r"in \[0.001, 100000\]"),
        (
            "start_yaw_deg = 45.0",
            "start_yaw_deg = 45.0\nspeed_mps = 1e-300",
            r"'speed_mps': must be >= 0.001",
        ),
        ("start_yaw_deg = 45.0", "start_yaw_deg = 45.0\nspeed_mps = 1e30", r"'speed_mps': must be <= 100"),
        ("start_yaw_deg = 45.0", "start_yaw_deg = 45.0\nperiod_s = 1e-9", r"'period_s': must be >= 0.001"),
        ("start_yaw_deg = 45.0", "start_yaw_deg = 45.0\nperiod_s = 1e9", r"'period_s': must be <= 3600"),
        ("sigma_range_m = 0.1", "sigma_range_m = 1e300", r"'sigma_range_m': must be <= 1000"),
        ("epochs = 10", "epochs = 1000000000", r"\[scenario\] field 'epochs': must be <= 100000"),
        ("epochs = 10", "epochs = 0", r"field 'epochs': must be >= 1"),
        ("enu_m = [1.0, 2.0, -3.0]", "enu_m = [1.0, 2.0, -30000.0]", r"z in \[-11000, 0\) m"),
        (
            "enu_m = [1.0, 2.0, -3.0]",
            "enu_m = [1e300, 2.0, -3.0]",
            r"'enu_m': must hold numbers in \[-100000",
        ),
        (
            "start_enu_m = [0.0, 0.0, 0.0]",
            "start_enu_m = [0.0, 1e300, 0.0]",
            r"\[vehicle\] field 'start_enu_m'",
        ),
        (
            "[[transponders]]\nenu_m = [1.0, 2.0, -3.0]",
            "[[transponders]]\nenu_m = [1.0, 2.0, -3.0]\n" * 65,
            r"field 'transponders': at most 64 transponders, got 65",
        ),
        ("epochs = 10", "epochs = 10\n[montecarlo]\nruns = 1000000000", r"'runs': must be <= 10000000"),
        ("[[transponders]]\nenu_m = [1.0, 2.0, -3.0]", "", "field 'transponders': is required"),
        ("epochs = 10", "epochs = 10\n[planner]\nkind = 'best'", "must be one of random-yaw"),
    ],
)
def test_validation_names_file_table_and_field(tmp_path, old, new, message):
    path = _write(tmp_path, GOOD.replace(old, new))
    with pytest.raises(ConfigError, match=message) as info:
        load_survey_scenario(path)
    assert str(path) in str(info.value)


def test_malformed_toml_and_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_survey_scenario(_write(tmp_path, "[scenario\nname="))
    with pytest.raises(ConfigError, match="file not found"):
        load_survey_scenario(tmp_path / "nope.toml")
    with pytest.raises(ConfigError, match="neither a scenario file nor a built-in"):
        load_survey_scenario("no-such-scenario")


def test_loader_keeps_the_toml_text_for_the_provenance_hash(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text(GOOD)
    assert load_survey_scenario(path).toml_text == GOOD
    builtin = load_survey_scenario("garcia2019-m1")
    assert "[scenario]" in builtin.toml_text and 'name = "garcia2019-m1"' in builtin.toml_text


def test_overrides_parse_planner_names():
    base = load_survey_scenario("garcia2019-m4")
    assert base.with_overrides(planner="k0").planner.kind == "random-yaw"
    assert base.with_overrides(horizon=3).planner.horizon == 3
    greedy = base.with_overrides(planner="greedy", epochs=7)
    assert greedy.planner.kind == "greedy" and greedy.epochs == 7
    with pytest.raises(ConfigError, match="unknown planner 'spiral'"):
        base.with_overrides(planner="spiral")
    with pytest.raises(ConfigError, match="epochs must be at least 1"):
        base.with_overrides(epochs=0)
