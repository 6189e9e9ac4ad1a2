"""The live page of a survey journal that another process is writing: served on loopback, read-only.

:func:`serve_journal` starts a :class:`LiveServer` (``http.server.ThreadingHTTPServer`` in a background
thread). It serves one page, in the look of the static journal report (plotly inlined, a
Content-Security-Policy that allows requests to this server only), which polls ``/data`` once a second
and draws what is new with ``Plotly.extendTraces`` (track, ranges, ellipse sizes) and ``Plotly.react``
(estimates, their 95 % ellipses, the ranges as taken and the planned sites).

Reading never gets in the writer's way: each read opens its own SQLite connection with ``mode=ro``
(no write, no schema statement, no lock beyond a WAL reader's), reads only the rows past the previous
read (by ``rowid``) in one short read transaction, and closes it. Rows are checked with the journal's own
checks (:func:`~oceanloc.field.survey.journal.fix_problem`, ...) and invalid ones skipped. The estimates
(:func:`~oceanloc.field.survey.estimates.survey_estimates`) and the next site are recomputed in the
background at most every :data:`ESTIMATE_PERIOD_S` seconds, when ranges arrived (every
:data:`FIX_REFRESH_S` when only fixes did), and only while a page is watching; a request only copies
what the client lacks. Where the journal has an ``events`` table
(``seq, t, kind, body``; kinds ``estimate``, ``plan``, ``command``, ``link``, JSON bodies), the latest
``plan`` is the next site shown and the latest ``link`` state is printed; without it the next site is
the survey planner's (:func:`~oceanloc.field.survey.estimates.next_waypoint`).

The server answers GET and HEAD only (anything else: 405); no endpoint changes anything, and the page
exposes no control of the vehicle. It binds loopback unless ``allow_remote`` is given, and answers only
requests whose ``Host`` names loopback (a web page elsewhere cannot read it through DNS rebinding).
"""

from __future__ import annotations

import datetime as dt
import html
import http.server
import ipaddress
import json
import logging
import math
import signal
import socket
import sqlite3
import threading
import time
import urllib.parse
from pathlib import Path
from typing import Any

import numpy as np

from oceanloc.errors import ConfigError, DataError
from oceanloc.field.survey.estimates import next_waypoint, survey_estimates
from oceanloc.field.survey.journal import (
    FORMAT_KEY,
    JOURNAL_FORMAT,
    JournalRecords,
    fix_problem,
    heading_problem,
    range_problem,
)
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.geo.enu import EnuOrigin, geodetic_to_enu
from oceanloc.report.html.journal import beacon_markers, range_geometry
from oceanloc.report.html.model import Estimate, MapLayers, Series
from oceanloc.report.html.page import (
    CSP,
    MAX_RANGE_SEGMENTS,
    MAX_TRACK_POINTS,
    figure_div,
    map_figure,
    page_head,
    series_figure,
)

_LOG = logging.getLogger(__name__)

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
POLL_S = 0.5
"""The journal is read at most this often (seconds), whatever the number of pages watching."""
ESTIMATE_PERIOD_S = 2.0
"""The estimates are recomputed at most this often (seconds), and only when records arrived."""
FIX_REFRESH_S = 10.0
"""When only fixes arrived, the next site (from the last fix) is recomputed at most this often (seconds)."""
WATCHED_S = 30.0
"""No estimate is computed when no page asked for data within this time (seconds)."""
MAX_BATCH = 20_000
"""Records of one kind sent per answer at most (a page catching up asks again at once)."""
SERIES_WINDOW = 5000
"""Points per beacon kept in the live time series (the latest)."""
CLIENT_POLL_MS = 1000
EVENT_KINDS = ("estimate", "plan", "command", "link")

_HEAD_EXTRA = '<link rel="icon" href="data:,"><style>#live-status li:empty{display:none}</style>'
"""No favicon request; the error line shows only when there is one."""
LIVE_CSP = CSP.replace("default-src 'none';", "default-src 'none'; connect-src 'self';")


def _utc(t: float) -> str:
    return dt.datetime.fromtimestamp(t, dt.UTC).strftime("%Y-%m-%d %H:%M:%S")


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


