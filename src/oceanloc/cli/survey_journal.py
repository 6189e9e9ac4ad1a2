"""``oceanloc survey``: a field survey journal (start, add, next, status, export).

Every fix, heading and range goes into an SQLite journal, one transaction per record
(:mod:`oceanloc.io.journal`); the estimates and the next waypoint are computed from the journal alone
(:mod:`oceanloc.field.survey_journal`), so a killed process loses nothing committed and a re-run gives the
same numbers.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from oceanloc.cli import root
from oceanloc.cli._common import console, err_console, write_json
from oceanloc.config.survey import PlannerSettings
from oceanloc.config.survey_journal import JournalSettings
from oceanloc.errors import ConfigError
from oceanloc.field.survey_journal import (
    MIN_RANGES,
    RANGE_STATUS,
    SurveyEstimates,
    Waypoint,
    next_waypoint,
    survey_estimates,
)
from oceanloc.geo.enu import EnuOrigin
from oceanloc.io.journal import AppendCounts, Journal, append_gps_log, append_range_log
from oceanloc.io.nmea import read_nmea
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import format_utc, read_usbl
from oceanloc.units import DEG

app = typer.Typer(
    help="Survey journal: record fixes and ranges as they arrive, estimate the beacons, plan the next site.",
    no_args_is_help=True,
)
root.app.add_typer(app, name="survey")

PLANNERS = ("greedy", "lookahead", "random", "random-disk", "random-yaw")
"""``--planner`` choices; ``random`` is the random point within ``d_max`` (``random-disk``)."""

MAX_RANGE_M = 10_000.0

JournalArg = Annotated[Path, typer.Argument(help="The survey journal (an SQLite file).", show_default=False)]


@app.command("start")
def start(
    journal: JournalArg,
    planner: Annotated[
        str, typer.Option(help="Planner: greedy | lookahead | random (random-disk) | random-yaw.")
    ] = "greedy",
    horizon: Annotated[int, typer.Option("--horizon", "-k", help="Look-ahead steps k (lookahead).")] = 2,
    max_distance: Annotated[float, typer.Option(help="Reach d_max between sites, m (greedy, random).")] = 5.0,
    max_yaw_rate: Annotated[
        float, typer.Option(help="Yaw-rate limit w_max, deg/s (lookahead, random-yaw).")
    ] = 30.0,
    speed: Annotated[float, typer.Option(help="Vehicle speed, m/s (lookahead, random-yaw).")] = 1.0,
    period: Annotated[
        float, typer.Option(help="Time between planned sites, s (lookahead, random-yaw).")
    ] = 5.0,
    sigma_range: Annotated[float, typer.Option(help="Total range sigma (USBL and GPS), m.")] = 1.006,
    origin: Annotated[
        str | None, typer.Option(help="ENU origin LAT,LON,H (deg, deg, m); default: the earliest fix.")
    ] = None,
    beacon: Annotated[
        list[int] | None, typer.Option("--beacon", help="A beacon id of the survey (repeat); default: any.")
    ] = None,
    prior_sigma: Annotated[str, typer.Option(help="Prior 1-sigma E,N,U around the nearest range, m.")] = (
        "100,100,10"
    ),
    prior_depth: Annotated[float, typer.Option(help="Prior depth below the antenna, m.")] = 2.0,
    heading: Annotated[
        float | None,
        typer.Option(help="Start heading, deg clockwise from north (until HDT or two fixes give one)."),
    ] = None,
    sound_speed: Annotated[
        float, typer.Option(help="Sound speed for travel-time range files, m/s.")
    ] = 1500.0,
    max_gap: Annotated[float, typer.Option(help="Largest GPS gap to interpolate a range across, s.")] = 2.0,
) -> None:
    """Start a survey: create the journal and store its settings (never overwritten later)."""
    if planner not in PLANNERS:
        raise ConfigError(f"--planner: expected one of {', '.join(PLANNERS)}, got {planner!r}")
    kind = "random-disk" if planner == "random" else planner
    o = None
    if origin is not None:
        lat, lon, h = _fields(origin, ("LAT", "LON", "H"), f"--origin {origin!r}")
        o = EnuOrigin(lat_deg=lat, lon_deg=lon, h_m=h)
    settings = JournalSettings(
        planner=PlannerSettings(kind=kind, horizon=horizon, max_distance_m=max_distance),  # type: ignore[arg-type]
        max_yaw_rate_rad_s=max_yaw_rate * DEG,
        speed_mps=speed,
        period_s=period,
        sigma_range_m=sigma_range,
        origin=o,
        beacons=tuple(beacon or ()),
        prior_sigma_enu_m=_fields(prior_sigma, ("E", "N", "U"), f"--prior-sigma {prior_sigma!r}"),  # type: ignore[arg-type]
        prior_depth_m=prior_depth,
        heading_deg=heading,
        sound_speed_mps=sound_speed,
        max_gap_s=max_gap,
    )
    with Journal.start(journal, settings.to_meta()):
        pass
    console.print(f"started survey journal {journal}: {_describe(settings)}", highlight=False)


@app.command("add")
def add(
    journal: JournalArg,
    nmea: Annotated[list[Path] | None, typer.Option("--nmea", help="NMEA 0183 GPS log (repeat).")] = None,
    ranges: Annotated[
        list[Path] | None, typer.Option("--ranges", help="USBL range CSV (utc,beacon,range_m|owtt_s|twtt_s).")
    ] = None,
    fix: Annotated[
        list[str] | None,
        typer.Option("--fix", help="One fix T,LAT,LON,H (T: UTC ISO 8601 or Unix seconds; repeat)."),
    ] = None,
    range_: Annotated[
        list[str] | None, typer.Option("--range", help="One range T,BEACON,R (R in metres; repeat).")
    ] = None,
) -> None:
    """Append records, one transaction each; bad lines are skipped and listed, re-adds change nothing."""
    if not (nmea or ranges or fix or range_):
        raise ConfigError(
            "nothing to add: give --nmea FILE, --ranges FILE, --fix T,LAT,LON,H or --range T,BEACON,R"
        )
    with Journal.open(journal) as j:
        settings = JournalSettings.from_meta(j.meta(), str(journal))
        known = settings.beacons or None
        # Read and check everything before the first write: an error leaves the journal as it was.
        fixes = [_parse_fix(text) for text in fix or []]
        manual_ranges = [_parse_range(text, known) for text in range_ or []]
        qc = QcReport()
        gps_logs = [(p, read_nmea(p, qc=qc)) for p in nmea or []]
        range_logs = [
            (p, read_usbl(p, sound_speed_mps=settings.sound_speed_mps, beacons=known, qc=qc))
            for p in ranges or []
        ]
        for path, log in gps_logs:
            fix_counts, head_counts = append_gps_log(j, log, path, qc)
            console.print(f"{path}: {fix_counts}, {head_counts}", highlight=False)
        for path, log in range_logs:
            console.print(f"{path}: {append_range_log(j, log, path, qc)}", highlight=False)
        if fixes:
            console.print(
                f"--fix: {_add_manual(fixes, j.add_fix, lambda f: j.fix_at(f[0]) == f[1:], 'fixes')}"
            )
        if manual_ranges:
            same = lambda r: j.range_at(r[0], r[1]) == r[2]  # noqa: E731
            console.print(f"--range: {_add_manual(manual_ranges, j.add_range, same, 'ranges')}")
        if qc.issues:
            err_console.print("QC: " + qc.summary(max_lines=50), highlight=False)
        rec = j.records()
    console.print(
        f"journal {journal}: {rec.n_fixes} fixes, {rec.heading_deg.size} headings, {rec.n_ranges} ranges",
        highlight=False,
    )


@app.command("next")
def next_(
    journal: JournalArg,
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the waypoint as JSON here.")] = None,
    seed: Annotated[
        int, typer.Option(min=0, help="Seed of the random planners (with the record counts).")
    ] = 0,
) -> None:
    """The next waypoint (ENU and latitude/longitude) from the current estimates and the survey's planner."""
    with Journal.open(journal) as j:
        settings = JournalSettings.from_meta(j.meta(), str(journal))
        rec = j.records()
    rng = np.random.default_rng([seed, rec.n_fixes, rec.n_ranges])
    w = next_waypoint(rec, settings, rng=rng)
    table = Table(title=f"Next waypoint ({w.planner}, from the fix of {format_utc(w.from_t_unix_s)})")
    for col in ("site", "E m", "N m", "U m", "lat deg", "lon deg", "heading deg"):
        table.add_column(col, justify="right")
    e, n, u = w.from_enu_m
    now_heading = "" if w.heading_source == "unused" else f"{_heading(w.yaw_rad)} ({w.heading_source})"
    table.add_row("now", f"{e:+.2f}", f"{n:+.2f}", f"{u:+.2f}", "", "", now_heading)
    headings = _planned_headings(w)
    for i, (p, g) in enumerate(zip(w.waypoints_enu_m, w.waypoints_geodetic, strict=True)):
        table.add_row(
            "next" if i == 0 else f"+{i + 1}",
            *(f"{v:+.2f}" for v in p),
            f"{g[0]:.7f}",
            f"{g[1]:.7f}",
            f"{headings[i]:.1f}",
        )
    console.print(table)
    console.print(
        f"go {w.distance_m:.2f} m on bearing {w.bearing_deg:.1f} deg to {w.next_geodetic[0]:.7f}, "
        f"{w.next_geodetic[1]:.7f}; expected information gain {w.objective_nats:.4f} nats over beacons "
        f"{', '.join(map(str, w.beacons))}",
        highlight=False,
    )
    if json_path is not None:
        write_json(json_path, waypoint_json(w))


