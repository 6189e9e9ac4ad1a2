import functools
import re

import pytest
from rich.console import Console

from oceanloc.config.survey import load_survey_scenario
from oceanloc.evaluation.survey import single_survey, survey_monte_carlo
from oceanloc.report.tables import survey as tables
from oceanloc.reproduce.survey_tables import TableRow, Verdict, table_verdicts


def _render(renderable) -> str:
    console = Console(record=True, width=100)
    console.print(renderable)
    return console.export_text()


@functools.cache
def _mc():
    scen = load_survey_scenario("garcia2019-m4").with_overrides(planner="k1", epochs=8)
    return survey_monte_carlo(scen, 4, seed=3)


def test_monte_carlo_table_has_units_and_fits_100_columns():
    text = _render(tables.monte_carlo_table(_mc()))
    assert all(len(line) <= 100 for line in text.splitlines())
    for unit in ("m=1", "m=4", "(m)", "(nats)", "(%)", "chi2(12)"):
        assert unit in text
    assert "planner k = 1" in text
    assert [int(line.split("│")[1]) for line in text.splitlines() if re.match(r"│\s+\d+ │", line)] == [
        3,
        7,
        8,
    ]


def test_monte_carlo_summary_reports_the_consistency_at_the_last_epoch():
    line = tables.monte_carlo_summary(_mc())
    assert "NEES at n = 8" in line and "above the 95 % quantile 21.03" in line


def test_single_survey_tables_print_truth_and_estimates():
    survey = single_survey(load_survey_scenario("garcia2019-m1").with_overrides(epochs=5), seed=2)
    text = _render(tables.single_survey_table(survey))
    assert all(len(line) <= 100 for line in text.splitlines())
    assert "17.00, 15.00, -6.00" in text and "sd U (m)" in text and "@ az" in text
    assert "clockwise from north" in text
    epochs = " ".join(_render(tables.single_survey_epoch_table(survey)).split())
    assert "log det Y_n (nats)" in epochs


def _row(planner, z, ours, paper):
    return TableRow(
        epoch=3, k=0, planner=planner, rmse_m=1.0, logdet_mean=ours, logdet_std=1.0, paper_rmse_m=1.0,
        paper_logdet_mean=paper, paper_logdet_std=1.0, logdet_z=z,
    )  # fmt: skip


def test_verdicts_never_claim_success_beside_a_failing_row():
    rows = {"5.3": [_row("random disk", 0.5, 3.6, 3.61), _row("greedy", 33.6, 5.43, 4.56)]}
    verdicts = table_verdicts(rows)
    assert [(v.item, v.status) for v in verdicts] == [
        ("Table 5.3, random disk", "reproduces"),
        ("Table 5.3, greedy", "does not reproduce"),
    ]
    assert "5.43 vs 4.56 (z = +33.6)" in verdicts[1].evidence
    line = tables.verdict_line(verdicts)
    assert line.startswith("[red]Does not reproduce") and "Table 5.3, greedy" in line
    text = _render(tables.verdicts_table(verdicts, "v"))
    assert "does not reproduce" in text and "reproduces" in text


@pytest.mark.parametrize(
    ("z", "ours", "grade"), [(2.9, 50.0, "agrees"), (8.0, 49.5, "close"), (8.0, 45.0, "differs")]
)
def test_row_agreement_grades(z, ours, grade):
    assert _row("k = 1", z, ours, 48.71).agreement == grade


def test_reproduction_table_names_planners_and_escapes_them():
    rows = [_row("[b]x", 1.0, 3.6, 3.61)]
    text = _render(tables.reproduction_table(rows, "t"))
    assert "[b]x" in text and "(nats)" in text and "z (1)" in text


def test_verdict_line_when_everything_reproduces():
    ok = [Verdict(item="Fig. 5.3", status="reproduces", evidence="")]
    assert "Every table and figure above reproduces" in tables.verdict_line(ok)
