import math

import pytest

from oceanloc.errors import ConfigError
from oceanloc.models.energy import EnergyBudget, thesis_budget


def test_table1_rows():
    rows = {name: (p, h, e) for name, p, h, e in EnergyBudget().table1()}
    assert rows["base"] == (5.0, 24.0, 120.0)
    assert rows["sensing & comms"] == (10.0, 6.0, 60.0)
    assert rows["flight"][2] == pytest.approx(220.0)
    assert rows["flight"][1] == pytest.approx(1.1)
    assert rows["solar (income)"][2] == 400.0
    assert EnergyBudget().daily_flight_budget_wh() == pytest.approx(220.0)


def test_direct_flight_in_both_conventions():
    start, goal = (-4000.0, 4000.0), (3000.0, -3000.0)
    d = math.hypot(7000.0, 7000.0)
    # Thesis: 200 W * d / (20 kn * 2000 m) = 49.5 Wh; international: 200 * d / (20 * 1852).
    assert float(thesis_budget().direct_flight_wh(start, goal)) == pytest.approx(200 * d / 40000.0)
    assert float(thesis_budget().direct_flight_wh(start, goal)) == pytest.approx(49.497, abs=1e-3)
    assert float(EnergyBudget().direct_flight_wh(start, goal)) == pytest.approx(200 * d / (20 * 1852.0))


def test_hop_length_and_speed():
    assert thesis_budget().max_hop_m == pytest.approx(20 * 2000 * 2 / 60)
    assert EnergyBudget().max_hop_m == pytest.approx(20 * 1852 * 2 / 60)
    assert EnergyBudget().flight_speed_mps == pytest.approx(20 * 1852 / 3600)


def test_solar_and_loads():
    b = EnergyBudget()
    assert float(b.solar_energy_wh(24 * 3600)) == pytest.approx(400.0)
    assert float(b.load_energy_wh(24 * 3600)) == pytest.approx(180.0)


def test_conventions_are_stated():
    assert "2000 m (thesis convention)" in thesis_budget().convention
    assert "1852 m (international)" in EnergyBudget().convention


def test_impossible_parameters_are_rejected():
    with pytest.raises(ConfigError, match="flight_speed_kn"):
        EnergyBudget(flight_speed_kn=0.0)
    with pytest.raises(ConfigError, match="sensing_hours_per_day"):
        EnergyBudget(sensing_hours_per_day=30.0)
