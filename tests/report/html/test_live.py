"""The live journal page: served read-only on loopback, redrawn in real Chromium as records are appended.

The browser test loads the page with every request other than the server's failing at a dead proxy,
appends fixes and ranges to the journal through the journal's own writer, and waits (bounded) for the
new points to be in the plot data; the server's reads must never make that writer wait.
"""

from __future__ import annotations

import base64
import json
import os
import signal
import socket
import sqlite3
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import ConfigError, DataError
from oceanloc.field.survey.journal import Journal
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic, geodetic_to_enu
from oceanloc.report.html.browser import find_chromium, load_page
from oceanloc.report.html.live import JournalTail, serve_journal
from tests.report.html.conftest import make_journal

APPEND_FIXES = 20
APPEND_RANGES = 8


@pytest.fixture
def journal(tmp_path) -> Path:
    return make_journal(tmp_path, duration_s=600.0)


def _continue_track(path: Path, n_fixes: int, n_ranges: int, *, timeout_s: float = 30.0) -> np.ndarray:
    """Append ``n_fixes`` fixes (1 s apart, 2 m/s east of the last fix) and ``n_ranges`` ranges to beacon
    1; returns the appended fixes' east-north (m) in the frame of the journal's first fix."""
    with Journal.open(path) as j:
        f = j.fixes()
    origin = EnuOrigin(lat_deg=f[0, 1], lon_deg=f[0, 2], h_m=f[0, 3])
    last = f[-1]
    start = np.asarray(geodetic_to_enu(last[1], last[2], last[3], origin)).reshape(3)
    k = np.arange(1, n_fixes + 1)
    enu = start + np.column_stack([2.0 * k, np.zeros_like(k), np.zeros_like(k)])
    geo = enu_to_geodetic(enu, origin).reshape(-1, 3)
    with Journal(path, create=False, timeout_s=timeout_s) as j:
        for i in range(n_fixes):
            j.add_fix(float(last[0] + k[i]), *map(float, geo[i]))
            if i < n_ranges:
                j.add_range(float(last[0] + k[i] + 0.5), 1, 12.0 + 0.1 * i)
    return enu[:, :2]


def _get(url: str, method: str = "GET", headers: dict | None = None) -> tuple[int, dict, bytes]:
    req = urllib.request.Request(url, method=method, headers=headers or {})
    if method in ("POST", "PUT", "PATCH"):
        req.data = b"{}"
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as exc:
        return exc.code, dict(exc.headers), exc.read()


def _array(v) -> np.ndarray:
    """A plotly JSON array: a list, or ``{"dtype", "bdata"}`` (base64 of the raw values)."""
    if isinstance(v, dict):
        return np.frombuffer(base64.b64decode(v["bdata"]), dtype=np.dtype(v["dtype"]))
    return np.asarray(v, dtype=float)


def _data(url: str, **q) -> dict:
    query = "&".join(f"{k}={v}" for k, v in q.items())
    return json.loads(_get(f"{url}data?{query}")[2])


def _wait_estimate(url: str, timeout_s: float = 30.0) -> dict:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        d = _data(url)
        if d.get("est") and d.get("table"):
            return d
        time.sleep(0.1)
    raise AssertionError("no estimate in time")


def test_tail_reads_only_what_is_new_and_skips_invalid_rows(journal):
    tail = JournalTail(journal)
    assert tail.read() == (600, tail.ranges.shape[0]) and tail.ranges.shape[0] > 300
    assert tail.read() == (0, 0)
    with sqlite3.connect(journal) as db:  # a row this version never writes: skipped, as Journal.records does
        db.execute("INSERT INTO fixes VALUES (?, ?, ?, ?)", (2e9, 95.0, 0.0, 0.0))
    _continue_track(journal, 3, 2)
    assert tail.read() == (3, 2)
    rec = tail.records()
    with Journal.open(journal) as j:
        ref = j.records()
    np.testing.assert_array_equal(rec.fix_t_unix_s, ref.fix_t_unix_s)
    np.testing.assert_array_equal(rec.range_m, ref.range_m)
    np.testing.assert_array_equal(rec.heading_deg, ref.heading_deg)