@app.command("status")
def status(
    journal: JournalArg,
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Write the estimates as JSON here.")
    ] = None,
) -> None:
    """Per beacon: estimate E/N/U and lat/lon, 1-sigma, 95% ellipse, ranges used and excluded."""
    with Journal.open(journal) as j:
        settings = JournalSettings.from_meta(j.meta(), str(journal))
        rec = j.records()
    console.print(f"survey {journal}: {_describe(settings)}", highlight=False)
    span = (
        f", {format_utc(float(rec.fix_t_unix_s[0]))} to {format_utc(float(rec.fix_t_unix_s[-1]))}"
        if rec.n_fixes
        else ""
    )
    console.print(
        f"{rec.n_fixes} fixes{span}, {rec.heading_deg.size} headings, {rec.n_ranges} ranges", highlight=False
    )
    if rec.n_fixes == 0:
        console.print("no GPS fix yet: nothing to estimate")
        return
    est = survey_estimates(rec, settings)
    _print_estimates(est)
    counts = np.bincount(est.range_status, minlength=len(RANGE_STATUS))
    console.print(
        "ranges: " + ", ".join(f"{c} {label}" for label, c in zip(RANGE_STATUS, counts, strict=True)),
        highlight=False,
    )
    for b, c in zip(est.waiting_beacons, est.waiting_ranges, strict=True):
        console.print(f"beacon {b}: {c} ranges with GPS, needs {MIN_RANGES}", highlight=False)
    if json_path is not None:
        write_json(json_path, estimates_json(est))


