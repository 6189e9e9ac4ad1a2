"""Each report kind in real headless Chromium, network off: no error, no request, the layers in the DOM.

Chromium is driven through its DevTools protocol (:mod:`oceanloc.report.html.browser`) with a dead proxy
and CDP offline emulation; the page's own Content-Security-Policy forbids any request too, and a
blocked one would show as a console error. A screenshot of each page goes to the test's tmp dir.
"""

from __future__ import annotations

import json

import pytest

from oceanloc.report.html.browser import PLOTLY_READY, find_chromium, load_page
from oceanloc.report.html.page import render_html

pytest.importorskip("websocket", reason="websocket-client (PyPI) drives chromium's DevTools protocol")
pytestmark = pytest.mark.skipif(
    find_chromium() is None,
    reason="chromium not installed (Debian: apt-get install chromium): browser tests skipped",
)

DOM = """JSON.stringify({
  kind: document.body.dataset.reportKind,
  checks: document.querySelectorAll('#checks tr.check').length,
  failing: document.querySelectorAll('#checks tr.check.fail').length,
  plots: Object.fromEntries(Array.from(document.querySelectorAll('.plotly-graph-div')).map(d => [d.id, {
    names: d._fullData.map(t => t.name),
    points: d._fullData.map(t => (t.x || []).length),
    drawn: d.querySelectorAll('.scatterlayer .trace').length,
    markers: Array.from(d.querySelectorAll('.scatterlayer .trace')).map(
      g => g.querySelectorAll('path.point').length),
    paths: Array.from(d.querySelectorAll('.scatterlayer .trace path.js-line')).filter(
      p => (p.getAttribute('d') || '').length > 10).length}]))
})"""

# kind -> (ellipses on the map, check rows, a trace the map or first series must hold)
EXPECTED = {
    "journal": (2, 4, "GPS track"),
    "survey": (4, 1, "measurement sites (in order)"),
    "gnssa": (5, 6, "survey positions (in time order)"),
    "gnssa-array": (3, 2, "array centre (estimated)"),
    "drift": (0, 3, "flight legs"),
    "montecarlo": (0, 3, None),
    "reproduction": (0, None, None),
}


@pytest.mark.parametrize("kind", list(EXPECTED))
def test_report_loads_offline_with_its_layers(sources, reports, kind, tmp_path):
    rep = reports[kind]
    page = tmp_path / f"{kind}.html"
    page.write_text(render_html(rep), encoding="utf-8")
    got = load_page(page, DOM, ready=PLOTLY_READY, timeout_s=30.0)
    (tmp_path / f"{kind}.png").write_bytes(got.screenshot_png)
    assert got.screenshot_png[:8] == b"\x89PNG\r\n\x1a\n" and len(got.screenshot_png) > 20_000
    assert got.console_errors == []
    assert got.outside_requests == [] and got.failed_requests == []
    dom = json.loads(got.value)
    assert dom["kind"] == kind
    ellipses, checks, layer = EXPECTED[kind]
    assert dom["checks"] == (len(rep.checks) if checks is None else checks)
    plots = dom["plots"]
    n_series = len(rep.series)
    assert sorted(plots) == sorted((["map"] if rep.map else []) + [f"series-{i}" for i in range(n_series)])
    for p in plots.values():  # every trace was drawn as SVG
        assert p["drawn"] == len(p["names"])
    if rep.map is not None:
        names = plots["map"]["names"]
        assert sum(n.startswith("95% ellipse") for n in names) == ellipses
        assert any(n.startswith(layer) for n in names)
        if kind == "journal":
            track = names.index("GPS track")
            assert plots["map"]["points"][track] == 600
            assert 600 in plots["map"]["markers"]  # one SVG marker per fix
        if ellipses:
            assert plots["map"]["paths"] >= ellipses


def test_gnssa_ping_residuals_load_offline(sources, tmp_path):
    from oceanloc.report.html.records import gnssa_report
    from tests.report.html.test_page import gnssa_with_pings

    rep = gnssa_report(gnssa_with_pings(sources))
    page = tmp_path / "gnssa-pings.html"
    page.write_text(render_html(rep), encoding="utf-8")
    got = load_page(page, DOM, ready=PLOTLY_READY, timeout_s=30.0)
    (tmp_path / "gnssa-pings.png").write_bytes(got.screenshot_png)
    assert got.console_errors == [] and got.outside_requests == [] and got.failed_requests == []
    pings = json.loads(got.value)["plots"][f"series-{len(rep.series) - 1}"]
    assert pings["names"][-2:] == ["excluded: elevation below 20 deg", "excluded: outlier"]
    assert pings["points"] == [18, 19, 1, 2] and pings["markers"] == [18, 19, 1, 2]


def test_markup_in_record_text_never_becomes_a_link(tmp_path):
    """A transponder id or file name holding ``<a href>`` once became a clickable link in a legend: plotly
    renders a subset of HTML in names and titles. Every label now reaches plotly escaped."""
    import numpy as np

    from oceanloc.report.html.model import Estimate, MapLayers, Report, Series

    evil = '<a href="https://example.invalid/">T1</a><span style="font-size:90px">x</span>'
    est = Estimate(label=evil, east_m=1.0, north_m=2.0, semi_major_m=0.5, semi_minor_m=0.2, angle_rad=0.3)
    series = Series(
        title=f"ranges of {evil}",
        x_label=evil,
        y_label="range (m)",
        lines=((evil, np.arange(3.0), np.arange(3.0), "lines", None),),
    )
    rep = Report(
        kind="journal",
        title=evil,
        map=MapLayers(track_en_m=np.array([[0.0, 0.0], [5.0, 5.0]]), track_label=evil, estimates=(est,)),
        series=(series,),
    )
    page = tmp_path / "evil.html"
    page.write_text(render_html(rep), encoding="utf-8")
    probe = """JSON.stringify({
      links: document.querySelectorAll('.plotly-graph-div a').length,
      styled: Array.from(document.querySelectorAll('.plotly-graph-div tspan')).filter(
        t => (t.getAttribute('style') || '').includes('90px')).length,
      legend: Array.from(document.querySelectorAll('.legendtext')).map(t => t.textContent)})"""
    got = load_page(page, probe, ready=PLOTLY_READY, timeout_s=30.0)
    dom = json.loads(got.value)
    assert dom["links"] == 0 and dom["styled"] == 0
    assert any(text.startswith('<a href="https://example.invalid/">T1</a>') for text in dom["legend"])
    assert got.console_errors == []
