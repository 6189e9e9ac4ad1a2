"""``oceanloc survey run``: the live survey loop on a vehicle, a GNSS and an acoustic modem.

Measure, journal, estimate, plan and command until the goal (:mod:`oceanloc.field.live_survey`). Ctrl-C
or SIGTERM holds the vehicle, journals the stop and exits 0; re-running the same command resumes.
"""

from __future__ import annotations

import json
import math
import shlex
import signal
import sys
import threading
from pathlib import Path
from typing import IO, Annotated

import typer

from oceanloc.cli._common import console, err_console, escape
from oceanloc.cli._options import parse_floats, parse_origin
from oceanloc.cli.survey_journal import JournalArg, app
from oceanloc.errors import ConfigError, DataError
from oceanloc.field.geofence import WatchdogConfig, read_geofence
from oceanloc.field.live_sources import position_opener, range_opener
from oceanloc.field.live_survey import Epoch, LiveOptions, Notice, StopRule, run_live_survey
from oceanloc.field.survey.journal import Journal
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.io.mavlink_vehicle import MavlinkVehicle
from oceanloc.io.records import to_jsonable
from oceanloc.report.tables import live as live_tables


@app.command("run")
def run(
    journal: JournalArg,
    position: Annotated[
        str,
        typer.Option(
            help="Position source: gpsd://HOST[:PORT], udp://HOST:PORT, tcp://HOST:PORT or serial:///dev/X?baud=N"
            " (NMEA 0183), or mavlink (the vehicle's telemetry).",
            show_default=False,
        ),
    ],
    ranges: Annotated[
        str,
        typer.Option(
            help="Range source: seatrac:///dev/X?beacons=1,2 (a SeaTrac USBL), or udp://, tcp://, serial:// "
            "(lines utc,beacon,range_m).",
            show_default=False,
        ),
    ],
    vehicle: Annotated[
        str | None,
        typer.Option(help="Autopilot (MAVLink): udp://HOST:PORT, udpout://, tcp://, serial:///dev/X?baud=N."),
    ] = None,
    goal: Annotated[
        float | None,
        typer.Option(help="Stop when every beacon's 95% ellipse semi-major axis is this small, m."),
    ] = None,
    max_time: Annotated[
        float | None, typer.Option(help="Time budget from the survey's first run, s.")
    ] = None,
    max_sites: Annotated[int | None, typer.Option(help="Budget of commanded sites.")] = None,
    fence: Annotated[Path | None, typer.Option(help="Geofence: a GeoJSON polygon no site may leave.")] = None,
    fence_radius: Annotated[
        float | None, typer.Option(help="Geofence: a radius about the survey's start, m.")
    ] = None,
    max_leg: Annotated[float | None, typer.Option(help="Longest leg to a commanded site, m.")] = None,
    timeouts: Annotated[
        str, typer.Option(help="HOLD after this long without position, ranges, vehicle heartbeat: P,R,V s.")
    ] = "5,30,3",
    dry_run: Annotated[bool, typer.Option("--dry-run", help="Plan and print; command nothing.")] = False,
    mission: Annotated[
        bool,
        typer.Option("--mission", help="Send the planned sites as a mission (AUTO), not GUIDED targets."),
    ] = False,
    return_to: Annotated[
        str | None, typer.Option(help="When done, send the vehicle to LAT,LON (deg).")
    ] = None,
    ping_interval: Annotated[float, typer.Option(help="Least time between two range requests, s.")] = 0.0,
    json_lines: Annotated[
        Path | None, typer.Option("--json-lines", help="Append one JSON object per epoch and notice here.")
    ] = None,
    serve: Annotated[
        int | None,
        typer.Option(help="Serve the live page (read-only) on http://127.0.0.1:PORT while the survey runs."),
    ] = None,
    gcs_heartbeat: Annotated[
        float, typer.Option(help="Our ground-station heartbeat rate, Hz (raise it for a sped-up simulator).")
    ] = 1.0,
    seed: Annotated[int, typer.Option(min=0, help="Seed of the random planners.")] = 0,
) -> None:
    """Run the survey: journal every record, re-estimate, plan the next D-optimal site and send the vehicle
    there, until the goal or a budget. Never arms the vehicle. Resumes from the journal when re-run."""
    t = parse_floats(timeouts, "--timeouts", 3)
    options = LiveOptions(
        stop=StopRule(goal_m=goal, max_time_s=max_time, max_sites=max_sites),
        fence=None if fence is None else read_geofence(fence),
        fence_radius_m=fence_radius,
        max_leg_m=math.inf if max_leg is None else max_leg,
        watchdog=WatchdogConfig(position_timeout_s=t[0], ranges_timeout_s=t[1], vehicle_timeout_s=t[2]),
        dry_run=dry_run,
        command="mission" if mission else "guided",
        return_to=None if return_to is None else _lat_lon(return_to),
        ping_interval_s=ping_interval,
        seed=seed,
    )
    with Journal.open(journal) as j:
        settings = JournalSettings.from_meta(j.meta(), str(journal))
    out = _open_lines(json_lines)
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())
    page = None
    if serve is not None:
        from oceanloc.report.html.live import serve_journal  # (scipy and plotly: only when serving)

        page = serve_journal(journal, serve)
    if page is not None:
        err_console.print(f"live page of {escape(str(journal))}: {page.url}", highlight=False)
    try:
        link = _connect(vehicle, gcs_heartbeat) if vehicle is not None and not dry_run else None
    except BaseException:
        if page is not None:
            page.stop()
        raise
    try:
        result = run_live_survey(
            journal,
            position=position_opener(position, link),
            ranges=range_opener(ranges, sound_speed_mps=settings.sound_speed_mps, beacons=settings.beacons),
            vehicle=link,
            options=options,
            on_epoch=lambda e: _epoch(e, out),
            on_notice=lambda n: _notice(n, out),
            stop_requested=stop,
            command_line=shlex.join(["oceanloc", *sys.argv[1:]]),
        )
    finally:
        if page is not None:
            page.stop()
        if link is not None:
            link.close()
        if out is not None:
            out.close()
    for line in live_tables.result_lines(result):
        console.print(line, highlight=False)
    if (table := live_tables.result_table(result)) is not None:
        console.print(table)
    if result.status == "failed":
        raise DataError(result.message)


def _lat_lon(text: str) -> tuple[float, float]:
    o = parse_origin(text, "--return-to")
    return o.lat_deg, o.lon_deg


def _connect(spec: str, heartbeat_hz: float) -> MavlinkVehicle:
    link = MavlinkVehicle(spec, gcs_heartbeat_hz=heartbeat_hz)
    res = link.connect(10.0)
    if not res.ok:
        link.close()
        raise ConfigError(f"--vehicle {spec}: {res.message}")
    return link


def _open_lines(path: Path | None) -> IO[str] | None:
    if path is None:
        return None
    try:
        return path.open("a", encoding="utf-8", buffering=1)
    except OSError as exc:
        raise ConfigError(f"--json-lines {path}: cannot open ({exc.strerror or exc})") from None


def _epoch(e: Epoch, out: IO[str] | None) -> None:
    console.print(live_tables.epoch_line(e), highlight=False, soft_wrap=True)
    if out is not None:
        out.write(json.dumps(to_jsonable({"type": "epoch", **e.to_record()})) + "\n")


def _notice(n: Notice, out: IO[str] | None) -> None:
    err_console.print(live_tables.notice_line(n), highlight=False)
    if out is not None:
        record = {"type": "notice", "t_unix_s": n.t_unix_s, "kind": n.kind, "message": n.message}
        out.write(json.dumps(to_jsonable(record)) + "\n")
