import dataclasses

import pytest
from rich.console import Console

from oceanloc.estimation.gnssa import GnssaOptions
from oceanloc.field.gnssa_surveys import process_gnssa_surveys
from oceanloc.io.gnssa import lajolla_paths
from oceanloc.report.tables import field as tables


def _render(table) -> str:
    console = Console(record=True, width=100)
    console.print(table)
    return console.export_text()


@pytest.fixture(scope="module")
def two_surveys():
    return process_gnssa_surveys(lajolla_paths()[3:5], GnssaOptions())


def test_gnssa_tables_state_units_fit_100_columns_and_escape_names(two_surveys):
    evil = dataclasses.replace(two_surveys.results[0], name="[/x][bold]mine")
    texts = [_render(t) for t in tables.gnssa_tables([evil, two_surveys.results[1]])]
    positions, acoustic, geodetic = texts
    for header in ("E m", "N m", "U m", "1σ E/N/U cm", "RMS cm"):
        assert header in positions
    for header in ("c m/s", "dc/dE, dc/dN m/s/km", "κ ppm", "σ path cm", "β cm/tan"):
        assert header in acoustic
    assert "latitude deg" in geodetic and "2022-03-21T" in geodetic
    assert "[/x][bold]mine" in positions  # escaped: printed as written, no markup error
    assert all(len(line) <= 100 for text in texts for line in text.splitlines())
    assert "…" not in "".join(texts)  # no column squeezed


def test_spread_table_has_units_targets_and_the_velocity_line(two_surveys):
    text = _render(tables.gnssa_spread_table(two_surveys.spread, [0.025, 0.035, 0.06]))
    assert "Spread across 2 surveys, moved to" in " ".join(text.split())
    assert "ITRF2014 PCFC: E -44.0, N +26.0 mm/yr" in " ".join(text.split())
    for header in ("std cm", "RMS σ cm", "target cm", "met"):
        assert header in text
    assert [line.split()[0] for line in text.splitlines() if line.split()[:1] in (["E"], ["N"], ["U"])] == [
        "E",
        "N",
        "U",
    ]
    lines = tables.gnssa_spread_lines(two_surveys)
    assert lines[0] == "site velocity (auto): header Lat0 32.8668, Lon0 -117.2701 is on PCFC"
    assert lines[1].startswith("as surveyed (no site velocity): std E/N/U")
