"""Tables of a GNATSS-format array solution: units in every numeric header, ids escaped, 100 columns."""

import dataclasses

from rich.console import Console

from oceanloc.field.gnatss_input import gnatss_example_config, load_gnatss_input, localize_gnatss_input
from oceanloc.report.tables.field import gnatss_geodetic_table, gnatss_positions_table, gnatss_summary_lines


def _render(table) -> str:
    console = Console(record=True, width=100)
    console.print(table)
    return console.export_text()


def test_array_tables_have_units_and_fit_100_columns():
    loc = localize_gnatss_input(load_gnatss_input(gnatss_example_config()), method="gnatss")
    loc = dataclasses.replace(loc, ids=("[b]SYN1-1", "SYN1-2", "SYN1-3"))
    text = _render(gnatss_positions_table(loc))
    for header in ("E m", "N m", "U m", "1σ E/N/U mm", "replies used"):
        assert header in text
    assert "[b]SYN1-1" in text  # user text printed as written, not as markup
    assert "-1526.5" in text
    geo = _render(gnatss_geodetic_table(loc))
    for header in ("latitude °", "longitude °", "height m"):
        assert header in geo
    assert "45.3046" in geo and "-124.9738" in geo
    assert all(len(line) <= 100 for line in (text + geo).splitlines())
    lines = gnatss_summary_lines(loc)
    assert lines[0].startswith("597 of 600 replies used; excluded: deleted")
    assert lines[1] == "converged: yes after 3 iterations; sound speed 1481.207/1481.276/1481.156 m/s"