def test_server_sends_new_fixes_ranges_and_estimates(journal):
    with serve_journal(journal, 0, estimate_period_s=0.2) as server:
        first = _wait_estimate(server.url)
        n_ranges = first["range"]["to"]
        assert first["fix"]["to"] == 600 and len(first["fix"]["e"]) == 600
        assert sum(len(v[0]) for v in first["range"]["by"].values()) == n_ranges
        names = [t["name"] for t in first["est"]["data"]]
        assert sum(n.startswith("95% ellipse") for n in names) == 2
        assert [t.get("meta") for t in first["est"]["data"]].count("track") == 1
        assert [r[0] for r in first["table"]] == ["1", "2"]
        assert "next site (greedy, computed here)" in first["status"]["plan"]
        assert first["status"]["link"] == "link: not recorded in this journal"
        en = _continue_track(journal, 5, 3)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            d = _data(server.url, gen=first["gen"], fix=600, range=n_ranges, est=first["est"]["version"])
            if d["fix"]["to"] == 605 and d["range"]["to"] == n_ranges + 3:
                break
            time.sleep(0.1)
        assert d["fix"]["to"] == 605 and len(d["fix"]["e"]) == 5  # only what is new
        np.testing.assert_allclose(np.column_stack([d["fix"]["e"], d["fix"]["n"]]), en, atol=2e-3)
        assert list(d["range"]["by"]) == ["1"] and d["range"]["by"]["1"][1] == [12.0, 12.1, 12.2]
        stale = _data(server.url, gen="0")
        assert stale == {"gen": first["gen"]}  # a page of an earlier server reloads


def test_reads_never_make_the_writer_wait(journal):
    """A writer that may not wait at all (timeout 0) appends while pages poll the server."""
    with serve_journal(journal, 0, estimate_period_s=0.1) as server:
        t0 = time.monotonic()
        for _ in range(10):
            _continue_track(journal, 5, 5, timeout_s=0.0)
            _data(server.url)
        took = time.monotonic() - t0
    with Journal.open(journal) as j:
        assert j.records().n_fixes == 650
    assert took < 20.0


def test_non_loopback_host_is_refused(journal):
    for host in ("0.0.0.0", "192.168.1.20", "example.org"):
        with pytest.raises(ConfigError, match=r"loopback only \(127\.0\.0\.1, ::1, localhost\)"):
            serve_journal(journal, 0, host=host)
    with pytest.raises(ConfigError, match="port 70000 is not in"):
        serve_journal(journal, 70000)


def test_missing_or_unstarted_journal_is_a_data_error(tmp_path):
    with pytest.raises(DataError, match="no survey journal here"):
        serve_journal(tmp_path / "none.db", 0)
    with sqlite3.connect(tmp_path / "raw.db") as db:
        db.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
    with pytest.raises(DataError, match="not a started survey journal"):
        serve_journal(tmp_path / "raw.db", 0)


def test_read_only_methods_paths_and_hosts(journal):
    with serve_journal(journal, 0) as server:
        for method in ("POST", "PUT", "DELETE", "PATCH", "OPTIONS", "TRACE"):
            code, headers, body = _get(server.url + "data", method)
            assert (code, headers["Allow"]) == (405, "GET, HEAD"), method
        code, headers, body = _get(server.url)
        assert code == 200 and b"Plotly.newPlot" in body and b"connect-src 'self'" in body
        assert "connect-src 'self'" in headers["Content-Security-Policy"]
        assert _get(server.url, "HEAD")[0] == 200
        assert _get(server.url + "control")[0] == 404
        assert _get(server.url, headers={"Host": "attacker.example:80"})[0] == 403
        assert _get(server.url, headers={"Host": f"localhost:{server.port}"})[0] == 200