class JournalTail:
    """What a journal holds, read incrementally: every valid fix, range and heading in arrival order,
    and the latest event of each kind.

    Each :meth:`read` opens a read-only connection, reads the rows past the last read in one read
    transaction, and closes it.

    Raises
    ------
    DataError
        If the file is missing, not SQLite, or not a started survey journal.
    """

    def __init__(self, path: str | Path, *, timeout_s: float = 5.0) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise DataError(f"{self.path}: no survey journal here (start one with `oceanloc survey start`)")
        self._uri = f"{self.path.resolve().as_uri()}?mode=ro"
        self._timeout_s = timeout_s
        self._rowid = {"fixes": 0, "ranges": 0, "headings": 0, "events": 0}
        self.fixes = np.zeros((0, 4))
        self.ranges = np.zeros((0, 3))
        self.headings = np.zeros((0, 3))
        self.latest_event: dict[str, dict] = {}
        self.n_events = 0
        self.has_events = False
        self._events_table = False
        self.meta = self._read(lambda db: dict(db.execute("SELECT key, value FROM meta").fetchall()))
        if self.meta.get(FORMAT_KEY) != JOURNAL_FORMAT:
            raise DataError(
                f"{self.path}: not a started survey journal (format {self.meta.get(FORMAT_KEY)!r}, expected "
                f"{JOURNAL_FORMAT!r})"
            )
        self.settings = JournalSettings.from_meta(self.meta, source=str(self.path))

    def _read(self, work):
        try:
            db = sqlite3.connect(self._uri, uri=True, isolation_level=None, timeout=self._timeout_s)
        except sqlite3.Error as exc:
            raise DataError(f"{self.path}: cannot open the journal read-only ({exc})") from None
        try:
            db.execute("BEGIN")
            try:
                return work(db)
            finally:
                db.execute("COMMIT")
        except sqlite3.Error as exc:
            raise DataError(f"{self.path}: cannot read the journal ({exc})") from None
        finally:
            db.close()

    def _new_rows(self, db: sqlite3.Connection, table: str, columns: str, check) -> np.ndarray:
        rows = db.execute(
            f"SELECT rowid, {columns} FROM {table} WHERE rowid > ? ORDER BY rowid", (self._rowid[table],)
        ).fetchall()
        if not rows:
            return np.zeros((0, columns.count(",") + 1))
        self._rowid[table] = int(rows[-1][0])
        good = [r[1:] for r in rows if check(*r[1:]) is None]
        return np.asarray(good, dtype=float).reshape(-1, columns.count(",") + 1)

    def read(self) -> tuple[int, int]:
        """Read what is new; returns how many fixes and ranges arrived."""

        def work(db: sqlite3.Connection) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
            f = self._new_rows(db, "fixes", "t, lat, lon, h", fix_problem)
            r = self._new_rows(db, "ranges", "t, beacon, range_m", range_problem)
            h = self._new_rows(db, "headings", "t, seq, heading_deg", heading_problem)
            events: list = []
            if not self._events_table:
                self._events_table = bool(
                    db.execute(
                        "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'events'"
                    ).fetchall()
                )
            if self._events_table:
                events = db.execute(
                    "SELECT seq, t, kind, body FROM events WHERE seq > ? ORDER BY seq",
                    (self._rowid["events"],),
                ).fetchall()
                # a journal written by `survey run` has events (its start first); others have none
                self.has_events = self.has_events or bool(events)
            return f, r, h, events

        f, r, h, events = self._read(work)
        self.fixes = np.concatenate([self.fixes, f]) if f.size else self.fixes
        self.ranges = np.concatenate([self.ranges, r]) if r.size else self.ranges
        self.headings = np.concatenate([self.headings, h]) if h.size else self.headings
        for seq, t, kind, body in events:
            self._rowid["events"] = max(self._rowid["events"], int(seq))
            self.n_events += 1
            try:
                parsed = json.loads(body) if isinstance(body, str | bytes) else body
            except json.JSONDecodeError:
                parsed = str(body)
            self.latest_event[str(kind)] = {"seq": int(seq), "t": _finite(float(t)), "body": parsed}
        return f.shape[0], r.shape[0]

    def records(self) -> JournalRecords:
        """Everything read so far, ordered like :meth:`Journal.records` (by time; ranges by time, beacon)."""
        f = self.fixes[np.argsort(self.fixes[:, 0], kind="stable")]
        r = self.ranges[np.lexsort((self.ranges[:, 1], self.ranges[:, 0]))]
        h = self.headings[np.lexsort((self.headings[:, 1], self.headings[:, 0]))]
        return JournalRecords(
            fix_t_unix_s=f[:, 0],
            lat_deg=f[:, 1],
            lon_deg=f[:, 2],
            h_m=f[:, 3],
            range_t_unix_s=r[:, 0],
            beacon=r[:, 1].astype(np.int64),
            range_m=r[:, 2],
            heading_t_unix_s=h[:, 0],
            heading_deg=h[:, 2],
        )