@app.command("export")
def export(
    journal: JournalArg,
    geojson: Annotated[
        Path | None, typer.Option("--geojson", help="GeoJSON file: beacons, 95% ellipses, track.")
    ] = None,
    csv: Annotated[
        Path | None,
        typer.Option("--csv", help="Folder for fixes.csv, headings.csv, ranges.csv, estimates.csv."),
    ] = None,
) -> None:
    """Export the beacon estimates with their 95% ellipses and the track (GeoJSON), and every table (CSV)."""
    from oceanloc.field.survey_journal_export import export_csv, export_geojson

    if geojson is None and csv is None:
        raise ConfigError("nothing to export: give --geojson PATH and/or --csv DIR")
    with Journal.open(journal) as j:
        settings = JournalSettings.from_meta(j.meta(), str(journal))
        rec = j.records()
    est = survey_estimates(rec, settings)
    if geojson is not None:
        path = export_geojson(geojson, rec, est)
        console.print(f"wrote {path} ({est.n_beacons} beacons with ellipses, track of {rec.n_fixes} fixes)")
    if csv is not None:
        paths = export_csv(csv, rec, est)
        console.print(f"wrote {', '.join(p.name for p in paths)} in {csv}", highlight=False)


def _add_manual(
    records: Sequence[tuple], add: Callable[..., bool], same: Callable[[tuple], bool], kind: str
) -> AppendCounts:
    """Append records given on the command line; one already stored with other values is kept as stored."""
    new = old = 0
    for rec in records:
        if add(*rec):
            new += 1
        elif same(rec):
            old += 1
        else:
            err_console.print(f"{kind[:-1]} {rec}: another value is stored for this key; kept as stored")
    return AppendCounts(kind=kind, new=new, already_stored=old, conflicting=len(records) - new - old)


