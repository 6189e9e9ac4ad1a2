"""Drift scenarios in time: tidal, linear and Rankine currents, objective, deadline, propulsion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from oceanloc.config.drift import load_drift_scenario, problem_from_scenario
from oceanloc.errors import ConfigError
from oceanloc.models.currents import LinearCurrent, RankineVortexCurrent, TidalCurrent, is_steady

HEAD = """
[scenario]
name = "t"
[map]
bounds_m = [0.0, 10000.0, 0.0, 8000.0]
[route]
start_m = [1000.0, 1000.0]
goal_m = [9000.0, 7000.0]
"""


def _load(tmp_path, currents: str, extra: str = ""):
    path = tmp_path / "s.toml"
    path.write_text(HEAD + "[currents]\n" + currents + "\n" + extra)
    return load_drift_scenario(path)


def test_tidal_linear_and_rankine_currents(tmp_path):
    sc = _load(
        tmp_path,
        'kind = "tidal"\nmean_mps = [0.1, 0.0]\namplitude_mps = [0.3, 0.2]\nperiod_h = 6.0\nphase_deg = 90.0',
    )
    assert isinstance(sc.current, TidalCurrent) and not is_steady(sc.current)
    assert sc.current.velocity_xy(0.0, 0.0, 0.0) == pytest.approx((0.4, 0.2))
    sc = _load(tmp_path, 'kind = "linear"\nmatrix_per_s = [[0.0, 1e-4], [0.0, 0.0]]')
    assert isinstance(sc.current, LinearCurrent) and is_steady(sc.current)
    assert sc.current.velocity_xy(0.0, 5000.0) == pytest.approx((0.5, 0.0))
    sc = _load(
        tmp_path,
        'kind = "rankine"\ncentre_m = [5000.0, 4000.0]\ncore_radius_m = 2000.0\npeak_speed_mps = 0.6\n'
        "pulse = 0.4\nperiod_h = 6.0\nbackground_mps = [0.1, 0.0]",
    )
    assert isinstance(sc.current, RankineVortexCurrent) and not is_steady(sc.current)
    # On the core's edge, east of the centre: north at the peak speed plus the background.
    assert sc.current.velocity_xy(7000.0, 4000.0, 0.0) == pytest.approx((0.1, 0.6))


def test_objective_deadline_and_propulsion(tmp_path):
    sc = _load(
        tmp_path,
        'kind = "uniform"\nvelocity_mps = [0.2, 0.0]',
        '[planner]\nobjective = "time"\ndeadline_h = 6.0\n'
        '[vehicle]\npropulsion = "water"\nflight_speed_kn = 3.0',
    )
    p = problem_from_scenario(sc)
    assert p.objective == "time" and p.max_duration_s == 6 * 3600.0 and p.propulsion == "water"
    assert p.max_leg_m is None  # a boat's legs are not hops
    assert p.deadline_s == p.t0_s + 6 * 3600.0
    assert math.isfinite(p.direct_flight_wh)


@pytest.mark.parametrize(
    ("currents", "extra", "message"),
    [
        ('kind = "tidal"', "", "[currents] field 'amplitude_mps': is required"),
        ('kind = "tidal"\namplitude_mps = [20.0, 0.0]', "", "[currents] field 'amplitude_mps': components"),
        ('kind = "linear"\nmatrix_per_s = [1.0, 2.0]', "", "[currents] field 'matrix_per_s': must be"),
        ('kind = "linear"\nmatrix_per_s = [[0.0, 5.0], [0.0, 0.0]]', "", "within [-1, 1] 1/s"),
        ('kind = "rankine"\ncore_radius_m = 0.0', "", "[currents] field 'core_radius_m'"),
        (
            'kind = "uniform"\nvelocity_mps = [0.1, 0.0]',
            '[planner]\nobjective = "fastest"',
            "[planner] field 'objective'",
        ),
        (
            'kind = "uniform"\nvelocity_mps = [0.1, 0.0]',
            "[planner]\ndeadline_h = 48.0",
            "beyond the planning horizon",
        ),
        (
            'kind = "uniform"\nvelocity_mps = [0.1, 0.0]',
            '[vehicle]\npropulsion = "rocket"',
            "[vehicle] field 'propulsion'",
        ),
    ],
)
def test_errors_name_the_table_and_field(tmp_path, currents, extra, message):
    with pytest.raises(ConfigError) as err:
        _load(tmp_path, currents, extra)
    assert message in str(err.value) and "s.toml" in str(err.value)


def test_rankine_velocity_is_solid_body_inside_and_irrotational_outside():
    f = RankineVortexCurrent(core_radius_m=1000.0, peak_speed_mps=0.5)
    r = np.array([250.0, 500.0, 1000.0, 2000.0, 4000.0])
    _, v = f.velocity_xy(r, np.zeros_like(r), 0.0)
    np.testing.assert_allclose(v, [0.125, 0.25, 0.5, 0.25, 0.125])
