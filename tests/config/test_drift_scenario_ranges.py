"""Every drift scenario field has a physical range (issue 11, section 2): hostile values are one-line
errors naming the file, the table, the field and the allowed range, never NaN results or tracebacks."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from oceanloc.config.drift import load_drift_scenario, problem_from_scenario
from oceanloc.errors import ConfigError
from oceanloc.planning.drift_rrt.lattice import LatticeOptions, lattice_memory_bytes, plan_lattice
from oceanloc.planning.drift_rrt.planner import make_planner
from oceanloc.planning.drift_rrt.problem import PlanStatus

TABLES = {
    "scenario": 'name = "hostile"',
    "currents": 'kind = "uniform"\nvelocity_mps = [0.2, 0.0]',
    "drift": 'integrator = "euler"\ndt_s = 60.0\nhorizon_h = 4.0',
    "map": "bounds_m = [0.0, 4000.0, 0.0, 3000.0]",
    "route": "start_m = [500.0, 500.0]\ngoal_m = [3500.0, 2500.0]",
    "vehicle": 'flight_legs = "any"',
    "hdop": "others_m = [[0.0, 0.0], [4000.0, 0.0]]\ntarget_m = [3600.0, 2600.0]",
    "planner": 'kind = "oceanloc"',
    "following": "runs = 10",
}


def scenario_text(**changes: str) -> str:
    """The base scenario with ``table="key = value"`` lines replacing (same key) or extending a table."""
    parts = []
    for name, body in TABLES.items():
        lines = dict(line.split(" = ", 1) for line in body.splitlines())
        for line in changes.get(name, "").splitlines():
            key, value = line.split(" = ", 1)
            lines[key] = value
        parts.append(f"[{name}]\n" + "\n".join(f"{k} = {v}" for k, v in lines.items()))
    return "\n\n".join(parts) + "\n"


CASES = [
    # (id, changes, substrings of the message)
    (
        "current 1e30 m/s",
        {"currents": "velocity_mps = [1e30, 0.0]"},
        ["[currents] field 'velocity_mps'", "[-10, 10] m/s"],
    ),
    (
        "gyre amplitude 1e30",
        {
            "currents": 'kind = "double-gyre"\namplitude_mps = 1e30',
            "map": "bounds_m = [0.0, 10000.0, 0.0, 5000.0]",
        },
        ["[currents] field 'amplitude_mps'", "<= 10.0"],
    ),
    ("gyre period 1e-9 h", {"currents": 'kind = "double-gyre"\nperiod_h = 1e-9'}, ["'period_h'", ">= 0.01"]),
    (
        "flight speed 1e-300",
        {"vehicle": "flight_speed_kn = 1e-300"},
        ["[vehicle] field 'flight_speed_kn'", ">= 0.5"],
    ),
    ("flight power 1e300", {"vehicle": "flight_power_w = 1e300"}, ["'flight_power_w'", "<= 100000.0"]),
    ("nautical mile 1 m", {"vehicle": "nautical_mile_m = 1.0"}, ["'nautical_mile_m'", ">= 1000.0"]),
    ("hop 1e-9 s", {"vehicle": "max_flight_time_s = 1e-9"}, ["'max_flight_time_s'", ">= 1.0"]),
    (
        "start equal to goal",
        {"route": "goal_m = [500.0, 500.0]"},
        ["[route] field 'goal_m'", "inside the goal disk"],
    ),
    ("goal tolerance 1e300", {"route": "goal_tolerance_m = 1e300"}, ["'goal_tolerance_m'", "<= 1000000.0"]),
    ("start 1e300", {"route": "start_m = [1e300, 0.0]"}, ["[route] field 'start_m'", "[-1e+07, 1e+07] m"]),
    ("start time 1e300", {"route": "start_time_s = 1e300"}, ["'start_time_s'", "<= 10000000000.0"]),
    (
        "bounds 1e300",
        {"map": "bounds_m = [-1e300, 1e300, -1e300, 1e300]"},
        ["[map] field 'bounds_m'", "[-1e+07, 1e+07] m"],
    ),
    (
        "rectangle 1e300",
        {"map": "rectangles = [{x_m = [0.0, 1e300], y_m = [0.0, 1.0]}]"},
        ["[map.rectangles[0]] field 'x_m'", "[-1e+07, 1e+07] m"],
    ),
    ("inflation 1e300", {"map": "inflation_m = 1e300"}, ["'inflation_m'", "<= 1000000.0"]),
    ("step 1e-3 s", {"drift": "dt_s = 1e-3"}, ["[drift] field 'dt_s'", ">= 1.0"]),
    ("one-year horizon", {"drift": "horizon_h = 8760.0"}, ["[drift] field 'horizon_h'", "<= 720.0"]),
    (
        "a month at 1 s",
        {"drift": "dt_s = 1.0\nhorizon_h = 720.0"},
        ["[drift] field 'horizon_h'", "at most 200000", "raise dt_s"],
    ),
    (
        "map too large for memory",
        {"map": "bounds_m = [-1e6, 1e6, -1e6, 1e6]"},
        ["GiB", "(at most 4)", "shrink [map] bounds_m", "raise [drift] dt_s"],
    ),
    (
        "hdop far away",
        {"hdop": "others_m = [[1e300, 0.0]]"},
        ["[hdop] field 'others_m'", "[-1e+07, 1e+07] m"],
    ),
    (
        "time weight 1e300",
        {"planner": "time_weight_wh_per_h = 1e300"},
        ["'time_weight_wh_per_h'", "<= 10000.0"],
    ),
    ("1e9 runs", {"following": "runs = 1000000000"}, ["[following] field 'runs'", "<= 100000"]),
    ("noise 1e30", {"following": "noise_mps = 1e30"}, ["[following] field 'noise_mps'", "<= 10.0"]),
    (
        "correlation 1e-300",
        {"following": "noise_correlation_s = 1e-300"},
        ["'noise_correlation_s'", ">= 1.0"],
    ),
]


@pytest.mark.parametrize(("changes", "reasons"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_hostile_values_are_errors_naming_file_table_field_and_range(tmp_path, changes, reasons):
    path = tmp_path / "hostile.toml"
    path.write_text(scenario_text(**changes))
    with pytest.raises(ConfigError) as err:
        load_drift_scenario(path)
    message = str(err.value)
    assert message.startswith(str(path)), message
    assert "\n" not in message
    for reason in reasons:
        assert reason in message, message


def test_the_base_scenario_loads_and_plans(tmp_path):
    path = tmp_path / "base.toml"
    path.write_text(scenario_text())
    problem = problem_from_scenario(load_drift_scenario(path))
    result = make_planner("oceanloc")(problem, np.random.default_rng(0))
    assert result.status is PlanStatus.EXACT and np.isfinite(result.flight_energy_wh)


def test_toml_nested_500_deep_is_an_error_naming_the_file(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text(scenario_text() + "deep = " + "[" * 500 + "]" * 500 + "\n")
    with pytest.raises(ConfigError, match="nested too deeply") as err:
        load_drift_scenario(path)
    assert str(path) in str(err.value)


def test_netcdf_currents_of_1e30_are_an_error(tmp_path):
    xr = pytest.importorskip("xarray")
    x = np.arange(0.0, 4001.0, 500.0)
    y = np.arange(0.0, 3001.0, 500.0)
    u = np.full((y.size, x.size), 0.2, dtype=np.float32)
    u[3, 3] = 1e30
    ms = {"units": "m s-1"}
    xr.Dataset(
        {
            "uo": (("y", "x"), u, {"standard_name": "eastward_sea_water_velocity", **ms}),
            "vo": (("y", "x"), np.zeros_like(u), {"standard_name": "northward_sea_water_velocity", **ms}),
        },
        coords={
            "y": ("y", y, {"standard_name": "projection_y_coordinate", "units": "m", "axis": "Y"}),
            "x": ("x", x, {"standard_name": "projection_x_coordinate", "units": "m", "axis": "X"}),
        },
    ).to_netcdf(tmp_path / "fast.nc")
    path = tmp_path / "fast.toml"
    path.write_text(scenario_text(currents='kind = "netcdf"\npath = "fast.nc"'))
    with pytest.raises(ConfigError) as err:
        load_drift_scenario(path)
    assert "[currents] field 'path'" in str(err.value) and "fast.nc holds currents up to 1e+30 m/s" in str(
        err.value
    )


def test_lattice_memory_is_checked_before_allocating():
    """A problem built in code (no loader) gets the same estimate: 1e300 m maps give inf, not MemoryError."""
    from tests.planning.drift_fixtures import uniform_problem

    problem = uniform_problem()
    total, nodes, samples = lattice_memory_bytes(problem, LatticeOptions())
    assert nodes == 16 * 11 and samples == 4 * 60 / 4 + 2
    assert total == pytest.approx(88 * samples * (nodes + 1) + 16 * nodes * (nodes + 1))
    with pytest.raises(ConfigError, match=r"would need about .* GiB \(at most 1e-05\)"):
        plan_lattice(problem, np.random.default_rng(0), None, LatticeOptions(max_memory_gib=1e-5))


@pytest.mark.parametrize("name", ["oceanloc", "thesis-single"])
def test_planners_given_a_start_inside_the_goal_disk_stay(name):
    from tests.planning.drift_fixtures import uniform_problem

    result = make_planner(name, 1000)(uniform_problem(goal=(0.0, 0.0)), np.random.default_rng(0))
    assert result.status is PlanStatus.EXACT and result.flight_energy_wh == 0.0
    assert result.path.n_points == 1 and "nothing to plan" in result.message
    assert result.to_record()["saving"] is None


SUBPROCESS_CASES = [
    ({"currents": "velocity_mps = [1e30, 0.0]"}, "[currents] field 'velocity_mps'"),
    ({"drift": "dt_s = 1e-3"}, "[drift] field 'dt_s': must be >= 1.0"),
    ({"map": "bounds_m = [-1e6, 1e6, -1e6, 1e6]"}, "shrink [map] bounds_m"),
    ({"vehicle": "flight_speed_kn = 1e-300"}, "[vehicle] field 'flight_speed_kn'"),
    ({"route": "goal_m = [500.0, 500.0]"}, "inside the goal disk"),
    ({"__deep__": ""}, "nested too deeply"),
]


@pytest.mark.parametrize(("changes", "reason"), SUBPROCESS_CASES)
def test_drift_plan_command_exits_2_with_one_line(tmp_path, changes, reason):
    path = tmp_path / "hostile.toml"
    if "__deep__" in changes:
        path.write_text(scenario_text() + "deep = " + "[" * 500 + "]" * 500 + "\n")
    else:
        path.write_text(scenario_text(**changes))
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "oceanloc",
            "drift-plan",
            "--scenario",
            str(path),
            "--out",
            str(tmp_path / "o"),
        ],
        capture_output=True,
        text=True,
        env=os.environ,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, proc.stderr
    assert reason in lines[0]


FUZZ_FIELDS = [
    ("currents", "velocity_mps = [{v}, 0.0]"),
    ("drift", "dt_s = {v}"),
    ("drift", "horizon_h = {v}"),
    ("map", "bounds_m = [0.0, {v}, 0.0, 3000.0]"),
    ("map", "inflation_m = {v}"),
    ("route", "start_m = [{v}, 500.0]"),
    ("route", "goal_m = [3500.0, {v}]"),
    ("route", "goal_tolerance_m = {v}"),
    ("route", "start_time_s = {v}"),
    ("vehicle", "flight_power_w = {v}"),
    ("vehicle", "flight_speed_kn = {v}"),
    ("vehicle", "max_flight_time_s = {v}"),
    ("vehicle", "nautical_mile_m = {v}"),
    ("vehicle", "solar_wh_per_day = {v}"),
    ("hdop", "target_m = [{v}, 2600.0]"),
    ("planner", "time_weight_wh_per_h = {v}"),
    ("following", "watch_circle_m = {v}"),
    ("following", "current_scale = {v}"),
    ("following", "stray_m = {v}"),
]
FUZZ_VALUES = [
    "0.0",
    "-1.0",
    "1e-300",
    "5e-324",
    "1e300",
    "-1e300",
    "nan",
    "inf",
    "-inf",
    "3.0",
    "2500.0",
    "1e6",
]


def test_fuzzed_field_values_are_errors_or_finite_plans(tmp_path):
    """48 of the 228 (field, value) pairs, drawn with a fixed seed: each either is a ConfigError naming the
    file and a field, or loads and plans with a finite energy (never NaN, inf or a traceback)."""
    rng = np.random.default_rng(11)
    pairs = [(t, f, v) for t, f in FUZZ_FIELDS for v in FUZZ_VALUES]
    picks = rng.choice(len(pairs), size=48, replace=False)
    accepted = 0
    for i in picks:
        table, template, value = pairs[int(i)]
        path = tmp_path / f"fuzz{i}.toml"
        path.write_text(scenario_text(**{table: template.format(v=value)}))
        try:
            scenario = load_drift_scenario(path)
        except ConfigError as exc:
            # The field itself, or the one it conflicts with (a start outside shrunken bounds).
            message = str(exc)
            assert message.startswith(str(path)) and " field '" in message and "\n" not in message, message
            continue
        accepted += 1
        result = make_planner("oceanloc")(problem_from_scenario(scenario), np.random.default_rng(0))
        assert result.status is PlanStatus.EXACT, (template, value, result.message)
        assert (
            np.isfinite(result.flight_energy_wh) and result.flight_energy_wh <= result.direct_flight_wh + 1e-9
        )
        assert np.all(np.isfinite(result.path.points_m)) and np.all(np.isfinite(result.path.times_s))
    assert 0 < accepted < 48
