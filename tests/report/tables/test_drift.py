import pytest
from rich.console import Console

from oceanloc.config.drift import load_drift_scenario
from oceanloc.evaluation.drift import plan_scenario
from oceanloc.evaluation.path_following import drift_follow_study, drift_swap_study
from oceanloc.report.tables.drift import (
    dillard_fields_table,
    dillard_notes,
    dillard_table,
    following_table,
    plan_table,
    swap_notes,
    swap_table,
)
from oceanloc.reproduce.dillard_drrt import reproduce_dillard_drrt


def _render(*items) -> str:
    console = Console(width=100, record=True, file=open("/dev/null", "w"))  # noqa: SIM115
    for item in items:
        console.print(item, highlight=False)
    text = console.export_text()
    assert max(len(line) for line in text.splitlines()) <= 100
    return text


def test_plan_table_states_units():
    text = _render(plan_table(plan_scenario(load_drift_scenario("dillard-drift-continuous"))))
    for label in ("flight energy (Wh)", "start -> goal (m)", "duration, drift (h)", "compute (ms)", "1852"):
        assert label in text
    assert "exact" in text


def test_following_and_swap_tables():
    text = _render(following_table(drift_follow_study(load_drift_scenario("dillard-drift-fixed"), runs=1)))
    assert (
        "arrival rate (%)" in text
        and "watch circle, stray (m)" in text
        and "planned flight energy (Wh)" in text
    )
    swap = drift_swap_study(load_drift_scenario("dillard-drift-swap"))
    text = _render(swap_table(swap), *swap_notes(swap))
    for label in ("flight energy (Wh)", "saving (%)", "duration (h)", "followed: flown (Wh)", "drifter 2"):
        assert label in text
    # Both drifters on one line per quantity.
    rows = [line for line in text.splitlines() if line.startswith("│ plan status")]
    assert len(rows) == 1 and rows[0].count("exact") == 2 and "closest approach" in text


@pytest.fixture(scope="module")
def small_report():
    return reproduce_dillard_drrt(runs=2, seed=1, fields=1, iterations=500, reference_spacing_m=400.0)


def test_dillard_tables_fit_100_columns_without_wrapping_planner_names(small_report):
    text = _render(
        dillard_table(small_report), *dillard_notes(small_report), dillard_fields_table(small_report)
    )
    for header in ("success (%)", "energy (Wh)", "saving (%)", "compute (ms)", "worst field", "(field mean)"):
        assert header in text
    # Full planner names on one line in both tables, and the thesis' Table 4 row under each DR-RRT* mode.
    assert text.count("thesis-optimality-seeking ") >= 2 and text.count("thesis Table 4") >= 2
    assert "38.69 +- 6.81" in text and "4964 +- 18" in text
    assert "nan" not in text
