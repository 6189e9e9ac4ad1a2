"""The live survey: measure, journal, estimate, plan and command, until the survey meets its goal.

``oceanloc survey run`` drives an autonomous surface vehicle that ranges to seafloor transponders.
Everything it reads goes into the survey journal (:mod:`oceanloc.field.survey.journal`) as it arrives, one
transaction per record, before anything is computed from it. Then, for every new range (an *epoch*; the
ranges that came while the previous epoch ran are folded into this one):

1. the survey's planner (greedy D-optimal or look-ahead, :func:`~oceanloc.field.survey.estimates.
   next_waypoint`) picks the next site from the vehicle's last fix, on the estimates of every range
   aligned so far (receding horizon: the site is re-planned at every range, so the vehicle always heads
   for the most informative point within reach; with drop positions, from the first fix on);
2. the site is checked against the geofence and the maximum leg (:func:`~oceanloc.field.geofence.
   check_site`: clipped inside, or refused) and sent to the vehicle as a GUIDED position target (or, with
   ``command="mission"``, as a mission of the planned sites flown in AUTO);
3. the beacons are re-estimated (:class:`EpochEstimator`: the journal's records held in memory by
   :class:`~oceanloc.field.survey.state.SurveyState`, only the beacons that got aligned ranges re-fitted
   from their previous estimates; the same robust MAP and linearization check as ``survey status``). A
   range is placed on the track only once the fix after it has come, so the range that started the
   epoch is seldom in any estimate yet; the plan of step 1 is the previous epoch's re-fit, short of the
   ranges aligned since (usually one: the previous range). Doing the re-fit after the command keeps it
   out of the range-to-command latency;
4. the stop rule is checked (:func:`check_stop`): every survey beacon's horizontal 95 % ellipse has a
   semi-major axis at most ``goal_m`` *and* the estimate is trusted (the range model's linearization
   check of the bad-input issue); or the time budget, counted from the survey's first run so that a
   resumed survey keeps its budget, or the budget of commanded sites is spent;
5. the estimate, the plan and the command are journaled as events, with the latency from the range's
   arrival to the command.

Safety: a watchdog (:func:`~oceanloc.field.geofence.watchdog_check`) commands HOLD when the position, the
ranges or the vehicle's heartbeat are quiet past their timeouts, says so, and resumes when they are
back. A vehicle the operator switched to another mode (MANUAL, ...) is never taken back: the loop waits
and says so. Nothing here arms the vehicle. A stop request (Ctrl-C, SIGTERM: ``stop_requested``) holds
the vehicle, journals the stop and returns; everything was committed as it came.

Resuming: the journal is the state. Re-running the same command after a crash or kill -9 reads what was
committed, keeps the survey's start time (time budget) and commanded sites (site budget), re-estimates
and re-plans from there; nothing is re-measured on purpose, since the plan already counts every range
taken.
"""

from __future__ import annotations

import dataclasses
import math
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from oceanloc import __version__
from oceanloc.errors import ConfigError, DataError
from oceanloc.field.geofence import (
    CheckedSite,
    Geofence,
    WatchdogConfig,
    check_site,
    contains,
    fence_from_radius,
    watchdog_check,
    watchdog_heard,
    watchdog_start,
)
from oceanloc.field.live_sources import Arrival, SourcePump
from oceanloc.field.survey.estimates import SurveyEstimates, Waypoint, next_waypoint
from oceanloc.field.survey.journal import Journal
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.field.survey.state import SurveyState
from oceanloc.io.mavlink_vehicle import CommandResult, LinkStatus, MavlinkVehicle
from oceanloc.io.nmea import GpsFix, Heading
from oceanloc.io.usbl import RangeRecord

CommandKind = Literal["guided", "mission"]
StopStatus = Literal["goal", "time", "sites", "interrupted", "failed"]

OPERATOR_MODES_WE_DRIVE: tuple[str, ...] = ("GUIDED", "HOLD", "AUTO", "LOITER")
"""Vehicle modes the loop may switch to GUIDED (its own, or HOLD it set); any other mode (MANUAL, ...)
means the operator has the vehicle, and the loop waits."""