def _plan_sites(body: Any, origin: EnuOrigin) -> tuple[np.ndarray, str]:
    """East-north of the start and planned sites of a ``plan`` body (a :meth:`Waypoint.to_record`), and a
    line describing it; positions from latitude/longitude where given (the plan's frame may differ)."""
    if not isinstance(body, dict):
        return np.zeros((0, 2)), f"next site: {body}"
    sites = [w for w in body.get("waypoints") or [] if isinstance(w, dict)]
    if not sites and isinstance(body.get("next"), dict):
        sites = [body["next"]]
    pts = []
    for w in sites:
        if "lat_deg" in w and "lon_deg" in w:
            enu = geodetic_to_enu(float(w["lat_deg"]), float(w["lon_deg"]), float(w.get("h_m", 0.0)), origin)
            pts.append(np.asarray(enu, dtype=float).reshape(-1)[:2])
        elif "e_m" in w and "n_m" in w:
            pts.append([float(w["e_m"]), float(w["n_m"])])
    start = (body.get("from") or {}).get("enu_m") if isinstance(body.get("from"), dict) else None
    if pts and isinstance(start, list) and len(start) >= 2:
        pts.insert(0, [float(start[0]), float(start[1])])
    nxt = body.get("next") if isinstance(body.get("next"), dict) else {}
    parts = [f"next site ({body.get('planner', '?')})"]
    if isinstance(body.get("distance_m"), int | float) and isinstance(body.get("bearing_deg"), int | float):
        parts.append(f"{body['distance_m']:.1f} m at {body['bearing_deg']:.0f}° true")
    if "lat_deg" in nxt and "lon_deg" in nxt:
        parts.append(f"lat {float(nxt['lat_deg']):.7f}°, lon {float(nxt['lon_deg']):.7f}°")
    return np.asarray(pts, dtype=float).reshape(-1, 2), ", ".join(parts)


def _describe(body: Any) -> str:
    """An event body as one line: ``key value`` pairs of a dict, else its text."""
    if isinstance(body, dict):
        return ", ".join(f"{k} {v}" for k, v in body.items() if not isinstance(v, dict | list))
    return str(body)


