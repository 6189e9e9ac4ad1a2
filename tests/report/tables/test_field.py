import dataclasses

import numpy as np
import pytest
from rich.console import Console

from oceanloc.estimation.gnssa import GnssaOptions
from oceanloc.field.gnssa_surveys import process_gnssa_surveys
from oceanloc.io.gnssa import lajolla_paths
from oceanloc.report.tables import field as tables
from oceanloc.report.tables import survey_journal as journal_tables


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


def test_log_tables_fit_100_columns_with_units_and_the_origin(tmp_path):
    from oceanloc.field.range_logs import localize_log_files, range_noise_files
    from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

    logs = simulate_pier_logs(tmp_path, PierLogSettings(duration_s=600.0), np.random.default_rng(5), seed=5)
    loc = localize_log_files(logs.nmea_path, logs.ranges_path, truth=logs.truth_path)
    text = _render(tables.beacons_table(loc))
    assert "ENU from" in text and "(earliest fix)" in text
    for header in ("E m", "N m", "U m", "1σ E/N/U m", "lat deg", "lon deg", "RMS m", "error m"):
        assert header in text
    assert all(len(line) <= 100 for line in text.splitlines()) and "…" not in text
    truth = _render(tables.truth_table(logs.truth))
    assert "True beacons, ENU from" in " ".join(truth.split()) and "h m" in truth
    noise = range_noise_files(logs.nmea_path, logs.ranges_path)
    text = _render(tables.range_noise_table(noise))
    for header in ("segment s", "range m", "σ mm", "± mm"):
        assert header in text
    assert "use it as --sigma-range" in tables.range_noise_line(noise)


def test_journal_estimates_table_shows_the_trust_column(tmp_path):
    from oceanloc.field.survey.estimates import survey_estimates
    from oceanloc.field.survey.journal import Journal, append_gps_log, append_range_log
    from oceanloc.field.survey.settings import JournalSettings
    from oceanloc.io.nmea import read_nmea
    from oceanloc.io.usbl import read_usbl
    from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

    settings = JournalSettings(beacons=(1, 2))
    logs = simulate_pier_logs(tmp_path, PierLogSettings(duration_s=600.0), np.random.default_rng(3))
    with Journal.start(tmp_path / "s.db", settings.to_meta()) as j:
        append_gps_log(j, read_nmea(logs.nmea_path), logs.nmea_path)
        append_range_log(j, read_usbl(logs.ranges_path, beacons=(1, 2)), logs.ranges_path)
        records = j.records()
    est = survey_estimates(records, settings)
    untrusted = dataclasses.replace(est, trusted=np.array([True, False]), trust_messages=("ok", "bent"))
    text = _render(journal_tables.journal_estimates_table(untrusted))
    rows = [line for line in text.splitlines() if line.strip().startswith(("1 ", "2 "))]
    assert "!" not in rows[0] and rows[1].count("!") == 1 and "not trusted" in text
    assert all(len(line) <= 100 for line in text.splitlines())
    lines = journal_tables.journal_range_lines(untrusted)
    assert any(line.startswith("beacon 2: bent (linearity ") for line in lines)
    assert not any("bent" in line or "ok" in line for line in journal_tables.journal_range_lines(est))


def test_waypoint_line_names_beacons_whose_ellipse_is_not_trusted():
    from oceanloc.field.survey.estimates import Waypoint
    from oceanloc.planning.status import PlanStatus

    w = Waypoint(
        planner="k1",
        from_t_unix_s=0.0,
        from_enu_m=np.zeros(3),
        yaw_rad=0.0,
        heading_source="HDT",
        next_enu_m=np.ones(3),
        next_geodetic=np.array([32.7, -117.2, 0.0]),
        next_heading_deg=10.0,
        distance_m=1.4,
        bearing_deg=45.0,
        waypoints_enu_m=np.ones((1, 3)),
        waypoints_geodetic=np.array([[32.7, -117.2, 0.0]]),
        yaw_rates_rad_s=None,
        objective_nats=1.0,
        beacons=np.array([1, 2]),
        status=PlanStatus.EXACT,
    )
    assert "not trusted" not in journal_tables.waypoint_line(w)
    flagged = dataclasses.replace(w, untrusted_beacons=np.array([2]))
    assert journal_tables.waypoint_line(flagged).endswith(
        "(ellipse of beacon 2 not trusted yet: planned on its linearized covariance)"
    )
    assert flagged.to_record()["untrusted_beacons"] == [2]
