import json
import re

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.report.html.model import Estimate, MapLayers, Report
from oceanloc.report.html.page import MAX_TRACK_POINTS, map_figure, render_html
from oceanloc.report.html.sources import detect_kind

KINDS = ("journal", "survey", "montecarlo", "gnssa", "gnssa-array", "reproduction", "drift")


def _names(fig) -> list[str]:
    return [t.name for t in fig.data]


def _outside_refs(page: str) -> list[str]:
    """Every script src, link href, img/iframe src or CSS url() in the page that points off the file."""
    pats = [
        r"<script\b[^>]*\bsrc\s*=",
        r"<link\b[^>]*\bhref\s*=",
        r"<(?:img|iframe|source|video|audio|embed|object)\b[^>]*\b(?:src|data)\s*=\s*[\"']?(?:https?:)?//",
        r"url\(\s*[\"']?(?:https?:)?//",
        r"@import",
    ]
    return [m.group(0) for p in pats for m in re.finditer(p, page, flags=re.IGNORECASE)]


@pytest.mark.parametrize("kind", KINDS)
def test_source_kind_is_detected(sources, kind):
    assert detect_kind(sources[kind])[0] == kind


@pytest.mark.parametrize("kind", KINDS)
def test_page_is_self_contained(sources, reports, kind):
    page = render_html(reports[kind])
    assert _outside_refs(page) == []
    assert page.count("<script") == page.count("</script>")
    # plotly's bundle once, in the head; the rest of the page names no web address at all
    assert page.count("plotly.js v") >= 1 and page.count('<script type="text/javascript">/**') == 1
    head, body = page.split("</head>", 1)
    assert "Content-Security-Policy" in head and "default-src 'none'" in head
    assert re.findall(r"https?://", body) == []


def test_journal_map_has_every_fix_one_ellipse_per_beacon_and_the_checks(sources, reports):
    rep = reports["journal"]
    assert rep.map.track_en_m.shape == (600, 2) and rep.map.origin is not None
    names = _names(map_figure(rep.map))
    assert sorted(n for n in names if n.startswith("95% ellipse")) == [
        "95% ellipse beacon 1",
        "95% ellipse beacon 2",
    ]
    track = next(t for t in map_figure(rep.map).data if t.name == "GPS track")
    assert len(track.x) == 600 and track.customdata.shape == (600, 2)  # lat, lon in the hover
    assert len(rep.checks) == 4 and len(rep.tables[0].rows) == 2
    page = render_html(rep)
    assert page.count('<tr class="check ') == 4
    assert "excluded: outlier" in page and "beacon has too few" not in page


def test_survey_ellipses_to_scale_with_magnified_inset(sources, reports):
    rep = reports["survey"]
    rec = json.loads(sources["survey"].read_text())
    fig = map_figure(rep.map)
    names = _names(fig)
    assert sum(n.startswith("95% ellipse") for n in names) == 4
    assert sum(n.startswith("inset ellipse") for n in names) == 4  # centimetre ellipses on a ~40 m map
    ring = next(t for t in fig.data if t.name == "95% ellipse m=1")
    t = rec["transponders"][0]
    dist = np.hypot(np.asarray(ring.x) - t["estimate_enu_m"][0], np.asarray(ring.y) - t["estimate_enu_m"][1])
    assert dist.max() == pytest.approx(t["ellipse95_semi_axes_m"][0], rel=1e-3)
    assert dist.min() == pytest.approx(t["ellipse95_semi_axes_m"][1], rel=1e-2)
    sites = next(t for t in fig.data if t.name.startswith("measurement sites"))
    assert len(sites.x) == 40
    assert any(s.name == "scale bar" for s in fig.layout.shapes)


def test_no_inset_when_ellipses_are_visible(sources, reports):
    names = _names(map_figure(reports["journal"].map))
    assert not any(n.startswith("inset") for n in names)