class _Live:
    """The state the page is drawn from, shared by the reader thread, the estimator thread and the
    request handlers (under ``lock``); requests only copy slices of it."""

    def __init__(self, tail: JournalTail, estimate_period_s: float) -> None:
        self.tail = tail
        self.settings = tail.settings
        self.period_s = estimate_period_s
        self.lock = threading.Lock()
        self.gen = f"{time.time_ns():x}"
        self.origin: EnuOrigin | None = self.settings.origin
        self.track_en = np.zeros((0, 2))
        self.track_geo = np.zeros((0, 2))
        self.range_rows = np.zeros((0, 3))
        self.sigma_rows = np.zeros((0, 3))  # t (ms), beacon, semi-major (m)
        self.est_version = 0
        self.est_block: dict = {}
        self.est_note = {"estimate": "no estimate yet", "plan": "next site: none yet"}
        self.table_rows: list[list[str]] = []
        self.dirty = threading.Event()
        self.moved = False
        self.fix_t_estimated = -math.inf
        self.estimated_at = -math.inf
        self.last_request = time.monotonic()
        self.read_error = ""

    # -- reader ---------------------------------------------------------------------------------------
    def read(self) -> None:
        """Read what is new in the journal and add it to the state."""
        try:
            n_fix, n_range = self.tail.read()
        except DataError as exc:
            with self.lock:
                self.read_error = str(exc)
            return
        plan_seq = self.tail.latest_event.get("plan", {}).get("seq")
        with self.lock:
            self.read_error = ""
            if self.origin is None and self.tail.fixes.shape[0]:
                f0 = self.tail.fixes[int(np.argmin(self.tail.fixes[:, 0]))]
                self.origin = EnuOrigin(lat_deg=float(f0[1]), lon_deg=float(f0[2]), h_m=float(f0[3]))
            if n_fix and self.origin is not None:
                new = self.tail.fixes[-n_fix:] if self.track_en.shape[0] else self.tail.fixes
                enu = geodetic_to_enu(new[:, 1], new[:, 2], new[:, 3], self.origin).reshape(-1, 3)
                self.track_en = np.concatenate([self.track_en, np.round(enu[:, :2], 3)])
                self.track_geo = np.concatenate([self.track_geo, new[:, 1:3]])
            if n_range:
                self.range_rows = self.tail.ranges.copy()
            new_plan = plan_seq != getattr(self, "_plan_seq", None)
            self._plan_seq = plan_seq
        r = self.tail.ranges
        first = n_fix and self.fix_t_estimated == -math.inf
        pending = n_fix and r.shape[0] and float(r[:, 0].max()) >= self.fix_t_estimated
        if n_range or new_plan or first or pending:  # pending: a range the last estimate could not align
            self.dirty.set()
        elif n_fix:  # only the track moved: the next site from the last fix, at most every FIX_REFRESH_S
            self.moved = True

    # -- estimator ------------------------------------------------------------------------------------
    def watched(self) -> bool:
        return time.monotonic() - self.last_request < WATCHED_S

    def estimate(self) -> None:
        """Re-estimate the beacons and the next site from everything read, and rebuild the map."""
        records = self.tail.records()
        self.fix_t_estimated = float(records.fix_t_unix_s[-1]) if records.n_fixes else -math.inf
        plan = self.tail.latest_event.get("plan")
        layers_kw: dict[str, Any] = {}
        estimates: tuple[Estimate, ...] = ()
        rows: list[list[str]] = []
        sigma = np.zeros((0, 3))
        notes = {"estimate": "no estimate yet (no GPS fix)", "plan": "next site: none yet"}
        origin = self.origin
        est = None
        if records.n_fixes:
            try:
                est = survey_estimates(records, self.settings)
            except DataError as exc:
                notes["estimate"] = f"no estimate: {exc}"
        if est is not None:
            origin = est.origin
            _, _, _, segs = range_geometry(records, self.settings, est)
            layers_kw["range_segments_en_m"] = segs[-MAX_RANGE_SEGMENTS:]
            estimates = beacon_markers(est)
            t_ms = float(records.fix_t_unix_s[-1]) * 1000.0
            sigma = np.column_stack(
                [np.full(est.n_beacons, t_ms), est.beacons.astype(float), est.ellipses.semi_major_m]
            )
            sig = est.sigma_enu_m
            rows = [
                [
                    str(b),
                    f"{est.positions_geodetic[i, 0]:.7f}",
                    f"{est.positions_geodetic[i, 1]:.7f}",
                    f"{est.positions_enu_m[i, 0]:.3f}",
                    f"{est.positions_enu_m[i, 1]:.3f}",
                    f"{est.positions_enu_m[i, 2]:.3f}",
                    f"{sig[i, 0]:.3f}",
                    f"{sig[i, 1]:.3f}",
                    f"{sig[i, 2]:.3f}",
                    f"{est.ellipses.semi_major_m[i]:.3f}",
                    f"{est.ellipses.semi_minor_m[i]:.3f}",
                    str(est.ranges_used[i]),
                    str(est.ranges_excluded[i]),
                    f"{est.residual_rms_m[i]:.4f}",
                    "yes" if est.trusted[i] else "not yet",
                ]
                for i, b in enumerate(est.beacons)
            ]
            waiting = ", ".join(
                f"{b} ({n} ranges)" for b, n in zip(est.waiting_beacons, est.waiting_ranges, strict=True)
            )
            untrusted = [
                f"beacon {b}: {m}"
                for b, ok, m in zip(est.beacons, est.trusted, est.trust_messages, strict=True)
                if not ok
            ]
            notes["estimate"] = (
                f"beacons estimated: {', '.join(str(b) for b in est.beacons) or 'none'}; waiting: "
                f"{waiting or 'none'}"
            )
            notes["estimate"] += "".join(f"; {m}" for m in untrusted)
        if origin is not None and plan is not None:
            sites, line = _plan_sites(plan["body"], origin)
            layers_kw["sites_en_m"] = sites
            notes["plan"] = f"{line} (from the survey run, {_utc(plan['t'] or 0.0)} UTC)"
        elif est is not None and est.n_beacons:
            try:
                wp = next_waypoint(records, self.settings, estimates=est, rng=np.random.default_rng(0))
                layers_kw["sites_en_m"] = np.vstack([wp.from_enu_m[:2], wp.waypoints_enu_m[:, :2]])
                notes["plan"] = (
                    f"next site ({wp.planner}, computed here): {wp.distance_m:.1f} m at "
                    f"{wp.bearing_deg:.0f}° true, lat {wp.next_geodetic[0]:.7f}°, "
                    f"lon {wp.next_geodetic[1]:.7f}°"
                )
            except DataError as exc:
                notes["plan"] = f"no next site: {exc}"
        with self.lock:
            track = self.track_en
            if origin is not None and self.origin is not None and origin != self.origin:
                self.origin = origin  # an earlier fix arrived late: a new frame, the pages start again
                f = self.tail.fixes
                enu = geodetic_to_enu(f[:, 1], f[:, 2], f[:, 3], origin).reshape(-1, 3)
                self.track_en, self.track_geo = np.round(enu[:, :2], 3), f[:, 1:3].copy()
                self.gen = f"{time.time_ns():x}"
                self.sigma_rows = np.zeros((0, 3))
                track = self.track_en
        idx = np.unique(np.linspace(0, track.shape[0] - 1, min(track.shape[0], MAX_TRACK_POINTS)).astype(int))
        layers = MapLayers(
            track_en_m=track[idx] if track.size else np.zeros((0, 2)),
            track_label="GPS track",
            sites_label="last fix (1) and planned sites in order",
            estimates=estimates,
            origin=origin,
            **layers_kw,
        )
        block = _map_block(layers)
        with self.lock:
            self.est_version += 1
            self.est_block = block
            self.table_rows = rows
            self.est_note = notes
            if sigma.size:
                self.sigma_rows = np.concatenate([self.sigma_rows, sigma])

    # -- answers --------------------------------------------------------------------------------------
    def data(self, query: dict[str, str]) -> dict:
        """The answer to ``/data?gen=&fix=&range=&sigma=&est=``: what the page lacks, and the status."""

        def num(key: str, default: int = 0) -> int:
            try:
                return max(int(query.get(key, default)), -1)
            except ValueError:
                return default

        self.last_request = time.monotonic()
        with self.lock:
            if query.get("gen") and query["gen"] != self.gen:
                return {"gen": self.gen}
            i, j, k, v = num("fix"), num("range"), num("sigma"), num("est", -1)
            tr, geo, rr, sg = self.track_en, self.track_geo, self.range_rows, self.sigma_rows
            out: dict[str, Any] = {"gen": self.gen}
            i2, j2, k2 = min(i + MAX_BATCH, tr.shape[0]), min(j + MAX_BATCH, rr.shape[0]), sg.shape[0]
            out["fix"] = {
                "to": i2,
                "e": tr[i:i2, 0].tolist(),
                "n": tr[i:i2, 1].tolist(),
                "geo": np.round(geo[i:i2], 8).tolist(),
            }
            out["range"] = {"to": j2, "by": _by_beacon(rr[j:j2, 0] * 1000.0, rr[j:j2, 1], rr[j:j2, 2])}
            out["sigma"] = {"to": k2, "by": _by_beacon(sg[k:k2, 0], sg[k:k2, 1], sg[k:k2, 2])}
            out["more"] = i2 < tr.shape[0] or j2 < rr.shape[0]
            if v != self.est_version and self.est_block:
                out["est"] = {"version": self.est_version, **self.est_block}
                out["table"] = self.table_rows
            n_fix, n_range = self.tail.fixes.shape[0], self.tail.ranges.shape[0]
            last = f", last fix {_utc(float(self.tail.fixes[-1, 0]))} UTC" if n_fix else ""
            link = self.tail.latest_event.get("link")
            out["status"] = {
                "records": f"{n_fix} fixes, {n_range} ranges, {self.tail.headings.shape[0]} headings{last}",
                **self.est_note,
                "link": "link: "
                + (
                    f"{_describe(link['body'])} ({_utc(link['t'] or 0.0)} UTC)"
                    if link
                    else ("no link event yet" if self.tail.has_events else "not recorded in this journal")
                ),
                "error": self.read_error,
            }
        return out