@dataclass(frozen=True, slots=True, kw_only=True)
class StopRule:
    """When the survey is done.

    Attributes
    ----------
    goal_m : float or None
        Largest semi-major axis of every survey beacon's horizontal 95 % ellipse, metres, with the
        estimate trusted; None: no goal (stop by a budget or by hand).
    max_time_s : float or None
        Time budget from the survey's first run, seconds.
    max_sites : int or None
        Budget of commanded sites.
    """

    goal_m: float | None = None
    max_time_s: float | None = None
    max_sites: int | None = None

    def __post_init__(self) -> None:
        if self.goal_m is None and self.max_time_s is None and self.max_sites is None:
            raise ConfigError(
                "survey run needs a stop rule: --goal METRES, --max-time SECONDS or --max-sites N"
            )
        for name in ("goal_m", "max_time_s"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"{name} must be a positive number, got {value}")
        if self.max_sites is not None and self.max_sites < 1:
            raise ConfigError(f"max_sites must be 1 or more, got {self.max_sites}")

    def to_record(self) -> dict:
        return {"goal_m": self.goal_m, "max_time_s": self.max_time_s, "max_sites": self.max_sites}


@dataclass(frozen=True, slots=True, kw_only=True)
class LiveOptions:
    """How the loop runs (see the module docstring).

    Attributes
    ----------
    stop : StopRule
    fence : Geofence or None
        No commanded site leaves it.
    fence_radius_m : float or None
        Without ``fence``: a circular fence of this radius about the survey's start (the journal's origin
        setting, else its first fix).
    max_leg_m : float
        Longest leg from the vehicle to a commanded site, metres.
    watchdog : WatchdogConfig
        Timeouts of the position, range and vehicle streams, seconds.
    dry_run : bool
        Plan and report, command nothing (no vehicle needed).
    command : str
        ``guided`` (a position target per epoch) or ``mission`` (the planned sites as a mission, AUTO).
    return_to : (lat_deg, lon_deg) or None
        Where to send the vehicle when the survey is done (checked against the fence).
    ping_interval_s : float
        Least time between two range reads (a SeaTrac ping cycle), seconds.
    seed : int
        Seed of the random planners (with the journal's record counts, as ``survey next``).
    """

    stop: StopRule
    fence: Geofence | None = None
    fence_radius_m: float | None = None
    max_leg_m: float = math.inf
    watchdog: WatchdogConfig = field(default_factory=WatchdogConfig)
    dry_run: bool = False
    command: CommandKind = "guided"
    return_to: tuple[float, float] | None = None
    ping_interval_s: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        if self.command not in ("guided", "mission"):
            raise ConfigError(f"command must be 'guided' or 'mission', got {self.command!r}")
        if self.fence_radius_m is not None and not (
            math.isfinite(self.fence_radius_m) and self.fence_radius_m > 0.0
        ):
            raise ConfigError(
                f"geofence radius must be a positive number of metres, got {self.fence_radius_m}"
            )
        if not self.max_leg_m > 0.0:
            raise ConfigError(f"maximum leg must be a positive number of metres, got {self.max_leg_m}")
        if not (math.isfinite(self.ping_interval_s) and self.ping_interval_s >= 0.0):
            raise ConfigError(f"ping interval must be 0 or more seconds, got {self.ping_interval_s}")

    def to_record(self) -> dict:
        return {
            "stop": self.stop.to_record(),
            "fence": None if self.fence is None else self.fence.to_record(),
            "fence_radius_m": self.fence_radius_m,
            "max_leg_m": None if math.isinf(self.max_leg_m) else self.max_leg_m,
            "timeouts_s": {
                "position": self.watchdog.position_timeout_s,
                "ranges": self.watchdog.ranges_timeout_s,
                "vehicle": self.watchdog.vehicle_timeout_s,
            },
            "dry_run": self.dry_run,
            "command": self.command,
            "return_to": None if self.return_to is None else list(self.return_to),
            "ping_interval_s": self.ping_interval_s,
            "seed": self.seed,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class StopCheck:
    """The stop rule's verdict at one epoch: ``done`` with its status and reason, and per beacon whether
    its goal is met (``met``, in the order of :attr:`SurveyEstimates.beacons`)."""

    done: bool
    status: StopStatus | None
    reason: str
    met: tuple[bool, ...] = ()


def check_stop(
    est: SurveyEstimates | None,
    settings: JournalSettings,
    rule: StopRule,
    *,
    elapsed_s: float,
    sites: int,
) -> StopCheck:
    """The stop rule (module docstring, step 2) on the current estimates, time used and sites commanded."""
    met: tuple[bool, ...] = ()
    if est is not None and est.n_beacons:
        a = est.ellipses.semi_major_m
        goal = rule.goal_m if rule.goal_m is not None else -math.inf
        met = tuple(bool(x) for x in (a <= goal) & est.trusted)
        wanted = set(settings.beacons) or set(est.beacons.tolist())
        missing = wanted - set(est.beacons.tolist())
        if rule.goal_m is not None and not missing and all(met):
            worst = float(np.max(a))
            return StopCheck(
                done=True,
                status="goal",
                reason=f"goal met: every beacon's 95 % ellipse within {rule.goal_m:g} m (largest "
                f"{worst:.2f} m), estimates trusted",
                met=met,
            )
    if rule.max_time_s is not None and elapsed_s >= rule.max_time_s:
        return StopCheck(
            done=True, status="time", reason=f"time budget of {rule.max_time_s:g} s spent", met=met
        )
    if rule.max_sites is not None and sites >= rule.max_sites:
        return StopCheck(done=True, status="sites", reason=f"{rule.max_sites} sites commanded", met=met)
    return StopCheck(done=False, status=None, reason="", met=met)


class EpochEstimator:
    """The current estimates and plan, kept up to date in memory as records are journaled
    (:class:`~oceanloc.field.survey.state.SurveyState`: started from the journal, so a resumed run
    continues from every committed record; work per epoch bounded by what the estimate needs)."""

    def __init__(self, journal: Journal, settings: JournalSettings) -> None:
        self.state = SurveyState.from_journal(journal)
        self.settings = settings
        self.last: SurveyEstimates | None = None

    def add_fix(self, fix: GpsFix) -> None:
        self.state.add_fixes(fix.t_unix_s, fix.lat_deg, fix.lon_deg, fix.h_m)

    def add_heading(self, fix_t_unix_s: float, heading_deg: float) -> None:
        self.state.add_headings(fix_t_unix_s, heading_deg)

    def add_range(self, t_unix_s: float, beacon: int, range_m: float) -> None:
        self.state.add_ranges(t_unix_s, beacon, range_m)

    def estimate(self) -> SurveyEstimates | None:
        """Re-fit with every record held (only beacons that got aligned ranges are re-fitted)."""
        self.last = self.state.estimates() if self.state.n_fixes else None
        return self.last

    def planning_estimates(self) -> SurveyEstimates | None:
        """The last estimates with the track up to the latest fix (the plan starts there); None before
        the first estimate."""
        if self.last is None:
            return None
        return dataclasses.replace(self.last, track_enu_m=self.state.track_enu_m)

    def plan(self, est: SurveyEstimates, seed: int) -> Waypoint:
        rng = np.random.default_rng([seed, self.state.n_fixes, self.state.n_ranges])
        return next_waypoint(self.state.records(), self.settings, estimates=est, rng=rng)


@dataclass(frozen=True, slots=True, kw_only=True)
class Epoch:
    """What one epoch did (the status line and ``--json-lines`` carry it).

    Attributes
    ----------
    number : int
        Epochs of this run, from 1.
    t_unix_s : float
        The range's time.
    estimates : SurveyEstimates or None
    waypoint : Waypoint or None
        The plan (None before a beacon is estimated).
    site : CheckedSite or None
        The site after the geofence and leg checks.
    command : CommandResult or None
        What the vehicle was sent (None in a dry run or when nothing was sent).
    latency_ms : float
        From the range's arrival to the command (or to the plan in a dry run), milliseconds.
    links : dict
        State of each stream (``ok`` or ``quiet``) and the vehicle's mode.
    stop : StopCheck
    note : str
        Why nothing was commanded, if so.
    """

    number: int
    t_unix_s: float
    estimates: SurveyEstimates | None
    waypoint: Waypoint | None
    site: CheckedSite | None
    command: CommandResult | None
    latency_ms: float
    links: dict
    stop: StopCheck
    note: str = ""

    def to_record(self) -> dict:
        est = self.estimates
        beacons = []
        if est is not None:
            for i, b in enumerate(est.beacons):
                beacons.append(
                    {
                        "beacon": int(b),
                        "enu_m": [float(v) for v in est.positions_enu_m[i]],
                        "lat_deg": float(est.positions_geodetic[i, 0]),
                        "lon_deg": float(est.positions_geodetic[i, 1]),
                        "h_m": float(est.positions_geodetic[i, 2]),
                        "sigma_enu_m": [float(v) for v in est.sigma_enu_m[i]],
                        "ellipse95_m": [
                            float(est.ellipses.semi_major_m[i]),
                            float(est.ellipses.semi_minor_m[i]),
                        ],
                        "trusted": bool(est.trusted[i]),
                        "ranges_used": int(est.ranges_used[i]),
                        "goal_met": bool(self.stop.met[i]) if i < len(self.stop.met) else False,
                    }
                )
        w = self.waypoint
        return {
            "epoch": self.number,
            "t_unix_s": self.t_unix_s,
            "beacons": beacons,
            "next": None
            if w is None
            else {
                "lat_deg": float(w.next_geodetic[0]),
                "lon_deg": float(w.next_geodetic[1]),
                "enu_m": [float(v) for v in w.next_enu_m],
                "distance_m": w.distance_m,
                "bearing_deg": w.bearing_deg,
                "gain_nats": w.objective_nats,
                "planner": w.planner,
            },
            "site": None if self.site is None else self.site.to_record(),
            "command": None if self.command is None else self.command.to_record(),
            "latency_ms": self.latency_ms,
            "links": self.links,
            "stop": {"done": self.stop.done, "status": self.stop.status, "reason": self.stop.reason},
            "note": self.note,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class Notice:
    """A message for the operator outside the epochs: a link lost or back, HOLD, a source error."""

    t_unix_s: float
    kind: str
    message: str


@dataclass(frozen=True, slots=True, kw_only=True)
class LiveSurveyResult:
    """How the run ended.

    Attributes
    ----------
    status : str
        ``goal``, ``time``, ``sites`` (a budget), ``interrupted`` (Ctrl-C, SIGTERM) or ``failed``.
    message : str
    epochs : int
        Epochs of this run.
    sites : int
        Sites commanded over the whole survey (this run and earlier ones).
    estimates : SurveyEstimates or None
        The last estimates.
    latencies_ms : (e,) float
        Range-to-command latency of each epoch of this run that commanded (or planned, in a dry run).
    resumed : bool
        The journal held records of an earlier run.
    returned : CommandResult or None
        The command sending the vehicle to ``return_to``.
    """

    status: StopStatus
    message: str
    epochs: int
    sites: int
    estimates: SurveyEstimates | None
    latencies_ms: np.ndarray
    resumed: bool
    returned: CommandResult | None = None

    def to_record(self) -> dict:
        lat = self.latencies_ms
        return {
            "status": self.status,
            "message": self.message,
            "epochs": self.epochs,
            "sites": self.sites,
            "resumed": self.resumed,
            "latency_ms": {
                "median": float(np.median(lat)) if lat.size else None,
                "p95": float(np.percentile(lat, 95)) if lat.size else None,
                "n": int(lat.size),
            },
            "estimates": None if self.estimates is None else self.estimates.to_record(),
            "returned": None if self.returned is None else self.returned.to_record(),
        }


class _Heard:
    """Heading order after each fix (the journal's heading key)."""

    def __init__(self) -> None:
        self.fix_t: float | None = None
        self.seq = 0


def run_live_survey(
    journal_path: str | Path,
    *,
    position: Callable[[], object],
    ranges: Callable[[], object],
    vehicle: MavlinkVehicle | None,
    options: LiveOptions,
    on_epoch: Callable[[Epoch], None] = lambda e: None,
    on_notice: Callable[[Notice], None] = lambda n: None,
    stop_requested: threading.Event | None = None,
    command_line: str = "",
) -> LiveSurveyResult:
    """Run the survey loop on a started journal until the stop rule, a budget or a stop request.

    Parameters
    ----------
    journal_path
        A journal started with ``oceanloc survey start`` (its settings: planner, sigma, beacons, ...).
    position, ranges
        Openers of the position and range streams (:func:`~oceanloc.field.live_sources.position_opener`,
        :func:`~oceanloc.field.live_sources.range_opener`).
    vehicle
        A connected vehicle, or None in a dry run.
    options : LiveOptions
    on_epoch, on_notice
        Called with each epoch and each notice (the status line).
    stop_requested
        Set it (from a signal handler) to stop: HOLD, journal the stop, return ``interrupted``.
    """
    if vehicle is None and not options.dry_run:
        raise ConfigError("survey run needs --vehicle SPEC to command, or --dry-run to plan only")
    stop_requested = stop_requested or threading.Event()
    with Journal.open(journal_path) as journal:
        settings = JournalSettings.from_meta(journal.meta(), str(journal_path))
        return _Loop(journal, settings, position, ranges, vehicle, options, on_epoch, on_notice,
                     stop_requested, command_line).run()  # fmt: skip


class _Loop:
    def __init__(self, journal, settings, position, ranges, vehicle, options, on_epoch, on_notice, stop,
                 command_line) -> None:  # fmt: skip
        self.j: Journal = journal
        self.settings: JournalSettings = settings
        self.vehicle: MavlinkVehicle | None = vehicle
        self.opt: LiveOptions = options
        self.on_epoch, self.on_notice, self.stop_requested = on_epoch, on_notice, stop
        self.q: queue.Queue[Arrival] = queue.Queue()
        self.pumps = [
            SourcePump("position", position, self.q),
            SourcePump("ranges", ranges, self.q, min_interval_s=options.ping_interval_s),
        ]
        self.estimator = EpochEstimator(journal, settings)
        self.fence: Geofence | None = options.fence
        self.heard = _Heard()
        self.epochs = 0
        self.latencies: list[float] = []
        self.last_fix: GpsFix | None = None
        self.estimates: SurveyEstimates | None = None
        self.holding_for_operator = False
        self.command_line = command_line
        starts = journal.events("start")
        self.resumed = bool(starts) or journal.records().n_fixes > 0
        self.t_start = starts[0].t_unix_s if starts else time.time()
        self.sites = sum(1 for e in journal.events("command") if e.body.get("status") in ("sent", "accepted"))

    # -- helpers ----------------------------------------------------------------------------------

    def notice(self, kind: str, message: str, body: dict | None = None) -> None:
        t = time.time()
        if kind in ("link", "stop"):
            self.j.add_event(t, kind, {"message": message, **(body or {})})
        self.on_notice(Notice(t_unix_s=t, kind=kind, message=message))

    def link(self) -> LinkStatus | None:
        return None if self.vehicle is None else self.vehicle.link()

    def hold(self, why: str) -> CommandResult | None:
        if self.vehicle is None or self.opt.dry_run:
            self.notice("link", f"{why} (dry run: no HOLD sent)")
            return None
        res = self.vehicle.hold()
        self.notice("link", f"{why}: HOLD {res.status}", {"command": res.to_record()})
        return res

    # -- the loop ---------------------------------------------------------------------------------

    def run(self) -> LiveSurveyResult:
        self.j.add_event(
            time.time(),
            "start",
            {"version": __version__, "command_line": self.command_line, "options": self.opt.to_record(),
             "resumed": self.resumed},
        )  # fmt: skip
        if self.resumed:
            rec = self.j.records()
            self.notice(
                "resume",
                f"resuming the survey: {rec.n_fixes} fixes, {rec.n_ranges} ranges and {self.sites} commanded "
                f"sites in the journal; {time.time() - self.t_start:.0f} s of the survey's time used",
            )
        for p in self.pumps:
            p.start()
        dog = watchdog_start(time.monotonic())
        try:
            while True:
                if self.stop_requested.is_set():
                    return self.finish("interrupted", "stopped by request (signal)")
                epoch_arrival = self.drain()
                now = time.monotonic()
                for pump, source in zip(self.pumps, ("position", "ranges"), strict=True):
                    dog = watchdog_heard(dog, source, pump.last_record_mono_s)
                link = self.link()
                if link is None:
                    dog = watchdog_heard(dog, "vehicle", now)
                elif math.isfinite(link.heartbeat_age_s):  # heard when the last heartbeat came
                    dog = watchdog_heard(dog, "vehicle", now - link.heartbeat_age_s)
                verdict = watchdog_check(dog, now, self.opt.watchdog)
                dog = verdict.state
                if verdict.action == "hold":
                    self.hold(verdict.message)
                    continue
                if verdict.action == "wait":
                    continue
                if verdict.action == "resume":
                    self.notice("link", verdict.message + ": resuming")
                if epoch_arrival is not None:
                    done = self.epoch(epoch_arrival, link)
                    if done is not None:
                        return done
                elif (
                    self.opt.stop.max_time_s is not None
                    and time.time() - self.t_start >= self.opt.stop.max_time_s
                ):
                    return self.finish("time", f"time budget of {self.opt.stop.max_time_s:g} s spent")
        except DataError as exc:
            self.hold(f"survey failed: {exc}")
            return self.finish("failed", str(exc), hold=False)
        finally:
            for p in self.pumps:
                p.stop()

    def drain(self) -> Arrival | None:
        """Journal everything queued (waiting up to 50 ms for the first item); returns the last range
        taken, which starts the epoch: ranges that came while the previous epoch ran are folded into this
        one, so the loop never falls behind its sources."""
        epoch = None
        timeout = 0.05
        while True:
            try:
                item = self.q.get(timeout=timeout) if timeout else self.q.get_nowait()
            except queue.Empty:
                return epoch
            timeout = 0.0
            taken = self.take(item)
            if taken is not None:
                epoch = taken

    def take(self, item: Arrival) -> Arrival | None:
        """Journal one arrival; returns it when it starts an epoch (a range)."""
        rec = item.record
        if item.kind == "error":
            self.notice("source", f"{item.source}: {item.message}")
            return None
        if isinstance(rec, GpsFix):
            try:
                new = self.j.add_fix(rec.t_unix_s, rec.lat_deg, rec.lon_deg, rec.h_m)
            except DataError as exc:
                self.notice("source", f"position: {exc}")
                return None
            if new:
                self.estimator.add_fix(rec)
            self.last_fix = rec
            self.heard.fix_t, self.heard.seq = rec.t_unix_s, 0
        elif isinstance(rec, Heading) and self.heard.fix_t is not None:
            if self.j.add_heading(self.heard.fix_t, self.heard.seq, rec.heading_deg % 360.0):
                self.estimator.add_heading(self.heard.fix_t, rec.heading_deg % 360.0)
            self.heard.seq += 1
        elif isinstance(rec, RangeRecord):
            if not rec.ok or rec.range_m is None:
                return None
            known = self.settings.beacons
            if known and rec.beacon not in known:
                self.notice(
                    "source", f"ranges: beacon {rec.beacon} is not one of the survey's; range skipped"
                )
                return None
            try:
                new = self.j.add_usbl_range(
                    rec.t_unix_s, rec.beacon, rec.range_m, rec.azimuth_deg, rec.elevation_deg
                )
            except DataError as exc:
                self.notice("source", f"ranges: {exc}")
                return None
            if new:
                self.estimator.add_range(rec.t_unix_s, rec.beacon, rec.range_m)
            return item
        return None

    def epoch(self, arrival: Arrival, link: LinkStatus | None) -> LiveSurveyResult | None:
        """One epoch: the command first, planned on the previous epoch's estimates, then the re-fit with
        the ranges the latest fixes aligned, and the stop rule on it (module docstring); the next epoch
        plans on this re-fit."""
        self.epochs += 1
        rec = arrival.record
        assert isinstance(rec, RangeRecord)
        links = {"vehicle": "none" if link is None else (link.mode_name if link.alive else "lost")}
        wp = site = command = None
        note = ""
        planned = self.estimator.planning_estimates()
        if planned is not None and self.last_fix is not None:
            try:
                wp = self.estimator.plan(planned, self.opt.seed)
            except DataError as exc:
                note = str(exc)
            else:
                site = self.check(wp)
                command, note = self.command(wp, site, link)
        latency_ms = (time.monotonic() - arrival.t_mono_s) * 1e3
        try:
            est = self.estimator.estimate()
        except DataError as exc:
            going = StopCheck(done=False, status=None, reason="")
            self.report(rec, None, wp, site, command, latency_ms, links, going, note=note or str(exc))
            return None
        self.estimates = est
        stop = check_stop(est, self.settings, self.opt.stop, elapsed_s=time.time() - self.t_start,
                          sites=self.sites)  # fmt: skip
        if est is None and not note:
            note = "no GPS fix yet"
        self.report(rec, est, wp, site, command, latency_ms, links, stop, note=note)
        if stop.done:
            return self.finish(stop.status or "goal", stop.reason)
        return None

    def check(self, wp: Waypoint) -> CheckedSite:
        lat, lon = float(wp.next_geodetic[0]), float(wp.next_geodetic[1])
        fix = self.last_fix
        assert fix is not None
        if self.survey_fence() is None and math.isinf(self.opt.max_leg_m):
            leg = float(wp.distance_m)
            return CheckedSite(status="inside", message=f"no geofence, leg {leg:.0f} m", lat_deg=lat,
                               lon_deg=lon, requested_lat_deg=lat, requested_lon_deg=lon, moved_m=0.0,
                               leg_m=leg)  # fmt: skip
        fence = self.survey_fence() or fence_from_radius(
            fix.lat_deg, fix.lon_deg, 2.0 * self.opt.max_leg_m + 1.0
        )
        return check_site(fence, fix.lat_deg, fix.lon_deg, lat, lon, max_leg_m=self.opt.max_leg_m)

    def command(
        self, wp: Waypoint, site: CheckedSite, link: LinkStatus | None
    ) -> tuple[CommandResult | None, str]:
        if not site.ok:
            return None, site.message
        if self.opt.dry_run or self.vehicle is None:
            self.sites += 1  # a rehearsal: the site budget counts the sites it would have sent
            return None, "dry run: nothing commanded"
        if link is None or not link.alive:
            return None, "vehicle link lost"
        if link.mode_name not in OPERATOR_MODES_WE_DRIVE:
            if not self.holding_for_operator:
                self.notice(
                    "link", f"the vehicle is in {link.mode_name}: the operator has it; not commanding"
                )
            self.holding_for_operator = True
            return None, f"vehicle in {link.mode_name} (operator): not commanded"
        self.holding_for_operator = False
        if self.opt.command == "mission":
            pts = [(float(g[0]), float(g[1])) for g in wp.waypoints_geodetic]
            pts[0] = (site.lat_deg, site.lon_deg)
            pts = [p for i, p in enumerate(pts) if i == 0 or self._inside(p)]
            up = self.vehicle.upload_mission(pts)
            if not up.ok:
                return CommandResult(status=up.status, message=up.message), ""
            res = self.vehicle.start_mission()
        elif link.mode_name == "GUIDED":
            res = self.vehicle.send_goto(site.lat_deg, site.lon_deg)
        else:
            res = self.vehicle.goto(site.lat_deg, site.lon_deg, ensure_guided=True)
        if res.status in ("sent", "accepted"):
            self.sites += 1
        return res, ""

    def _inside(self, p: tuple[float, float]) -> bool:
        fence = self.survey_fence()
        return True if fence is None else bool(contains(fence, p[0], p[1]))

    def survey_fence(self) -> Geofence | None:
        """The given fence, or the radius about the survey's start once that is known."""
        if self.fence is None and self.opt.fence_radius_m is not None:
            o = self.settings.origin
            if o is not None:
                self.fence = fence_from_radius(o.lat_deg, o.lon_deg, self.opt.fence_radius_m)
            else:
                fixes = self.j.fixes()
                if fixes.shape[0]:
                    self.fence = fence_from_radius(
                        float(fixes[0, 1]), float(fixes[0, 2]), self.opt.fence_radius_m
                    )
        return self.fence

    def report(self, rec, est, wp, site, command, latency, links, stop, note: str = "") -> None:
        if wp is not None and (command is not None or self.opt.dry_run):
            self.latencies.append(latency)
        now = time.monotonic()
        for p in self.pumps:
            age = now - p.last_record_mono_s
            links[p.name] = "ok" if age <= self.opt.watchdog.timeout_s(p.name) else f"quiet {age:.0f} s"
        e = Epoch(number=self.epochs, t_unix_s=rec.t_unix_s, estimates=est, waypoint=wp, site=site,
                  command=command, latency_ms=latency, links=links, stop=stop, note=note)  # fmt: skip
        body = e.to_record()
        events: list[tuple[str, dict]] = [("estimate", {"epoch": e.number, "beacons": body["beacons"]})]
        if wp is not None:
            events.append(("plan", {"epoch": e.number, "next": body["next"], "site": body["site"]}))
        if command is not None or note:
            events.append(
                ("command", {"epoch": e.number, "status": None if command is None else command.status,
                             "message": note if command is None else command.message,
                             "latency_ms": latency}),
            )  # fmt: skip
        self.j.add_events(time.time(), events)
        self.on_epoch(e)

    def finish(self, status: StopStatus, message: str, *, hold: bool = True) -> LiveSurveyResult:
        returned = None
        commanding = self.vehicle is not None and not self.opt.dry_run
        if status in ("goal", "time", "sites") and self.opt.return_to is not None and commanding:
            returned = self._return()
        elif hold and commanding:
            self.hold("survey stopped" if status == "interrupted" else message)
        lat = np.asarray(self.latencies, dtype=float)
        result = LiveSurveyResult(status=status, message=message, epochs=self.epochs, sites=self.sites,
                                  estimates=self.estimates, latencies_ms=lat, resumed=self.resumed,
                                  returned=returned)  # fmt: skip
        self.j.add_event(time.time(), "stop", result.to_record())
        self.on_notice(Notice(t_unix_s=time.time(), kind="stop", message=message))
        return result

    def _return(self) -> CommandResult:
        assert self.vehicle is not None and self.opt.return_to is not None
        lat, lon = self.opt.return_to
        fence = self.survey_fence()
        if fence is not None:
            fix = self.last_fix
            site = check_site(fence, fix.lat_deg if fix else lat, fix.lon_deg if fix else lon, lat, lon)
            if not site.ok:
                self.hold(f"return point refused: {site.message}")
                return CommandResult(status="rejected", message=site.message)
            lat, lon = site.lat_deg, site.lon_deg
        res = self.vehicle.goto(lat, lon, ensure_guided=True)
        self.notice("link", f"returning to {lat:.7f}, {lon:.7f}: {res.status}", {"command": res.to_record()})
        return res