def test_events_table_plan_and_link_are_shown(journal):
    with Journal.open(journal) as j:
        f = j.fixes()
    o = EnuOrigin(lat_deg=f[0, 1], lon_deg=f[0, 2], h_m=f[0, 3])
    sites = enu_to_geodetic(np.array([[10.0, 0.0, 0.0], [10.0, 10.0, 0.0]]), o).reshape(-1, 3)
    plan = {
        "planner": "k2",
        "from": {"enu_m": [0.0, 0.0, 0.0]},
        "next": {"lat_deg": sites[0, 0], "lon_deg": sites[0, 1], "h_m": sites[0, 2]},
        "waypoints": [{"lat_deg": s[0], "lon_deg": s[1], "h_m": s[2]} for s in sites],
        "distance_m": 10.0,
        "bearing_deg": 90.0,
    }
    with sqlite3.connect(journal) as db:
        db.execute(
            "CREATE TABLE IF NOT EXISTS events (seq INTEGER PRIMARY KEY, t REAL, kind TEXT, body TEXT)"
        )
        rows = [
            (1, f[-1, 0], "link", json.dumps({"state": "down"})),
            (2, f[-1, 0], "plan", json.dumps(plan)),
            (3, f[-1, 0] + 1, "link", json.dumps({"state": "up", "rtt_ms": 41})),
            (4, f[-1, 0] + 1, "command", json.dumps({"goto": [1, 2]})),
        ]
        db.executemany("INSERT INTO events VALUES (?, ?, ?, ?)", rows)
    with serve_journal(journal, 0, estimate_period_s=0.2) as server:
        d = _wait_estimate(server.url)
    assert d["status"]["link"].startswith("link: state up, rtt_ms 41")
    assert d["status"]["plan"].startswith("next site (k2), 10.0 m at 90° true")
    assert "from the survey run" in d["status"]["plan"]
    trace = next(t for t in d["est"]["data"] if t["name"].startswith("last fix (1) and planned"))
    np.testing.assert_allclose(_array(trace["x"]), [0.0, 10.0, 10.0], atol=1e-6)
    np.testing.assert_allclose(_array(trace["y"]), [0.0, 0.0, 10.0], atol=1e-6)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_cli_serves_and_exits_0_on_sigterm(journal):
    port = _free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "oceanloc", "report", str(journal), "--serve", str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ,
    )
    try:
        line = proc.stdout.readline()
        assert f"http://127.0.0.1:{port}/" in line
        code, _, body = _get(f"http://127.0.0.1:{port}/")
        assert code == 200 and b"Live survey journal survey.db" in body
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert "Traceback" not in err and "stopped serving" in err


@pytest.mark.parametrize(
    ("args", "reason"),
    [
        (["--serve", "0", "--host", "0.0.0.0"], "refusing to serve the live page on 0.0.0.0"),
        ([], "nothing to do: give --html PATH"),
        (["--serve", "0", "--kml", "x.kml"], "--kml PATH goes with --html PATH"),
    ],
)
def test_cli_usage_errors(journal, args, reason):
    res = subprocess.run(
        [sys.executable, "-m", "oceanloc", "report", str(journal), *args],
        capture_output=True,
        text=True,
        env=os.environ,
        timeout=60,
    )
    assert res.returncode == 2
    assert reason in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


LIVE_DOM = """JSON.stringify((() => {
  const map = document.getElementById('map');
  const track = map.data.find(t => t.meta === 'track');
  const ranges = document.getElementById('series-0').data;
  const sigma = document.getElementById('series-1').data;
  return {
    track_n: track.x.length, track_last: [track.x[track.x.length - 1], track.y[track.y.length - 1]],
    names: map.data.map(t => t.name),
    ranges: ranges.map(t => [t.name, t.x.length]),
    sigma: sigma.map(t => [t.name, t.x.length]),
    rows: document.querySelectorAll('#estimates tbody tr').length,
    records: document.getElementById('live-records').textContent,
    plan: document.getElementById('live-plan').textContent,
    connection: document.getElementById('live-connection').textContent,
    drawn_markers: map.querySelectorAll('.scatterlayer .trace path.point').length,
  };
})())"""


def _track_ready(n: int, ranges_drawn: int | None = None) -> str:
    """True once the track holds ``n`` points, the table two rows and, if given, the map the estimate
    made from ``ranges_drawn`` ranges."""
    ranges = (
        "true"
        if ranges_drawn is None
        else f"m.data.some(t => t.name === 'ranges as taken ({ranges_drawn} drawn)')"
    )
    return (
        "(() => { const m = document.getElementById('map'); const t = m.data && m.data.find("
        f"t => t.meta === 'track'); return !!t && t.x.length === {n} && {ranges} && "
        "document.querySelectorAll('#estimates tbody tr').length === 2; })()"
    )