def test_gnssa_one_ellipse_per_survey_and_spread_checks(sources, reports):
    rep = reports["gnssa"]
    names = _names(map_figure(rep.map))
    assert sum(n.startswith("95% ellipse") for n in names) == 5
    assert len(rep.checks) == 6 and all("spread" in c.name for c in rep.checks)
    assert rep.series[0].title == "Sound speed estimated per survey"


def test_reproduction_checks_and_paper_tables(sources, reports):
    rec = json.loads(sources["reproduction"].read_text())
    rep = reports["reproduction"]
    assert len(rep.checks) == len(rec["checks"]) and rep.map is None
    page = render_html(rep)
    assert page.count('<tr class="check ') == len(rec["checks"])
    assert "Table III: paper beside ours" in page and "RMSE paper (m)" in page


def test_drift_legs_obstacles_and_current(sources, reports):
    names = _names(map_figure(reports["drift"].map))
    assert {"flight legs", "drift legs", "goal tolerance", "current"} <= set(names)
    assert names.count("obstacle") == 2


def test_montecarlo_has_no_map_and_the_nees_check(sources, reports):
    rep = reports["montecarlo"]
    assert rep.map is None and rep.checks[0].name.startswith("mean NEES at epoch 12")


def test_track_is_thinned_for_drawing_only():
    n = 3 * MAX_TRACK_POINTS + 7
    track = np.column_stack([np.arange(n, dtype=float), np.zeros(n)])
    layers = MapLayers(track_en_m=track)
    drawn = map_figure(layers).data[0]
    assert len(drawn.x) <= MAX_TRACK_POINTS and drawn.x[0] == 0.0 and drawn.x[-1] == n - 1
    assert f"of {n} points drawn" in drawn.name and layers.track_en_m.shape[0] == n


def test_user_text_is_escaped():
    rep = Report(
        kind="survey",
        title="<b>x</b>",
        summary=("<script>alert(1)</script>",),
        map=MapLayers(
            estimates=(
                Estimate(label="<i>", east_m=0, north_m=0, semi_major_m=1, semi_minor_m=1, angle_rad=0),
            )
        ),
    )
    page = render_html(rep)
    assert "<script>alert(1)</script>" not in page and "&lt;script&gt;alert(1)" in page


def test_unknown_json_and_foreign_files_are_data_errors(tmp_path):
    (tmp_path / "a.json").write_text('{"x": 1}')
    with pytest.raises(DataError, match="not a record oceanloc report knows"):
        detect_kind(tmp_path / "a.json")
    (tmp_path / "b.bin").write_bytes(b"\x00\xff" * 10)
    with pytest.raises(DataError, match="neither a survey journal"):
        detect_kind(tmp_path / "b.bin")
    with pytest.raises(DataError, match="no such file"):
        detect_kind(tmp_path / "missing.db")


def test_journal_sigma_by_time_ends_at_the_final_ellipse(sources, reports):
    rep = reports["journal"]
    sigma = rep.series[0]
    assert sigma.title.startswith("95 % ellipse semi-major axis by time")
    finals = {e.label: e.semi_major_m for e in rep.map.estimates}
    for name, _, y, _, _ in sigma.lines:
        assert y[-1] == pytest.approx(finals[name], rel=1e-9)  # the last cut is the whole journal
        assert y[-1] < y[0]  # more ranges, smaller ellipse


def gnssa_with_pings(sources) -> dict:
    """The session's GNSS-A record with per-ping residuals added by hand to its first survey: two
    transponders, 40 pings, three excluded for two reasons."""
    rec = json.loads(sources["gnssa"].read_text())
    rec.pop("pings", None)  # the record's own (every survey's pings), replaced by these
    t = np.arange(40.0) * 15.0
    residual = 0.02 * np.sin(t / 50.0)
    excluded = np.zeros(40, dtype=bool)
    excluded[[5, 17, 30]] = True
    residual[excluded] = [0.9, -1.1, 0.7]
    reason = ["" if not e else "outlier" for e in excluded]
    reason[30] = "elevation below 20 deg"
    rec["surveys"][0]["pings"] = {
        "t_s": t.tolist(),
        "transponder": ["M1" if i % 2 else "M2" for i in range(40)],
        "residual_m": residual.tolist(),
        "excluded": excluded.tolist(),
        "reason": reason,
    }
    return rec


