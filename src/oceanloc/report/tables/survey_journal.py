"""Terminal tables (rich) of the survey journal: ``survey status`` (settings, counts, estimates with
their 95 % ellipses, range status) and ``survey next`` (the planned sites).

Every numeric column header states its unit; text that comes from a user is escaped; each table fits 100
columns. Bearings and headings are degrees clockwise from true north. Kept apart from :mod:`.field` so
that ``survey status`` imports only what it draws.
"""

from __future__ import annotations

import numpy as np
from rich import box
from rich.markup import escape
from rich.table import Table

from oceanloc.field.survey.estimates import MIN_RANGES, RANGE_STATUS, JournalStatus, SurveyEstimates, Waypoint
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.geo.enu import EnuOrigin
from oceanloc.io.usbl import format_utc
from oceanloc.planning.site_planners import parse_site_planner, site_planner_label
from oceanloc.units import DEG


def compact_table(title: str) -> Table:
    """A compact table (rules under the header only) so wide rows fit 100 columns."""
    return Table(title=title, box=box.SIMPLE_HEAD, pad_edge=False, collapse_padding=True)


def origin_text(origin: EnuOrigin, how: str = "") -> str:
    """``32.7050000, -117.2360000, -1.478 m`` (latitude, longitude in degrees, height in metres), with how
    it was chosen in parentheses."""
    text = f"{origin.lat_deg:.7f}, {origin.lon_deg:.7f}, {origin.h_m:.3f} m"
    return f"{text} ({how})" if how else text


def journal_settings_text(s: JournalSettings) -> str:
    """One line describing a survey's settings: planner (its one label), reach or vehicle, sigma, origin,
    beacons."""
    p = s.planner
    plan = site_planner_label(p)
    if p.kind in ("lookahead", "random-yaw"):
        plan += f", w_max {s.max_yaw_rate_rad_s / DEG:g} deg/s, {s.speed_mps:g} m/s, T {s.period_s:g} s"
    else:
        plan += f", d_max {p.max_distance_m:g} m"
    origin = "earliest fix" if s.origin is None else origin_text(s.origin, "given")
    beacons = ", ".join(map(str, s.beacons)) or "any"
    return escape(f"planner {plan}; sigma {s.sigma_range_m:g} m; origin {origin}; beacons {beacons}")


def journal_status_lines(st: JournalStatus) -> list[str]:
    """``survey status``: the journal, its settings, and its records' counts and time span."""
    rec = st.records
    span = (
        f", {format_utc(rec.first_fix_t_unix_s)} to {format_utc(rec.last_fix_t_unix_s)}"
        if rec.n_fixes
        else ""
    )
    return [
        f"survey {escape(st.path)}: {journal_settings_text(st.settings)}",
        f"{rec.n_fixes} fixes{span}, {rec.n_headings} headings, {rec.n_ranges} ranges",
    ]


def journal_estimates_table(est: SurveyEstimates, origin_source: str = "") -> Table:
    """``survey status``: per beacon the estimate (ENU and latitude/longitude), 1-sigma, 95 % ellipse
    semi-axes and the major axis' azimuth (clockwise from north), ranges used and excluded, and whether
    the ellipse can be trusted (``!`` after it where the range model's linearization check fails)."""
    table = compact_table(f"Beacons, ENU from {origin_text(est.origin, origin_source)}")
    table.caption = (
        "95% a/b: ellipse semi-axes (! not trusted: the range model bends over it, see below);"
        " az: its major axis, clockwise from true north"
    )
    cols = ("beacon", "E m", "N m", "U m", "lat deg", "lon deg", "1σ E/N/U m", "95% a/b m", "az deg")
    cols = (*cols, "used/excl")
    for col in cols:
        table.add_column(col, justify="right")
    for i, b in enumerate(est.beacons):
        table.add_row(
            str(b),
            *(f"{v:+.2f}" for v in est.positions_enu_m[i]),
            f"{est.positions_geodetic[i, 0]:.6f}",
            f"{est.positions_geodetic[i, 1]:.6f}",
            "/".join(f"{v:.2f}" for v in est.sigma_enu_m[i]),
            f"{est.ellipses.semi_major_m[i]:.2f}/{est.ellipses.semi_minor_m[i]:.2f}"
            + ("" if est.trusted[i] else "!"),
            f"{est.ellipse_azimuth_deg[i]:.0f}",
            f"{est.ranges_used[i]}/{est.ranges_excluded[i]}",
        )
    return table


def journal_range_lines(est: SurveyEstimates) -> list[str]:
    """The ranges' status counts and the beacons still waiting for ranges."""
    counts = np.bincount(est.range_status, minlength=len(RANGE_STATUS))
    lines = ["ranges: " + ", ".join(f"{c} {label}" for label, c in zip(RANGE_STATUS, counts, strict=True))]
    lines += [
        f"beacon {b}: {c} ranges with GPS, needs {MIN_RANGES}"
        for b, c in zip(est.waiting_beacons, est.waiting_ranges, strict=True)
    ]
    lines += [
        f"beacon {b}: {msg} (linearity {stat:.2f}, trusted up to {np.log(2.0):.2f})"
        for b, ok, msg, stat in zip(est.beacons, est.trusted, est.trust_messages, est.linearity, strict=True)
        if not ok
    ]
    return lines


def waypoint_table(w: Waypoint) -> Table:
    """``survey next``: the start and every planned site, ENU and latitude/longitude, with the heading of
    each leg (degrees clockwise from true north)."""
    label = site_planner_label(parse_site_planner(w.planner))
    title = f"Next waypoint ({label}, from the fix of {format_utc(w.from_t_unix_s)})"
    if w.origin is not None:
        title += f", ENU from {origin_text(w.origin)}"
    table = compact_table(title)
    for col in ("site", "E m", "N m", "U m", "lat deg", "lon deg", "heading deg"):
        table.add_column(col, justify="right")
    e, n, u = w.from_enu_m
    now = "" if w.from_heading_deg is None else f"{w.from_heading_deg:.1f} ({w.heading_source})"
    table.add_row("now", f"{e:+.2f}", f"{n:+.2f}", f"{u:+.2f}", "", "", now)
    headings = w.planned_headings_deg
    for i, (p, g) in enumerate(zip(w.waypoints_enu_m, w.waypoints_geodetic, strict=True)):
        table.add_row(
            "next" if i == 0 else f"+{i + 1}",
            *(f"{v:+.2f}" for v in p),
            f"{g[0]:.7f}",
            f"{g[1]:.7f}",
            f"{headings[i]:.1f}",
        )
    return table


def waypoint_line(w: Waypoint) -> str:
    """Where to go: distance, bearing (clockwise from true north), position and information gain."""
    return (
        f"go {w.distance_m:.2f} m on bearing {w.bearing_deg:.1f} deg (clockwise from true north) to "
        f"{w.next_geodetic[0]:.7f}, {w.next_geodetic[1]:.7f}; expected information gain "
        f"{w.objective_nats:.4f} nats over beacons {', '.join(map(str, w.beacons))}"
        + (
            f" (ellipse of beacon {', '.join(map(str, w.untrusted_beacons))} not trusted yet: planned on"
            " its linearized covariance)"
            if w.untrusted_beacons.size
            else ""
        )
    )
