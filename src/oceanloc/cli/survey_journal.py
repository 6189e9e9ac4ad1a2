"""``oceanloc survey``: a field survey journal (start, add, check, next, status, export).

Every fix, heading and range goes into an SQLite journal (:mod:`oceanloc.field.survey.journal`: files in
transactions of 2,000 records in file order, so a killed add leaves a prefix of them committed); the
estimates and the next waypoint are computed from the journal alone
(:mod:`oceanloc.field.survey.estimates`), so a killed process loses nothing committed and a re-run gives the
same numbers.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from oceanloc.cli import root
from oceanloc.cli._common import cli_provenance, console, err_console, escape, write_json
from oceanloc.cli._options import parse_fields, parse_number, parse_origin, parse_time
from oceanloc.errors import ConfigError
from oceanloc.field.survey.check import check_journal, journal_invalid_records
from oceanloc.field.survey.estimates import add_to_journal, journal_next_waypoint, journal_status
from oceanloc.field.survey.journal import Journal, fix_problem, range_problem
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.planning.site_planners import parse_site_planner
from oceanloc.report.tables import survey_journal as tables
from oceanloc.units import DEG

app = typer.Typer(
    help="Survey journal: record fixes and ranges as they arrive, estimate the beacons, plan the next site.",
    no_args_is_help=True,
)
root.app.add_typer(app, name="survey")

JournalArg = Annotated[Path, typer.Argument(help="The survey journal (an SQLite file).", show_default=False)]


@app.command("start")
def start(
    journal: JournalArg,
    planner: Annotated[
        str,
        typer.Option(
            help="Planner: greedy, lookahead (with -k), k0..k10 (k0: random yaw, k1..k10: look-ahead k), "
            "random-yaw, random-disk (or random)."
        ),
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
    drop: Annotated[
        list[str] | None,
        typer.Option(
            "--drop",
            help="A beacon's drop position BEACON:LAT,LON,DEPTH (deg, deg, m below the antenna; repeat): its "
            "prior mean, with --prior-sigma.",
        ),
    ] = None,
    sigma_gps: Annotated[
        float | None,
        typer.Option(help="GPS part of the range sigma, m (default 1 m when the sigma is above it, else 0)."),
    ] = None,
    gps_correlation: Annotated[
        float, typer.Option(help="Time constant of the GPS error, s (0: white).")
    ] = 60.0,
) -> None:
    """Start a survey: create the journal and store its settings (never overwritten later)."""
    settings = JournalSettings(
        planner=parse_site_planner(planner, horizon=horizon, max_distance_m=max_distance),
        max_yaw_rate_rad_s=max_yaw_rate * DEG,
        speed_mps=speed,
        period_s=period,
        sigma_range_m=sigma_range,
        origin=None if origin is None else parse_origin(origin),
        beacons=tuple(beacon or ()),
        prior_sigma_enu_m=parse_fields(prior_sigma, ("E", "N", "U"), "--prior-sigma"),  # type: ignore[arg-type]
        prior_depth_m=prior_depth,
        drops=tuple(_parse_drop(text) for text in drop or []),
        heading_deg=heading,
        sound_speed_mps=sound_speed,
        max_gap_s=max_gap,
        sigma_gps_m=sigma_gps,
        gps_correlation_s=gps_correlation if gps_correlation > 0 else None,
    )
    with Journal.start(journal, settings.to_meta()):
        pass
    console.print(
        f"started survey journal {escape(str(journal))}: {tables.journal_settings_text(settings)}",
        highlight=False,
    )


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
    """Append records (files in transactions of 2,000 records in file order: a killed add leaves a
    prefix committed); bad lines are skipped and listed, re-adds change nothing."""
    res = add_to_journal(
        journal,
        nmea=nmea or (),
        ranges=ranges or (),
        fixes=[_parse_fix(text) for text in fix or []],
        manual_ranges=[_parse_range(text) for text in range_ or []],
    )
    for record in journal_invalid_records(journal):
        err_console.print(escape(f"{journal}: invalid stored record skipped: {record}"), highlight=False)
    for source, counts in res.sources:
        console.print(escape(f"{source}: {counts}"), highlight=False)
    for line in res.conflicts:
        err_console.print(escape(line), highlight=False)
    if res.qc.issues:
        err_console.print(escape("QC: " + res.qc.summary(max_lines=50)), highlight=False)
    console.print(
        escape(f"journal {journal}: {res.n_fixes} fixes, {res.n_headings} headings, {res.n_ranges} ranges"),
        highlight=False,
    )


@app.command("check")
def check(
    journal: JournalArg,
    remove_invalid: Annotated[
        bool, typer.Option("--remove-invalid", help="Delete the invalid stored records (one transaction).")
    ] = False,
) -> None:
    """Check every page and stored record; list invalid records (table, time, problem).

    Exit status: 0 when the journal is clean (or was cleaned with --remove-invalid), 1 when problems
    remain, 2 on a usage error or a file that is not a journal.
    """
    res = check_journal(journal, remove_invalid=remove_invalid)
    for line in res.lines():
        console.print(escape(f"{journal}: {line}"), highlight=False)
    if res.removed:
        console.print(escape(f"{journal}: removed {res.removed} invalid record(s)"), highlight=False)
    if res.clean:
        console.print(escape(f"{journal}: ok ({'clean now' if res.removed else 'no problems'})"))
        return
    hint = "" if res.damaged else "; `--remove-invalid` deletes them"
    err_console.print(escape(f"{journal}: {len(res.lines())} problem(s){hint}"), highlight=False)
    raise SystemExit(1)  # problems remain: exit status 1 (not a usage error)


@app.command("next")
def next_(
    journal: JournalArg,
    json_path: Annotated[Path | None, typer.Option("--json", help="Write the waypoint as JSON here.")] = None,
    seed: Annotated[
        int, typer.Option(min=0, help="Seed of the random planners (with the record counts).")
    ] = 0,
) -> None:
    """The next waypoint (ENU and latitude/longitude, headings clockwise from north) from the current
    estimates and the survey's planner."""
    w = journal_next_waypoint(journal, seed=seed)
    console.print(tables.waypoint_table(w))
    console.print(tables.waypoint_line(w), highlight=False)
    if json_path is not None:
        write_json(json_path, w, cli_provenance(seed=seed, inputs=[journal]))


