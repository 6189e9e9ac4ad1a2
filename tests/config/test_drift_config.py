import numpy as np
import pytest

from oceanloc.config.drift import builtin_drift_scenarios, load_drift_scenario, problem_from_scenario
from oceanloc.config.survey import builtin_survey_scenarios
from oceanloc.errors import ConfigError, OceanlocError

BASE = """
[scenario]
name = "t"
[currents]
kind = "uniform"
velocity_mps = [0.2, 0.0]
[map]
bounds_m = [0.0, 1000.0, 0.0, 1000.0]
[[map.rectangles]]
x_m = [400.0, 600.0]
y_m = [400.0, 600.0]
[route]
start_m = [100.0, 100.0]
goal_m = [900.0, 900.0]
"""


def _write(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


def test_builtins_load_and_stay_out_of_the_survey_list():
    names = builtin_drift_scenarios()
    assert {
        "dillard-drift-fixed",
        "dillard-drift-continuous",
        "dillard-drift-swap",
        "dillard-drift-gyre-netcdf",
    } <= set(names)
    assert not any(n.startswith("dillard-drift-") for n in builtin_survey_scenarios())
    for name in names:
        sc = load_drift_scenario(name)
        problem = problem_from_scenario(sc)
        assert problem.space.is_valid(problem.start_m)
    gyre = load_drift_scenario("dillard-drift-gyre-netcdf")
    assert gyre.projection is not None and gyre.obstacles.grid is not None  # the island
    assert gyre.time_weight_wh_per_h == 1.0


def test_a_minimal_file(tmp_path):
    sc = load_drift_scenario(_write(tmp_path, BASE))
    p = problem_from_scenario(sc)
    assert p.max_leg_m == pytest.approx(p.energy.max_hop_m)
    assert sc.integrator == "rk4" and p.hdop is None
    np.testing.assert_allclose(p.goal_m, [900.0, 900.0])


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ('kind = "uniform"', 'kind = "whirlpool"', r"\[currents\] field 'kind': must be one of"),
        ("x_m = [400.0, 600.0]", "x_m = [600.0, 400.0]", r"\[map.rectangles\[0\]\] field 'x_m'"),
        (
            "start_m = [100.0, 100.0]",
            "start_m = [500.0, 500.0]",
            r"\[route\] field 'start_m'.*inside an obstacle",
        ),
        ("[route]", "[route]\nspeed = 3", r"\[route\] field 'speed': unknown field"),
        ('kind = "uniform"', 'kind = "netcdf"\npath = "nowhere.nc"', "current file not found"),
    ],
)
def test_errors_name_the_file_table_and_field(tmp_path, old, new, message):
    path = _write(tmp_path, BASE.replace(old, new))
    with pytest.raises(OceanlocError, match=message) as info:
        load_drift_scenario(path)
    assert "Traceback" not in str(info.value)


def test_unknown_builtin_is_a_config_error():
    with pytest.raises(ConfigError, match="built-in drift scenario"):
        load_drift_scenario("dillard-drift-nope")


def test_the_scenario_keeps_its_toml_text_and_data_files(tmp_path):
    sc = load_drift_scenario(_write(tmp_path, BASE))
    assert sc.toml_text == BASE and sc.data_files == ()
    builtin = load_drift_scenario("dillard-drift-fixed")
    assert "[scenario]" in builtin.toml_text and 'name = "dillard-drift-fixed"' in builtin.toml_text
    gyre = load_drift_scenario("dillard-drift-gyre-netcdf")
    assert len(gyre.data_files) == 1 and gyre.data_files[0].endswith("dillard-drift-gyre.nc")


def test_an_unknown_planner_kind_names_the_field(tmp_path):
    text = BASE + '[planner]\nkind = "rrt-connect"\n'
    with pytest.raises(ConfigError, match=r"\[planner\] field 'kind': must be one of thesis-single"):
        load_drift_scenario(_write(tmp_path, text))