def _by_beacon(x: np.ndarray, beacon: np.ndarray, y: np.ndarray) -> dict[str, list]:
    """``{beacon: [x list, y list]}`` for each beacon present (a value that is not finite is null)."""
    shown = np.round(y, 4).astype(object)
    shown[~np.isfinite(y)] = None
    return {str(int(b)): [x[beacon == b].tolist(), shown[beacon == b].tolist()] for b in np.unique(beacon)}


def _map_block(layers: MapLayers) -> dict:
    """The map's traces and layout as plotly JSON, the track trace marked (``meta: "track"``) and empty:
    the page fills it with the points it holds."""
    fig = map_figure(layers)
    fig.update_layout(uirevision="live")
    block = json.loads(fig.to_json())
    track = [t for t in block["data"] if str(t.get("name", "")).startswith(layers.track_label)]
    if not track:  # no fix yet: the style of a drawn track, with no point
        style = MapLayers(track_en_m=np.zeros((1, 2)), track_label=layers.track_label, origin=layers.origin)
        empty = json.loads(map_figure(style).to_json())["data"]
        track = [t for t in empty if str(t.get("name", "")).startswith(layers.track_label)]
        block["data"].insert(0, track[0])
    track[0].update(meta="track", x=[], y=[], customdata=[], name=layers.track_label)
    return {"data": block["data"], "layout": block["layout"]}


TABLE_HEADER = (
    "beacon",
    "lat (deg)",
    "lon (deg)",
    "E (m)",
    "N (m)",
    "U (m)",
    "sigma E (m)",
    "sigma N (m)",
    "sigma U (m)",
    "95 % semi-major (m)",
    "95 % semi-minor (m)",
    "ranges used",
    "excluded",
    "residual RMS (m)",
    "ellipse trusted",
)