@app.command("status")
def status(
    journal: JournalArg,
    json_path: Annotated[
        Path | None, typer.Option("--json", help="Write the estimates as JSON here.")
    ] = None,
) -> None:
    """Per beacon: estimate E/N/U and lat/lon, 1-sigma, 95% ellipse, ranges used and excluded."""
    st = journal_status(journal)
    for line in tables.journal_status_lines(st):
        console.print(line, highlight=False)
    if st.estimates is None:
        console.print("no GPS fix yet: nothing to estimate")
        return
    how = "earliest fix" if st.settings.origin is None else "given"
    console.print(tables.journal_estimates_table(st.estimates, how))
    for line in tables.journal_range_lines(st.estimates):
        console.print(line, highlight=False)
    if json_path is not None:
        write_json(json_path, st, cli_provenance(inputs=[journal]))


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
    from oceanloc.field.survey.export import export_journal

    res = export_journal(journal, geojson=geojson, csv=csv)
    if res.geojson is not None:
        console.print(
            escape(
                f"wrote {res.geojson} ({res.n_beacons} beacons with ellipses, track of {res.n_fixes} fixes)"
            ),
            highlight=False,
        )
    if res.csv_folder is not None:
        console.print(
            escape(f"wrote {', '.join(p.name for p in res.csv)} in {res.csv_folder}"), highlight=False
        )


def _parse_fix(text: str) -> tuple[float, float, float, float]:
    """``--fix T,LAT,LON,H`` (T: ISO 8601 UTC or Unix seconds; degrees, degrees, metres)."""
    where = f"--fix {text!r}"
    parts = text.split(",")
    if len(parts) != 4:
        raise ConfigError(f"{where}: expected T,LAT,LON,H (4 values), got {len(parts)}")
    lat = parse_number(parts[1], "LAT", where, -90.0, 90.0)
    lon = parse_number(parts[2], "LON", where, -180.0, 360.0)
    values = (parse_time(parts[0], where), lat, lon, parse_number(parts[3], "H", where))
    if problem := fix_problem(*values):
        raise ConfigError(f"{where}: {problem}; nothing was added")
    return values


def _parse_drop(text: str) -> tuple[int, float, float, float]:
    """``--drop BEACON:LAT,LON,DEPTH``."""
    where = f"--drop {text!r}"
    head, sep, rest = text.partition(":")
    try:
        beacon = int(head)
    except ValueError:
        raise ConfigError(f"{where}: expected BEACON:LAT,LON,DEPTH with an integer beacon id") from None
    parts = rest.split(",")
    if not sep or len(parts) != 3:
        raise ConfigError(f"{where}: expected BEACON:LAT,LON,DEPTH (deg, deg, m)")
    lat = parse_number(parts[0], "LAT", where, -90.0, 90.0)
    lon = parse_number(parts[1], "LON", where, -180.0, 360.0)
    return beacon, lat, lon, parse_number(parts[2], "DEPTH", where, 0.0, 12_000.0)


def _parse_range(text: str) -> tuple[float, int, float]:
    """``--range T,BEACON,R`` (R in metres)."""
    where = f"--range {text!r}"
    parts = text.split(",")
    if len(parts) != 3:
        raise ConfigError(f"{where}: expected T,BEACON,R (3 values), got {len(parts)}")
    try:
        beacon = int(parts[1])
    except ValueError:
        raise ConfigError(f"{where}: BEACON {parts[1].strip()!r} is not an integer id") from None
    values = (parse_time(parts[0], where), beacon, parse_number(parts[2], "R", where))
    if problem := range_problem(*values):
        raise ConfigError(f"{where}: {problem}; nothing was added")
    return values