def test_gnssa_pings_draw_residuals_used_and_excluded_with_reasons(sources):
    from oceanloc.report.html.records import gnssa_report

    rec = gnssa_with_pings(sources)
    rep = gnssa_report(rec)
    pings = rep.series[-1]
    assert pings.title == f"Residuals per ping: {rec['surveys'][0]['file']} (3 of 40 excluded)"
    names = [line[0] for line in pings.lines]
    assert names == [
        "transponder M1 used",
        "transponder M2 used",
        "excluded: elevation below 20 deg",
        "excluded: outlier",
    ]
    assert [len(line[1]) for line in pings.lines] == [18, 19, 1, 2]
    assert pings.lines[3][2].tolist() == [0.9, -1.1]
    assert pings.lines[3][4] == ["transponder M1: outlier"] * 2 and pings.lines[2][2].tolist() == [0.7]
    assert "not per-ping residuals" not in " ".join(rep.notes)
    page = render_html(rep)
    assert "Residuals per ping" in page and "elevation below 20 deg" in page


def test_gnssa_without_pings_has_no_ping_panel_and_says_so(reports, sources):
    from oceanloc.report.html.records import gnssa_report

    # `localize gnssa --json` records carry every ping's residual: the panel is drawn
    assert any(s.title.startswith("Residuals per ping") for s in reports["gnssa"].series)
    rec = json.loads(sources["gnssa"].read_text())
    rec.pop("pings")
    rep = gnssa_report(rec)
    assert not any(s.title.startswith("Residuals per ping") for s in rep.series)
    assert "not per-ping residuals" in " ".join(rep.notes)


def test_gnssa_array_one_ellipse_per_transponder_ping_panel_and_checks(sources, reports):
    rec = json.loads(sources["gnssa-array"].read_text())
    rep = reports["gnssa-array"]
    ids = [t["id"] for t in rec["transponders"]]
    names = _names(map_figure(rep.map))
    assert sorted(n for n in names if n.startswith("95% ellipse")) == [
        f"95% ellipse {i}" for i in sorted(ids)
    ]
    assert "array centre (estimated)" in names and rep.map.origin is not None
    # the east-north block of the covariance: an axis-aligned ellipse's semi-axes would be 2.448 sd E, sd N;
    # the rotated one's area is the same: a * b = 2.448^2 sd E sd N sqrt(1 - rho^2) <= 2.448^2 sd E sd N
    cov = np.asarray(rec["details"]["covariance_m2"])
    for k, (t, e) in enumerate(zip(rec["transponders"], rep.map.estimates, strict=True)):
        block = cov[3 * k : 3 * k + 2, 3 * k : 3 * k + 2]
        assert e.semi_major_m * e.semi_minor_m == pytest.approx(
            5.991 * np.sqrt(np.linalg.det(block)), rel=1e-3
        )
        assert np.sqrt(block[0, 0]) == pytest.approx(t["sigma_e_m"], rel=1e-9)
    assert any(n.startswith("inset ellipse") for n in names)  # cm-sized ellipses on a km-sized map
    pings = rep.series[0]
    excluded = sum(rec["pings"]["excluded"])
    assert pings.title == f"Residuals per ping: array ({excluded} of {rec['replies']} excluded)"
    assert [line[0] for line in pings.lines if not line[0].startswith("excluded")] == [
        f"transponder {i} used" for i in sorted(ids)
    ]
    assert sum(len(line[1]) for line in pings.lines if line[0].startswith("excluded")) == excluded
    # the packaged example is drift free: the model selection dropped the knots, so no sound-speed panel
    assert rec["details"]["knot_times_s"] == [] and len(rep.series) == 1
    assert [t["kept"] for t in rec["details"]["model_tests"]][:3] == [False, False, False]
    assert [c.name for c in rep.checks] == [
        "solver converged",
        "replies used vs excluded: at most 5 % excluded",
    ]
    assert rep.checks[0].passed is bool(rec["converged"])
    assert rep.checks[1].value == f"{rec['replies'] - excluded} used, {excluded} excluded"
    assert len(rep.tables[1].rows) == len(rec["iterations"])
    page = render_html(rep)
    assert page.count('<tr class="check ') == 2 and "outlier" in page