def estimates_json(est: SurveyEstimates) -> dict:
    """The ``status --json`` payload."""
    beacons = []
    for i, b in enumerate(est.beacons):
        beacons.append(
            {
                "beacon": int(b),
                "enu_m": est.positions_enu_m[i],
                "sigma_enu_m": est.sigma_enu_m[i],
                "covariance_enu_m2": est.covariances_m2[i],
                "lat_deg": est.positions_geodetic[i, 0],
                "lon_deg": est.positions_geodetic[i, 1],
                "h_m": est.positions_geodetic[i, 2],
                "ellipse95_semi_major_m": est.ellipses.semi_major_m[i],
                "ellipse95_semi_minor_m": est.ellipses.semi_minor_m[i],
                "ellipse95_major_azimuth_deg": est.ellipse_azimuth_deg[i],
                "ranges_used": est.ranges_used[i],
                "ranges_excluded": est.ranges_excluded[i],
                "residual_rms_m": est.residual_rms_m[i],
            }
        )
    o = est.origin
    return {
        "origin": {"lat_deg": o.lat_deg, "lon_deg": o.lon_deg, "h_m": o.h_m},
        "beacons": beacons,
        "waiting": {str(b): int(c) for b, c in zip(est.waiting_beacons, est.waiting_ranges, strict=True)},
        "ranges": dict(
            zip(
                RANGE_STATUS, np.bincount(est.range_status, minlength=len(RANGE_STATUS)).tolist(), strict=True
            )
        ),
    }


def waypoint_json(w: Waypoint) -> dict:
    """The ``next --json`` payload."""
    sites = [
        {"e_m": p[0], "n_m": p[1], "u_m": p[2], "lat_deg": g[0], "lon_deg": g[1], "h_m": g[2]}
        for p, g in zip(w.waypoints_enu_m, w.waypoints_geodetic, strict=True)
    ]
    return {
        "planner": w.planner,
        "from": {
            "utc": format_utc(w.from_t_unix_s),
            "enu_m": w.from_enu_m,
            "heading_deg": None if w.heading_source == "unused" else float(_heading(w.yaw_rad)),
        },
        "heading_source": w.heading_source,
        "next": sites[0] | {"heading_deg": w.next_heading_deg},
        "distance_m": w.distance_m,
        "bearing_deg": w.bearing_deg,
        "waypoints": sites,
        "yaw_rates_deg_s": None if w.yaw_rates_rad_s is None else w.yaw_rates_rad_s / DEG,
        "objective_nats": w.objective_nats,
        "beacons": w.beacons,
        "status": w.status.value,
    }


def _print_estimates(est: SurveyEstimates) -> None:
    o = est.origin
    table = Table(title=f"Beacons (ENU from {o.lat_deg:.7f}, {o.lon_deg:.7f}, {o.h_m:.3f} m)")
    cols = (
        "beacon",
        "E m",
        "N m",
        "U m",
        "lat deg",
        "lon deg",
        "1σ E/N/U m",
        "95% a/b m",
        "az deg",
        "used/excl",
    )
    for col in cols:
        table.add_column(col, justify="right")
    for i, b in enumerate(est.beacons):
        table.add_row(
            str(b),
            *(f"{v:+.2f}" for v in est.positions_enu_m[i]),
            f"{est.positions_geodetic[i, 0]:.7f}",
            f"{est.positions_geodetic[i, 1]:.7f}",
            "/".join(f"{v:.2f}" for v in est.sigma_enu_m[i]),
            f"{est.ellipses.semi_major_m[i]:.2f}/{est.ellipses.semi_minor_m[i]:.2f}",
            f"{est.ellipse_azimuth_deg[i]:.0f}",
            f"{est.ranges_used[i]}/{est.ranges_excluded[i]}",
        )
    console.print(table)