_SCRIPT = """
(() => {
const MAX_TRACK = %(max_track)d, WINDOW = %(window)d, POLL = %(poll)d, TRACK = %(track)s;
const S = {gen: null, fix: 0, range: 0, sigma: 0, est: -1, x: [], y: [], cd: [], keys: {r: {}, s: {}}};
const $ = id => document.getElementById(id);
function setText(id, s) { const e = $(id); if (e && e.textContent !== s) e.textContent = s; }
function drawn() {
  const n = S.x.length, step = Math.max(1, Math.ceil(n / MAX_TRACK));
  const t = {x: [], y: [], customdata: [], step};
  for (let i = 0; i < n; i += step) { t.x.push(S.x[i]); t.y.push(S.y[i]); t.customdata.push(S.cd[i]); }
  if (n && (n - 1) %% step) { t.x.push(S.x[n - 1]); t.y.push(S.y[n - 1]); t.customdata.push(S.cd[n - 1]); }
  t.name = step === 1 ? TRACK : `${TRACK} (${t.x.length} of ${n} points drawn)`;
  t.mode = step === 1 ? 'lines+markers' : 'lines';
  return t;
}
async function drawTrack(gd, added) {
  const i = gd.data.findIndex(t => t.meta === 'track');
  if (i < 0 || !added) return;
  if (S.x.length <= MAX_TRACK && gd.data[i].x.length === S.x.length - added) {
    await Plotly.extendTraces(gd, {x: [S.x.slice(-added)], y: [S.y.slice(-added)],
      customdata: [S.cd.slice(-added)]}, [i]);
  } else {
    const t = drawn();
    await Plotly.restyle(gd, {x: [t.x], y: [t.y], customdata: [t.customdata], name: [t.name],
      mode: [t.mode]}, [i]);
  }
}
async function extendByKey(gd, keys, by, label, unit, mode) {
  const idx = [], xs = [], ys = [];
  for (const [k, [x, y]] of Object.entries(by)) {
    if (!(k in keys)) {
      const hover = `${label(k)}<br>%%{x|%%H:%%M:%%S} UTC: %%{y:.4g} ${unit}<extra></extra>`;
      await Plotly.addTraces(gd, {type: 'scatter', mode, name: label(k), x: [], y: [],
        marker: {size: 4}, hovertemplate: hover});
      keys[k] = gd.data.length - 1;
    }
    idx.push(keys[k]); xs.push(x); ys.push(y);
  }
  if (idx.length) await Plotly.extendTraces(gd, {x: xs, y: ys}, idx, WINDOW);
}
function fillTable(rows) {
  const body = $('estimates').tBodies[0];
  body.replaceChildren(...rows.map(r => {
    const tr = document.createElement('tr');
    r.forEach((c, j) => { const td = document.createElement('td'); td.textContent = c;
      if (j > 0 && !isNaN(parseFloat(c))) td.className = 'num'; tr.appendChild(td); });
    return tr;
  }));
}
async function apply(d) {
  const map = $('map');
  const f = d.fix, added = f.e.length;
  for (let i = 0; i < added; i++) { S.x.push(f.e[i]); S.y.push(f.n[i]); S.cd.push(f.geo[i]); }
  S.fix = f.to;
  if (d.est) {
    const t = drawn();
    const data = d.est.data.map(tr => tr.meta === 'track' ? Object.assign({}, tr, t) : tr);
    await Plotly.react(map, data, d.est.layout);
    S.est = d.est.version;
    fillTable(d.table);
  } else {
    await drawTrack(map, added);
  }
  await extendByKey($('series-0'), S.keys.r, d.range.by, k => `beacon ${k}`, 'm', 'markers');
  S.range = d.range.to;
  await extendByKey($('series-1'), S.keys.s, d.sigma.by, k => `beacon ${k}`, 'm', 'lines+markers');
  S.sigma = d.sigma.to;
  for (const [k, v] of Object.entries(d.status)) setText(`live-${k}`, v);
  document.body.dataset.fixes = S.x.length;
  document.body.dataset.estimates = S.est;
}
async function poll() {
  let wait = POLL;
  try {
    const q = `gen=${S.gen || ''}&fix=${S.fix}&range=${S.range}&sigma=${S.sigma}&est=${S.est}`;
    const r = await fetch(`data?${q}`, {cache: 'no-store'});
    if (!r.ok) throw new Error(`HTTP ${r.status}`);
    const d = await r.json();
    if (S.gen !== null && d.gen !== S.gen) { location.reload(); return; }
    S.gen = d.gen;
    await apply(d);
    if (d.more) wait = 0;
    setText('live-connection', `connected, updated ${new Date().toISOString().slice(11, 19)} UTC`);
  } catch (e) {
    setText('live-connection', `no answer from the server (${e.message}); trying again`);
    wait = 3 * POLL;
  }
  setTimeout(poll, wait);
}
poll();
})();
"""