@pytest.mark.skipif(find_chromium() is None, reason="chromium not installed: live browser test skipped")
def test_live_page_in_chromium_draws_appended_records(journal, tmp_path):
    pytest.importorskip("websocket", reason="websocket-client drives chromium's DevTools protocol")
    appended: list[np.ndarray] = []
    with serve_journal(journal, 0, estimate_period_s=0.5) as server:
        n_ranges = _wait_estimate(server.url)["range"]["to"]
        got = load_page(
            server.url,
            LIVE_DOM,
            ready=_track_ready(600),
            actions=[
                (
                    lambda: appended.append(_continue_track(journal, APPEND_FIXES, APPEND_RANGES)),
                    _track_ready(600 + APPEND_FIXES, n_ranges + APPEND_RANGES),
                )
            ],
            timeout_s=40.0,
        )
    (tmp_path / "live.png").write_bytes(got.screenshot_png)
    assert got.screenshot_png[:8] == b"\x89PNG\r\n\x1a\n" and len(got.screenshot_png) > 20_000
    assert got.console_errors == []
    assert got.outside_requests == [] and got.failed_requests == []
    assert got.action_s[0] < 10.0  # the new fixes are drawn within a few seconds (polled every second)
    dom = json.loads(got.value)
    assert dom["track_n"] == 600 + APPEND_FIXES
    np.testing.assert_allclose(dom["track_last"], appended[0][-1], atol=2e-3)
    assert dom["drawn_markers"] >= 600 + APPEND_FIXES  # one SVG marker per fix
    assert sum(n for _, n in dom["ranges"]) == n_ranges + APPEND_RANGES  # every range, by beacon
    assert sorted(name for name, _ in dom["ranges"]) == ["beacon 1", "beacon 2"]
    assert sorted(name for name, _ in dom["sigma"]) == ["beacon 1", "beacon 2"]
    assert min(n for _, n in dom["sigma"]) >= 2  # re-estimated with the new ranges, and drawn
    assert sum(n.startswith("95% ellipse") for n in dom["names"]) == 2
    assert dom["rows"] == 2 and dom["records"].startswith(
        f"{600 + APPEND_FIXES} fixes, {n_ranges + 8} ranges"
    )
    assert f"ranges as taken ({n_ranges + APPEND_RANGES} drawn)" in dom["names"]
    assert dom["plan"].startswith("next site (greedy, computed here)")
    assert dom["connection"].startswith("connected")


def test_page_of_a_journal_started_empty_fills_as_fixes_arrive(tmp_path):
    from tests.report.html.conftest import JOURNAL_SETTINGS

    path = tmp_path / "empty.db"
    Journal.start(path, JOURNAL_SETTINGS.to_meta()).close()
    with serve_journal(path, 0, estimate_period_s=0.2) as server:
        d = _wait_until(server.url, lambda d: "est" in d)
        assert d["fix"]["to"] == 0 and d["status"]["estimate"] == "no estimate yet (no GPS fix)"
        assert [t.get("meta") for t in d["est"]["data"]] == ["track"]  # an empty track, styled
        with Journal(path, create=False) as j:
            j.add_fix(1.6e9, 32.7, -117.2, 0.0)
            j.add_fix(1.6e9 + 1, 32.70001, -117.2, 0.0)
        d = _wait_until(server.url, lambda d: d["fix"]["to"] == 2 and "est" in d, est=d["est"]["version"])
        assert d["fix"]["e"] == [0.0, 0.0] and d["fix"]["n"][1] == pytest.approx(1.109, abs=1e-3)
        assert d["status"]["estimate"].startswith("beacons estimated: none; waiting: 1 (0 ranges)")


def _wait_until(url: str, ok, timeout_s: float = 15.0, **q) -> dict:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        d = _data(url, **q)
        if ok(d):
            return d
        time.sleep(0.1)
    raise AssertionError(f"not in time: {d}")


def test_port_in_use_is_a_data_error(journal):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(DataError, match=f"cannot serve the live page on 127.0.0.1:{port}: .*in use"):
            serve_journal(journal, port)
