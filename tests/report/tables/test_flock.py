"""Flock tables: content, units in headers, no thesis columns beside another scenario, 100 columns."""

import dataclasses

import numpy as np
import pytest
from rich.console import Console

from oceanloc.config.flock import load_flock_scenario
from oceanloc.estimation.time_delay import estimate_recording_delay
from oceanloc.io.wav import example_recordings
from oceanloc.planning.dop import hdop_map, optimize_placement
from oceanloc.report.tables import flock as tables
from oceanloc.reproduce.dillard_filters import reproduce_dillard_filters
from oceanloc.reproduce.dillard_lab_tdoa import reproduce_dillard_lab_tdoa


def _render(table) -> str:
    console = Console(record=True, width=100)
    console.print(table)
    return console.export_text()


def _fits(text: str) -> None:
    assert max(len(line) for line in text.splitlines()) <= 100
    assert "…" not in text  # nothing truncated


@pytest.fixture(scope="module")
def filters():
    sc = load_flock_scenario("dillard-filters").with_overrides(duration_s=1.0)
    return reproduce_dillard_filters(sc, runs=2)


def test_table_2_sets_the_thesis_beside_ours(filters):
    text = _render(tables.table_2(filters))
    _fits(text)
    assert "Table 2: bearing-only tracking MSE" in text
    for value in ("765.7431", "97.6823", "668.0608", "3.5440"):
        assert value in text
    assert "(m/s)²" in text and "m²" in text and "± SE (paired)" in text
    rows = [line for line in text.splitlines() if line.startswith("│ ")]
    assert [r.split("│")[1].strip() for r in rows] == ["X", "Y", "U", "V"]


def test_stats_table_units_and_variants(filters):
    text = _render(tables.filter_stats_table(filters))
    _fits(text)
    for header in ("pos. MSE (m²)", "NEES (1)", "RMSE/√PCRLB", "run (s)", "thesis (s)"):
        assert header in text
    assert text.count("EKF ctrl") == 1 and "constant-acceleration" in text and "0.85" in text
    # The thesis' R is 1000 x too small for its noise: every epoch is outside the gate, every run diverges.
    assert "NIS gate off; gated epochs (%), diverged runs: ekf 0.00 2/2, ukf 0.00 2/2" in text


def test_another_scenario_has_no_thesis_columns():
    sc = dataclasses.replace(load_flock_scenario("dillard-filters"), name="[my] ring", duration_s=1.0)
    res = reproduce_dillard_filters(sc, runs=2, controls=False)
    text = _render(tables.table_2(res)) + _render(tables.filter_stats_table(res))
    _fits(text)
    assert "[my] ring: bearing-only tracking MSE over 2 runs (1 s)" in text  # escaped, not markup
    assert "thesis" not in text and "Table 2" not in text


def test_lab_table():
    sc = load_flock_scenario("dillard-lab-tdoa").with_overrides(duration_s=3.0)
    text = _render(tables.lab_table(reproduce_dillard_lab_tdoa(sc, runs=2)))
    _fits(text)
    assert "thesis (1 run) vs oceanloc (2 runs)" in text
    assert "peaks coincide (Fig. 67)" in text and "0.21" in text and "│ ms " in text
    assert "NIS gate off: 0.0 epochs gated per run;" in text and "/2 runs diverged" in text


def test_dop_tables_state_units_and_bearings_from_north():
    dop = hdop_map(
        [[100.0, 0.0]],
        [0.0, 0.0],
        "range",
        x_range_m=(-50, 50),
        y_range_m=(-50, 50),
        resolution_m=10,
        sigma=2.0,
    )
    text = _render(tables.hdop_map_table(dop))
    assert "minimum HDOP (m)" in text and "singular cells (%)" in text
    res = optimize_placement(
        2,
        "range",
        min_standoff_m=50,
        max_standoff_m=60,
        fixed_nodes_m=[[0.0, 100.0]],
        starts=2,
        rng=np.random.default_rng(0),
    )
    text = _render(tables.placement_table(res))
    _fits(text)
    assert "bearing (° cw from N)" in text
    fixed = next(line for line in text.splitlines() if "fixed 1" in line)
    assert fixed.split("│")[-2].strip() == "0.0" and "100.00" in fixed
    assert "m; even ring" not in tables.placement_summary(res)  # sigma 1 for ranges: dimensionless
    assert tables.placement_summary(res).startswith(f"HDOP {res.hdop:.5g} 1;")


def test_delay_table():
    text = _render(tables.delay_table(estimate_recording_delay(*example_recordings())))
    _fits(text)
    assert "delay, arrival at A minus at B (s)" in text and "0.00123" in text
    assert "B (hydrophone_b.wav)" in text and "sample rate (Hz)" in text
