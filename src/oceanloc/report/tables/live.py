"""The live survey's status line (one per epoch), its notices and its closing summary."""

from __future__ import annotations

import datetime as dt

import numpy as np
from rich.markup import escape

from oceanloc.field.live_survey import Epoch, LiveSurveyResult, Notice
from oceanloc.report.tables.survey_journal import journal_estimates_table


def _clock(t_unix_s: float) -> str:
    return dt.datetime.fromtimestamp(t_unix_s, dt.UTC).strftime("%H:%M:%S")


def epoch_line(e: Epoch) -> str:
    """``12:03:04 #57 | b1 E+120.31 N+79.92 U-60.70 σ0.18/0.07/0.43 a95 0.45 ok | next 32.7012345
    -117.2456789 34 m 045° +0.31 nat | position ok ranges ok vehicle GUIDED | 12 ms``.

    Per beacon: ENU estimate (m), 1-sigma E/N/U (m), 95 % ellipse semi-major axis (m) and its state:
    ``goal`` (met), ``ok`` (trusted), ``!`` (not trusted yet); then the next site (latitude, longitude,
    distance, true bearing, expected information gain), the streams and the vehicle's mode, and the
    latency from the range to the command.
    """
    parts = [f"{_clock(e.t_unix_s)} #{e.number}"]
    est = e.estimates
    if est is not None:
        for i, b in enumerate(est.beacons):
            p, s = est.positions_enu_m[i], est.sigma_enu_m[i]
            met = i < len(e.stop.met) and e.stop.met[i]
            state = "goal" if met else ("ok" if est.trusted[i] else "!")
            parts.append(
                f"b{b} E{p[0]:+.2f} N{p[1]:+.2f} U{p[2]:+.2f} σ{s[0]:.2f}/{s[1]:.2f}/{s[2]:.2f} "
                f"a95 {est.ellipses.semi_major_m[i]:.2f} {state}"
            )
        for b, c in zip(est.waiting_beacons, est.waiting_ranges, strict=True):
            parts.append(f"b{b} waiting ({c} ranges)")
    w = e.waypoint
    if w is not None:
        site = e.site
        lat, lon = (site.lat_deg, site.lon_deg) if site is not None and site.ok else w.next_geodetic[:2]
        clipped = " clipped" if site is not None and site.status == "clipped" else ""
        parts.append(
            f"next {lat:.7f} {lon:.7f} {w.distance_m:.0f} m {w.bearing_deg:03.0f}° "
            f"+{w.objective_nats:.2f} nat{clipped}"
        )
    links = " ".join(f"{k} {v}" for k, v in e.links.items())
    parts.append(links)
    tail = f"{e.latency_ms:.0f} ms"
    if e.command is not None:
        tail = f"{e.command.status} {tail}"
    if e.note:
        tail += f" ({e.note})"
    parts.append(tail)
    return escape(" | ".join(parts))


def notice_line(n: Notice) -> str:
    """A notice: its time, kind and message."""
    return escape(f"{_clock(n.t_unix_s)} {n.kind}: {n.message}")


def result_lines(r: LiveSurveyResult) -> list[str]:
    """The closing summary: why it stopped, epochs and sites, latency."""
    lat = r.latencies_ms
    lines = [
        escape(f"survey {r.status}: {r.message}"),
        f"{r.epochs} epochs this run{' (resumed)' if r.resumed else ''}; {r.sites} sites commanded in all",
    ]
    if lat.size:
        lines.append(
            f"range to command: median {np.median(lat):.1f} ms, 95th percentile "
            f"{np.percentile(lat, 95):.1f} ms over {lat.size} epochs"
        )
    return lines


def result_table(r: LiveSurveyResult):
    """The final estimates (the ``survey status`` table), or None before any."""
    if r.estimates is None or r.estimates.n_beacons == 0:
        return None
    return journal_estimates_table(r.estimates)