def live_page(tail: JournalTail) -> str:
    """The live page (plotly inlined): status lines, the map, the estimates table, the time series."""
    title = f"Live survey journal {tail.path.name}"
    empty_map = map_figure(MapLayers())
    empty_map.update_layout(uirevision="live")
    ranges = series_figure(
        Series(
            title=f"Ranges per ping (the latest {SERIES_WINDOW} per beacon)",
            x_label="time (UTC)",
            y_label="range (m)",
            lines=(),
        )
    )
    sigma = series_figure(
        Series(
            title="95 % ellipse semi-major axis at each update of the estimates",
            x_label="time of the last fix (UTC)",
            y_label="semi-major axis (m)",
            lines=(),
            log_y=True,
        )
    )
    for fig in (ranges, sigma):
        fig.update_xaxes(type="date")
    status = "".join(
        f'<li id="live-{k}">{html.escape(v)}</li>'
        for k, v in (
            ("connection", "connecting to the server"),
            ("records", "reading the journal"),
            ("estimate", "no estimate yet"),
            ("plan", "next site: none yet"),
            ("link", "link: not known yet"),
            ("error", ""),
        )
    )
    head = "".join(f"<th>{html.escape(h)}</th>" for h in TABLE_HEADER)
    settings = {k: v for k, v in tail.meta.items() if k != FORMAT_KEY}
    prov = "".join(
        f"<dt>{html.escape(k)}</dt><dd><code>{html.escape(v)}</code></dd>"
        for k, v in (("journal", str(tail.path)), ("settings", json.dumps(settings, sort_keys=True)))
    )
    script = _SCRIPT % {
        "max_track": MAX_TRACK_POINTS,
        "window": SERIES_WINDOW,
        "poll": CLIENT_POLL_MS,
        "track": json.dumps("GPS track"),
    }
    return "".join(
        [
            page_head(
                title,
                "live",
                csp=LIVE_CSP,
                head_extra=_HEAD_EXTRA,
            ),
            f'<ul class="summary" id="live-status">{status}</ul>',
            '<p class="note">Read-only: this page shows the journal as it is written and controls nothing. '
            "It asks the server for new records every second.</p>",
            '<h2>Map</h2><p class="note">East-north in metres about the frame\'s origin, equal scale; drag '
            "to pan, scroll to zoom, hover for values (the view is kept as records arrive).</p>",
            figure_div(empty_map, "map"),
            f'<h2>Beacon estimates</h2><table id="estimates"><thead><tr>{head}</tr></thead><tbody></tbody>'
            "</table>",
            "<h2>Time series</h2>",
            figure_div(ranges, "series-0"),
            figure_div(sigma, "series-1"),
            f'<h2>Provenance</h2><dl id="provenance">{prov}</dl>',
            f"<script>{script}</script></body></html>\n",
        ]
    )


def _is_loopback(host: str) -> bool:
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def _host_name(header: str) -> str:
    """The host of a ``Host`` header (``[::1]:8000`` -> ``::1``, ``localhost:80`` -> ``localhost``)."""
    if header.startswith("["):
        return header[1:].split("]", 1)[0]
    return header.rsplit(":", 1)[0] if header.count(":") == 1 else header