def test_gnssa_array_with_knots_has_a_sound_speed_panel(sources):
    from oceanloc.report.html.records import gnssa_array_report

    rec = json.loads(sources["gnssa-array"].read_text())
    t0 = float(rec["details"]["epoch_s"])
    rec["details"].update(
        knot_times_s=[t0 - 1800.0, t0, t0 + 1800.0],
        sound_speed_knots_mps=[1481.0, 1481.5, 1482.0],
        sound_speed_knot_sigma_mps=[0.2, 0.2, 0.2],
    )
    series = gnssa_array_report(rec).series
    assert series[0].title.startswith("Residuals per ping")
    assert series[1].title.startswith("Sound speed at the knots")
    assert len(series[1].lines[0][1]) == 3


def test_gnssa_pings_of_unequal_length_are_a_data_error(sources, tmp_path):
    from oceanloc.report.html.sources import load_report

    rec = gnssa_with_pings(sources)
    rec["surveys"][0]["pings"]["excluded"].pop()
    path = tmp_path / "g.json"
    path.write_text(json.dumps(rec))
    with pytest.raises(
        DataError, match=r"a gnssa record with a missing or malformed field.*differ in length"
    ):
        load_report(path)


def test_dense_markers_are_drawn_as_their_extent_per_bin_keeping_every_extreme():
    from oceanloc.report.html.model import Series
    from oceanloc.report.html.page import MAX_SERIES_MARKERS, SERIES_BINS, series_figure

    rng = np.random.default_rng(5)
    n = 5 * MAX_SERIES_MARKERS
    t = np.sort(rng.uniform(0.0, 86_400.0, n))
    r = rng.normal(0.0, 0.05, n)
    r[1234] = 0.9  # one isolated spike must stay visible
    few = (t[:50], r[:50])
    fig = series_figure(
        Series(
            title="x",
            x_label="time (s)",
            y_label="residual (m)",
            lines=(("beacon 1 used", t, r, "markers", None), ("beacon 2 used", *few, "markers", None)),
        )
    )
    dense, sparse = fig.data
    assert dense.mode == "lines" and len(dense.x) <= 3 * SERIES_BINS
    assert dense.name == f"beacon 1 used ({n} points, drawn as their extent per {np.ptp(t) / 1000:.3g} s)"
    y = np.asarray(dense.y, dtype=float)
    x = np.asarray(dense.x, dtype=float)
    pad = 0.003 * np.ptp(r)
    assert np.nanmax(y) == pytest.approx(0.9 + pad) and np.nanmin(y) == pytest.approx(r.min() - pad)
    spike = x[np.nanargmax(y)]
    assert abs(spike - t[1234]) <= np.ptp(t) / SERIES_BINS  # drawn in its own bin
    lo, hi = y[0::3], y[1::3]  # every point lies on its bin's stroke
    edges = np.linspace(t[0], t[-1], SERIES_BINS + 1)
    b = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, SERIES_BINS - 1)
    mids = 0.5 * (edges[b] + edges[b + 1])
    k = np.searchsorted(x[0::3], mids)
    assert np.all((lo[k] <= r) & (r <= hi[k]))
    assert sparse.mode == "markers" and len(sparse.x) == 50  # a short line keeps a marker per point