def _describe(s: JournalSettings) -> str:
    p = s.planner
    if p.kind == "lookahead":
        plan = f"lookahead k={p.horizon}, w_max {s.max_yaw_rate_rad_s / DEG:g} deg/s"
    elif p.kind == "random-yaw":
        plan = f"random-yaw, w_max {s.max_yaw_rate_rad_s / DEG:g} deg/s"
    else:
        plan = f"{p.kind}, d_max {p.max_distance_m:g} m"
    if p.kind in ("lookahead", "random-yaw"):
        plan += f", {s.speed_mps:g} m/s, T {s.period_s:g} s"
    origin = (
        "earliest fix" if s.origin is None else f"{s.origin.lat_deg}, {s.origin.lon_deg}, {s.origin.h_m} m"
    )
    beacons = ", ".join(map(str, s.beacons)) or "any"
    return f"planner {plan}; sigma {s.sigma_range_m:g} m; origin {origin}; beacons {beacons}"


def _heading(yaw_rad: float) -> str:
    return f"{(90.0 - yaw_rad / DEG) % 360.0:.1f}"


def _planned_headings(w: Waypoint) -> list[float]:
    sites = np.vstack([w.from_enu_m, w.waypoints_enu_m])
    step = np.diff(sites, axis=0)
    return [float((90.0 - math.degrees(math.atan2(d[1], d[0]))) % 360.0) for d in step]


def _fields(text: str, names: tuple[str, ...], where: str) -> tuple[float, ...]:
    """Comma-separated finite numbers, one per name; errors start with ``where`` and name the field."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != len(names):
        raise ConfigError(f"{where}: expected {','.join(names)} ({len(names)} values), got {len(parts)}")
    return tuple(_number(part, name, where) for name, part in zip(names, parts, strict=True))


def _number(text: str, name: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(f"{where}: {name} {text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise ConfigError(f"{where}: {name} is NaN or infinite")
    return value


def _parse_time(text: str, where: str) -> float:
    text = text.strip()
    try:
        return _number(text, "T", where)
    except ConfigError as exc:
        if "NaN" in str(exc):
            raise
    try:
        stamp = dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise ConfigError(f"{where}: T {text!r} is neither ISO 8601 UTC nor Unix seconds") from None
    return (stamp if stamp.tzinfo else stamp.replace(tzinfo=dt.UTC)).timestamp()


def _parse_fix(text: str) -> tuple[float, float, float, float]:
    where = f"--fix {text!r}"
    parts = text.split(",")
    if len(parts) != 4:
        raise ConfigError(f"{where}: expected T,LAT,LON,H (4 values), got {len(parts)}")
    t = _parse_time(parts[0], where)
    lat, lon, h = (_number(p, name, where) for p, name in zip(parts[1:], ("LAT", "LON", "H"), strict=True))
    if not -90.0 <= lat <= 90.0:
        raise ConfigError(f"{where}: LAT {lat} is outside [-90, 90]")
    if not -180.0 <= lon <= 360.0:
        raise ConfigError(f"{where}: LON {lon} is outside [-180, 360]")
    return t, lat, lon, h


def _parse_range(text: str, known: tuple[int, ...] | None) -> tuple[float, int, float]:
    where = f"--range {text!r}"
    parts = text.split(",")
    if len(parts) != 3:
        raise ConfigError(f"{where}: expected T,BEACON,R (3 values), got {len(parts)}")
    t = _parse_time(parts[0], where)
    try:
        beacon = int(parts[1])
    except ValueError:
        raise ConfigError(f"{where}: BEACON {parts[1].strip()!r} is not an integer id") from None
    r = _number(parts[2], "R", where)
    if not 0.0 < r <= MAX_RANGE_M:
        raise ConfigError(f"{where}: R {r} m is not in (0, {MAX_RANGE_M:g}]")
    if known is not None and beacon not in known:
        raise ConfigError(
            f"{where}: beacon {beacon} is not one of the survey's beacons {', '.join(map(str, known))}"
        )
    return t, beacon, r