class _HttpServer(http.server.ThreadingHTTPServer):
    daemon_threads = True

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A browser that went away mid-answer is normal; anything else is logged, never printed."""
        _LOG.debug("live page: error answering %s", client_address, exc_info=True)


class _Handler(http.server.BaseHTTPRequestHandler):
    """GET and HEAD of ``/``, ``/data`` (JSON) and ``/favicon.ico`` (empty); 405 for any other method."""

    server_version = "oceanloc-live"
    protocol_version = "HTTP/1.1"
    live: _Live
    page: bytes
    any_host: bool

    def __getattr__(self, name: str) -> Any:
        if name.startswith("do_"):  # every method other than GET and HEAD
            return self._not_allowed
        raise AttributeError(name)

    def log_message(self, format: str, *args: Any) -> None:
        _LOG.debug("live page: " + format, *args)

    def _send(self, code: int, body: bytes, content_type: str, *, head: bool = False, **extra: str) -> None:
        self.send_response(code)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")
        for k, v in extra.items():
            self.send_header(k.replace("_", "-"), v)
        self.end_headers()
        if not head:
            self.wfile.write(body)

    def _not_allowed(self) -> None:
        self._send(405, b"read-only: GET and HEAD only\n", "text/plain; charset=utf-8", Allow="GET, HEAD")

    def do_HEAD(self) -> None:
        self._answer(head=True)

    def do_GET(self) -> None:
        self._answer(head=False)

    def _answer(self, *, head: bool) -> None:
        host = _host_name(self.headers.get("Host") or "")
        if not self.any_host and not _is_loopback(host):
            self._send(
                403, b"this page answers loopback requests only\n", "text/plain; charset=utf-8", head=head
            )
            return
        url = urllib.parse.urlsplit(self.path)
        if url.path in ("/", "/index.html"):
            self._send(
                200, self.page, "text/html; charset=utf-8", head=head, Content_Security_Policy=LIVE_CSP
            )
        elif url.path == "/data":
            query = dict(urllib.parse.parse_qsl(url.query))
            body = json.dumps(self.live.data(query), allow_nan=False, separators=(",", ":")).encode()
            self._send(200, body, "application/json", head=head)
        elif url.path == "/favicon.ico":
            self._send(204, b"", "image/x-icon", head=True)
        else:
            self._send(404, b"not found\n", "text/plain; charset=utf-8", head=head)


class LiveServer:
    """The live page of one journal, served from a background thread (a context manager).

    Use :func:`serve_journal` to make and start one; :meth:`stop` ends it (and its threads).

    Attributes
    ----------
    url : str
        ``http://HOST:PORT/`` once started (the port the system chose when 0 was asked).
    """

    def __init__(
        self,
        journal_path: str | Path,
        port: int,
        host: str = "127.0.0.1",
        *,
        allow_remote: bool = False,
        estimate_period_s: float = ESTIMATE_PERIOD_S,
    ) -> None:
        if not (0 <= int(port) <= 65535):
            raise ConfigError(f"port {port} is not in [0, 65535] (0: any free port)")
        if not allow_remote and not _is_loopback(host):
            raise ConfigError(
                f"refusing to serve the live page on {host}: it is served on loopback only (127.0.0.1, ::1, "
                "localhost), since anyone who can reach the port can read the survey; give allow_remote "
                "(--allow-remote) to serve other hosts"
            )
        self.host, self.port = host, int(port)
        self.allow_remote = allow_remote
        self.tail = JournalTail(journal_path)
        self._live = _Live(self.tail, estimate_period_s)
        self._page = live_page(self.tail).encode("utf-8")
        self._httpd: _HttpServer | None = None
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    def start(self) -> LiveServer:
        """Bind, read the journal once, and start serving (returns self; a second call does nothing).

        Raises
        ------
        DataError
            If the port cannot be bound (in use, not permitted).
        """
        if self._httpd is not None:
            return self
        handler = type(
            "LiveHandler",
            (_Handler,),
            {"live": self._live, "page": self._page, "any_host": self.allow_remote},
        )
        server_cls = _HttpServer
        if ":" in self.host:
            server_cls = type("_HttpServer6", (_HttpServer,), {"address_family": socket.AF_INET6})
        try:
            self._httpd = server_cls((self.host, self.port), handler)
        except OSError as exc:
            raise DataError(
                f"cannot serve the live page on {self.host}:{self.port}: {exc.strerror or exc}"
            ) from None
        self.port = int(self._httpd.server_address[1])
        self._live.read()
        self._live.dirty.set()  # the first map, even of a journal with no record yet
        self._stop.clear()
        self._threads = [
            threading.Thread(target=self._httpd.serve_forever, kwargs={"poll_interval": 0.2}, daemon=True),
            threading.Thread(target=self._read_loop, daemon=True),
            threading.Thread(target=self._estimate_loop, daemon=True),
        ]
        for t in self._threads:
            t.start()
        return self

    def _read_loop(self) -> None:
        while not self._stop.wait(POLL_S):
            self._live.read()

    def _estimate_loop(self) -> None:
        """Re-estimate when ranges (or a plan) arrived, or when only fixes did and :data:`FIX_REFRESH_S`
        passed; at most every period (longer when estimating is slow: it takes at most a third of a core),
        and only while a page is watching (or before the first page)."""
        live = self._live
        wait = 0.0
        while not self._stop.wait(wait):
            wait = 0.0
            refresh = live.moved and time.monotonic() - live.estimated_at >= FIX_REFRESH_S
            if not live.dirty.wait(0.2) and not refresh:
                continue
            if live.est_version and not live.watched():
                continue
            live.dirty.clear()
            live.moved = False
            t0 = live.estimated_at = time.monotonic()
            try:
                live.estimate()
            except Exception:  # a failed estimate must not end the page; the next may work
                _LOG.warning("live page: estimate failed", exc_info=True)
            wait = max(live.period_s, 2.0 * (time.monotonic() - t0))

    def stop(self) -> None:
        """Stop serving and join the threads (idempotent)."""
        self._stop.set()
        if self._httpd is not None:
            self._httpd.shutdown()
            self._httpd.server_close()
            self._httpd = None
        for t in self._threads:
            t.join(timeout=30.0)
        self._threads = []

    def wait(self, signals: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM)) -> int:
        """Serve until one of ``signals`` arrives (main thread only), then stop; returns the signal."""
        got: list[int] = []
        done = threading.Event()

        def on_signal(signum: int, frame: Any) -> None:
            got.append(signum)
            done.set()

        old = {s: signal.signal(s, on_signal) for s in signals}
        try:
            while not done.wait(0.5):
                pass
        finally:
            for s, h in old.items():
                signal.signal(s, h)
            self.stop()
        return got[0]

    def __enter__(self) -> LiveServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


def serve_journal(
    journal_path: str | Path,
    port: int,
    host: str = "127.0.0.1",
    *,
    allow_remote: bool = False,
    estimate_period_s: float = ESTIMATE_PERIOD_S,
) -> LiveServer:
    """Serve the live page of the journal at ``journal_path`` on ``host:port`` (started; stop it, or use
    it as a context manager). ``port`` 0 picks a free port (see :attr:`LiveServer.url`).

    Raises
    ------
    ConfigError
        If ``host`` is not loopback and ``allow_remote`` is not given, or the port is out of range.
    DataError
        If the journal is missing or not a started survey journal, or the port cannot be bound.
    """
    server = LiveServer(
        journal_path, port, host, allow_remote=allow_remote, estimate_period_s=estimate_period_s
    )
    return server.start()
