"""A field survey from its journal: the current beacon estimates and the next waypoint.

Both are pure functions of the journal's records and settings (:class:`JournalRecords`,
:class:`JournalSettings`): the same journal gives the same numbers to the bit, whether it was written
in one go or by a process that was killed and re-run.

* :func:`survey_estimates` aligns the ranges with the GPS track (:func:`align_ranges`, ENU from the
  settings' origin or the earliest fix) and localizes each beacon with at least
  :data:`MIN_RANGES` aligned ranges by robust MAP (:func:`localize_beacons`); every range gets a status
  (used, outlier, no GPS, beacon still waiting for ranges). Each estimate carries its 95 % confidence
  ellipse (Garcia et al. 2019, Appendix B) in east-north.
* :func:`next_waypoint` runs the survey's planner (:func:`make_site_planner`) once from the last fix with
  the current estimates: greedy D-optimal point within ``d_max``, look-ahead over ``k`` yaw rates, or a
  random baseline. The yaw-rate planners need the vehicle's heading: the latest HDT heading if one was
  recorded since the previous fix, else the course between the last two fixes, else the heading given
  at the start.

``survey status`` and ``survey next`` read the estimates stored in the journal when the journal's
records are those they were computed from (:func:`stored_survey_estimates`: the journal's
:meth:`~.journal.Journal.fingerprint`, the settings and the version key them), and compute and
store them otherwise; ``survey add`` stores them after adding. Stored or computed, they are the same
numbers to the bit (tested).
"""

from __future__ import annotations

import dataclasses
import io
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc import __version__
from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError, DataError
from oceanloc.estimation.consistency import (
    ConfidenceEllipse,
    LinearizationCheck,
    confidence_ellipse,
    range_linearization_check,
)
from oceanloc.estimation.range_logs import localize_beacons, prior_mean
from oceanloc.field.survey.journal import (
    AppendCounts,
    Journal,
    JournalRecords,
    RecordSummary,
    append_gps_log,
    append_range_log,
)
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic, geodetic_to_enu
from oceanloc.io.nmea import read_nmea
from oceanloc.io.qc import QcReport
from oceanloc.io.usbl import AlignedRanges, align_ranges, format_utc, read_usbl
from oceanloc.planning.measurement_sites import PlanningState
from oceanloc.planning.site_planners import make_site_planner, site_planner_name
from oceanloc.planning.status import PlanStatus

MIN_RANGES = 4
"""Aligned ranges a beacon needs before it is estimated (three unknowns, one redundant range)."""

RANGE_STATUS: tuple[str, ...] = ("used", "outlier", "no-gps", "waiting")
"""Labels of :attr:`SurveyEstimates.range_status`: used in the estimate; excluded by the outlier rule;
no GPS fix within ``max_gap_s``; its beacon has fewer than :data:`MIN_RANGES` aligned ranges."""

ELLIPSE_CONFIDENCE = 0.95

_MIN_COURSE_STEP_M = 1e-3
"""Two fixes closer than this give no course."""


@dataclass(frozen=True, slots=True, kw_only=True)
class SurveyEstimates:
    """The journal's current beacon estimates (``M`` estimated beacons, ``n`` fixes, ``m`` ranges).

    Attributes
    ----------
    origin : EnuOrigin
        The ENU frame of every position below.
    beacons : (M,) int
        Estimated beacons, increasing ids.
    positions_enu_m : (M, 3) float
        MAP estimates, metres.
    covariances_m2 : (M, 3, 3) float
        Their covariances, square metres.
    positions_geodetic : (M, 3) float
        The estimates as latitude (deg), longitude (deg), ellipsoidal height (m).
    ellipses : ConfidenceEllipse
        95 % east-north confidence ellipses, batch ``(M,)``, metres.
    ranges_used, ranges_excluded : (M,) int
        Ranges in each estimate and ranges excluded as outliers.
    residual_rms_m : (M,) float
        RMS of the used ranges' residuals, metres.
    waiting_beacons, waiting_ranges : (P,) int
        Beacons not estimated yet (known from the settings or seen in the ranges) and their aligned
        ranges so far (fewer than :data:`MIN_RANGES`).
    track_enu_m : (n, 3) float
        Every fix in ENU, metres.
    range_status : (m,) int
        Index into :data:`RANGE_STATUS` of each journal range (journal order).
    trusted : (M,) bool
        Whether each ellipse can be trusted: the range model is close to linear over its 95 % ellipsoid
        (:func:`~oceanloc.estimation.consistency.range_linearization_check`).
    linearity : (M,) float
        That check's statistic, ``max |log(cost increase / quadratic prediction)|`` (trusted up to log 2).
    trust_messages : tuple of str
        One line per beacon saying why its ellipse is or is not trusted.
    """

    origin: EnuOrigin
    beacons: IntArray
    positions_enu_m: FloatArray
    covariances_m2: FloatArray
    positions_geodetic: FloatArray
    ellipses: ConfidenceEllipse
    ranges_used: IntArray
    ranges_excluded: IntArray
    residual_rms_m: FloatArray
    waiting_beacons: IntArray
    waiting_ranges: IntArray
    track_enu_m: FloatArray
    range_status: IntArray
    trusted: BoolArray
    linearity: FloatArray
    trust_messages: tuple[str, ...]

    @property
    def sigma_enu_m(self) -> FloatArray:
        """1-sigma per axis, ``(M, 3)``, metres."""
        return np.sqrt(np.diagonal(self.covariances_m2, axis1=-2, axis2=-1))

    @property
    def n_beacons(self) -> int:
        return int(self.beacons.size)

    @property
    def ellipse_azimuth_deg(self) -> FloatArray:
        """True bearing of each ellipse's major axis, degrees clockwise from north in ``[0, 180)``."""
        return np.mod(90.0 - np.rad2deg(self.ellipses.angle_rad), 180.0)

    @property
    def ellipse_area_m2(self) -> FloatArray:
        """Area of each 95 % ellipse, ``pi a b``, square metres."""
        return np.pi * self.ellipses.semi_major_m * self.ellipses.semi_minor_m

    def to_record(self) -> dict:
        """Plain JSON-ready data (``survey status --json``): the origin, per beacon the estimate (ENU and
        latitude/longitude), 1-sigma, covariance, 95 % ellipse (azimuth clockwise from north), counts."""
        beacons = []
        for i, b in enumerate(self.beacons):
            beacons.append(
                {
                    "beacon": int(b),
                    "enu_m": self.positions_enu_m[i].tolist(),
                    "sigma_enu_m": self.sigma_enu_m[i].tolist(),
                    "covariance_enu_m2": self.covariances_m2[i].tolist(),
                    "lat_deg": float(self.positions_geodetic[i, 0]),
                    "lon_deg": float(self.positions_geodetic[i, 1]),
                    "h_m": float(self.positions_geodetic[i, 2]),
                    "ellipse95_semi_major_m": float(self.ellipses.semi_major_m[i]),
                    "ellipse95_semi_minor_m": float(self.ellipses.semi_minor_m[i]),
                    "ellipse95_major_azimuth_deg": float(self.ellipse_azimuth_deg[i]),
                    "ranges_used": int(self.ranges_used[i]),
                    "ranges_excluded": int(self.ranges_excluded[i]),
                    "residual_rms_m": float(self.residual_rms_m[i]),
                    "ellipse_trusted": bool(self.trusted[i]),
                    "linearity": float(self.linearity[i]),
                    "trust_message": self.trust_messages[i],
                }
            )
        o = self.origin
        counts = np.bincount(self.range_status, minlength=len(RANGE_STATUS)).tolist()
        return {
            "origin": {"lat_deg": o.lat_deg, "lon_deg": o.lon_deg, "h_m": o.h_m},
            "beacons": beacons,
            "waiting": {
                str(b): int(c) for b, c in zip(self.waiting_beacons, self.waiting_ranges, strict=True)
            },
            "ranges": dict(zip(RANGE_STATUS, counts, strict=True)),
        }

    def ellipse_rings_geodetic(self, n: int = 129) -> FloatArray:
        """The 95 % ellipses as closed rings of latitude, longitude, height, ``(M, n, 3)``.

        Each ring runs counter-clockwise (seen from above) at the estimate's height; its last point is
        exactly its first.
        """
        ring_en = self.ellipses.points(n)
        up = np.broadcast_to(self.positions_enu_m[:, None, 2:3], (*ring_en.shape[:-1], 1))
        ring = enu_to_geodetic(np.concatenate([ring_en, up], axis=-1), self.origin)
        ring[:, -1] = ring[:, 0]
        return ring


@dataclass(frozen=True, slots=True, kw_only=True)
class Waypoint:
    """The next measurement site from the survey's planner (``k`` planned sites).

    Attributes
    ----------
    planner : str
        Planner name (:func:`~oceanloc.planning.site_planners.site_planner_name`: k0, k2, greedy, ...).
    from_t_unix_s : float
        Time of the last fix, the planning start.
    from_enu_m : (3,) float
        Vehicle position at that fix, metres.
    yaw_rad : float
        Vehicle heading used, radians counter-clockwise from east.
    heading_source : str
        ``HDT``, ``fixes`` (course of the last two fixes), ``start`` (the start setting) or ``unused``
        (point planners, which do not need it; 0 is used).
    next_enu_m : (3,) float
        The next site, metres.
    next_geodetic : (3,) float
        Its latitude (deg), longitude (deg), ellipsoidal height (m).
    next_heading_deg : float
        True heading (clockwise from north) on arrival, degrees.
    distance_m, bearing_deg : float
        Horizontal distance and true bearing from the last fix to the next site.
    waypoints_enu_m, waypoints_geodetic : (k, 3) float
        Every planned site (only the first is meant to be sailed: receding horizon).
    yaw_rates_rad_s : (k,) float or None
        Planned yaw rates (yaw-rate planners).
    objective_nats : float
        Information gain of the planned sites over the estimated beacons, nats.
    beacons : (M,) int
        The beacons planned for.
    status : PlanStatus
    origin : EnuOrigin or None
        The ENU frame of the positions above (the estimates').
    untrusted_beacons : (U,) int
        Planned-for beacons whose ellipse is not trusted yet (:attr:`SurveyEstimates.trusted`): the plan
        uses their linearized covariances, which overstate what is known there.
    """

    planner: str
    from_t_unix_s: float
    from_enu_m: FloatArray
    yaw_rad: float
    heading_source: str
    next_enu_m: FloatArray
    next_geodetic: FloatArray
    next_heading_deg: float
    distance_m: float
    bearing_deg: float
    waypoints_enu_m: FloatArray
    waypoints_geodetic: FloatArray
    yaw_rates_rad_s: FloatArray | None
    objective_nats: float
    beacons: IntArray
    status: PlanStatus
    origin: EnuOrigin | None = None
    untrusted_beacons: IntArray = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @property
    def from_heading_deg(self) -> float | None:
        """The vehicle's true heading at the start (clockwise from north, degrees); None when unused."""
        return None if self.heading_source == "unused" else _yaw_to_true_heading(self.yaw_rad)

    @property
    def planned_headings_deg(self) -> FloatArray:
        """True bearing of each planned leg (from the previous site), degrees clockwise from north."""
        sites = np.vstack([self.from_enu_m, self.waypoints_enu_m])
        step = np.diff(sites, axis=0)
        return np.mod(90.0 - np.degrees(np.arctan2(step[:, 1], step[:, 0])), 360.0)

    def to_record(self) -> dict:
        """Plain JSON-ready data (``survey next --json``); headings and bearings clockwise from north."""
        sites = [
            {
                "e_m": float(p[0]), "n_m": float(p[1]), "u_m": float(p[2]),
                "lat_deg": float(g[0]), "lon_deg": float(g[1]), "h_m": float(g[2]),
            }
            for p, g in zip(self.waypoints_enu_m, self.waypoints_geodetic, strict=True)
        ]  # fmt: skip
        return {
            "planner": self.planner,
            "from": {
                "utc": format_utc(self.from_t_unix_s),
                "enu_m": self.from_enu_m.tolist(),
                "heading_deg": self.from_heading_deg,
            },
            "heading_source": self.heading_source,
            "next": sites[0] | {"heading_deg": self.next_heading_deg},
            "distance_m": self.distance_m,
            "bearing_deg": self.bearing_deg,
            "waypoints": sites,
            "yaw_rates_deg_s": None
            if self.yaw_rates_rad_s is None
            else np.degrees(self.yaw_rates_rad_s).tolist(),
            "objective_nats": self.objective_nats,
            "beacons": self.beacons.tolist(),
            "status": self.status.value,
            "untrusted_beacons": self.untrusted_beacons.tolist(),
            "origin": None
            if self.origin is None
            else {"lat_deg": self.origin.lat_deg, "lon_deg": self.origin.lon_deg, "h_m": self.origin.h_m},
        }


def survey_origin(records: JournalRecords, settings: JournalSettings) -> EnuOrigin:
    """The settings' origin, else the earliest fix."""
    if settings.origin is not None:
        return settings.origin
    if records.n_fixes == 0:
        raise DataError("no GPS fix in the journal yet: no ENU frame (add fixes, or start with --origin)")
    return EnuOrigin(
        lat_deg=float(records.lat_deg[0]), lon_deg=float(records.lon_deg[0]), h_m=float(records.h_m[0])
    )


def survey_estimates(records: JournalRecords, settings: JournalSettings) -> SurveyEstimates:
    """The current estimate of every beacon with enough ranges (see the module docstring).

    Raises
    ------
    DataError
        If the journal holds no GPS fix yet.
    """
    if records.n_fixes == 0:
        raise DataError("no GPS fix in the journal yet: nothing to estimate")
    origin = survey_origin(records, settings)
    track = geodetic_to_enu(records.lat_deg, records.lon_deg, records.h_m, origin).reshape(-1, 3)
    aligned = align_ranges(
        records.gps_log(), records.range_log(), origin=origin, max_gap_s=settings.max_gap_s,
        track_enu_m=track,
    )  # fmt: skip
    status = np.full(records.n_ranges, RANGE_STATUS.index("no-gps"), dtype=np.int64)
    ids, counts = np.unique(aligned.beacon, return_counts=True)
    ready = ids[counts >= MIN_RANGES]
    waiting = {int(b): 0 for b in settings.beacons}
    waiting |= {int(b): int(c) for b, c in zip(ids, counts, strict=True) if c < MIN_RANGES}
    for b in ready:
        waiting.pop(int(b), None)
    seen = np.isin(aligned.beacon, ready)
    status[aligned.line[~seen]] = RANGE_STATUS.index("waiting")
    subset = _select(aligned, seen)
    surface = float(np.median(subset.vehicle_enu_m[:, 2])) if subset.range_m.size else 0.0
    drop_means = drop_means_enu_m(settings, origin, surface)
    found = (
        localize_beacons(
            subset,
            sigma_range_m=settings.sigma_range_m,
            prior_sigma_enu_m=settings.prior_sigma_enu_m,
            prior_depth_m=settings.prior_depth_m,
            prior_means_enu_m=drop_means,
            sigma_gps_m=settings.gps_sigma_m,
            gps_correlation_s=settings.gps_correlation_s if settings.gps_sigma_m > 0.0 else None,
        )
        if ready.size
        else []
    )
    for e in found:
        lines = subset.line[subset.select(e.beacon)]
        status[lines] = np.where(e.used, RANGE_STATUS.index("used"), RANGE_STATUS.index("outlier"))
    pos = np.array([e.position_enu_m for e in found]).reshape(-1, 3)
    cov = np.array([e.covariance_m2 for e in found]).reshape(-1, 3, 3)
    wait_ids = np.array(sorted(waiting), dtype=np.int64)
    check = _linearization(subset, found, pos, cov, settings, drop_means)
    return SurveyEstimates(
        origin=origin,
        beacons=np.array([e.beacon for e in found], dtype=np.int64),
        positions_enu_m=pos,
        covariances_m2=cov,
        positions_geodetic=enu_to_geodetic(pos, origin).reshape(-1, 3),
        ellipses=confidence_ellipse(pos[:, :2], cov[:, :2, :2], ELLIPSE_CONFIDENCE),
        ranges_used=np.array([int(e.used.sum()) for e in found], dtype=np.int64),
        ranges_excluded=np.array([e.n_excluded for e in found], dtype=np.int64),
        residual_rms_m=np.array([e.residual_rms_m for e in found], dtype=float),
        waiting_beacons=wait_ids,
        waiting_ranges=np.array([waiting[int(b)] for b in wait_ids], dtype=np.int64),
        track_enu_m=track,
        range_status=status,
        trusted=check.trusted,
        linearity=check.statistic,
        trust_messages=tuple(check.messages()),
    )


def drop_means_enu_m(settings: JournalSettings, origin: EnuOrigin, surface_m: float) -> dict[int, FloatArray]:
    """The known drop positions as prior means in the survey's ENU frame, metres (``depth_m`` below the
    antenna's median height ``surface_m``)."""
    out = {}
    for b, lat, lon, depth in settings.drops:
        e, n, _ = geodetic_to_enu(lat, lon, origin.h_m, origin).reshape(3)
        out[int(b)] = np.array([e, n, surface_m - depth])
    return out


def _linearization(
    subset: AlignedRanges,
    found: Sequence,
    pos: FloatArray,
    cov: FloatArray,
    settings: JournalSettings,
    drop_means: dict[int, FloatArray],
) -> LinearizationCheck:
    """The linearization check of every estimate, on its used ranges and the prior
    :func:`~oceanloc.estimation.range_logs.localize_beacons` put on it (below the shortest range,
    ``prior_depth_m`` under the antenna's median height)."""
    n = max((e.used.size for e in found), default=1)
    sensors = np.zeros((len(found), n, 3))
    ranges = np.zeros((len(found), n))
    used = np.zeros((len(found), n), dtype=bool)
    mean = np.zeros((len(found), 3))
    surface = float(np.median(subset.vehicle_enu_m[:, 2])) if subset.range_m.size else 0.0
    for i, e in enumerate(found):
        sel = subset.select(e.beacon)
        m = e.used.size
        sensors[i, :m], ranges[i, :m], used[i, :m] = subset.vehicle_enu_m[sel], subset.range_m[sel], e.used
        mean[i] = prior_mean(
            e.beacon, sensors[i, :m], ranges[i, :m], surface, settings.prior_depth_m, drop_means
        )
    return range_linearization_check(
        pos,
        cov,
        sensors,
        ranges,
        used,
        settings.sigma_range_m,
        mean,
        np.diag(np.square(settings.prior_sigma_enu_m)),
    )


def vehicle_yaw(
    records: JournalRecords, settings: JournalSettings, origin: EnuOrigin | None = None
) -> tuple[float, str]:
    """The vehicle's heading for planning, radians counter-clockwise from east, and its source.

    The latest HDT heading if it was recorded at or after the previous fix (``HDT``); else the course
    between the last two fixes if they are apart (``fixes``, in the survey's ENU frame ``origin``,
    default :func:`survey_origin` of ``records``); else the start setting (``start``).

    Raises
    ------
    DataError
        If none of them is available.
    """
    n = records.n_fixes
    if n and records.heading_deg.size:
        t_prev = records.fix_t_unix_s[max(n - 2, 0)]
        if records.heading_t_unix_s[-1] >= t_prev:
            return _true_heading_to_yaw(float(records.heading_deg[-1])), "HDT"
    if n >= 2:
        origin = survey_origin(records, settings) if origin is None else origin
        last = geodetic_to_enu(records.lat_deg[-2:], records.lon_deg[-2:], records.h_m[-2:], origin)
        step = last[1] - last[0]
        if np.hypot(step[0], step[1]) > _MIN_COURSE_STEP_M:
            return float(np.arctan2(step[1], step[0])), "fixes"
    if settings.heading_deg is not None:
        return _true_heading_to_yaw(settings.heading_deg), "start"
    raise DataError(
        "no vehicle heading for the yaw-rate planner: add GPS logs with HDT sentences or two distinct "
        "fixes, or start the survey with --heading"
    )


def next_waypoint(
    records: JournalRecords,
    settings: JournalSettings,
    *,
    estimates: SurveyEstimates | None = None,
    rng: np.random.Generator | None = None,
) -> Waypoint:
    """The survey planner's next site from the last fix (see the module docstring).

    Parameters
    ----------
    records, settings
        The journal's content.
    estimates : SurveyEstimates, optional
        :func:`survey_estimates` of the same records, if already computed.
    rng : numpy.random.Generator, optional
        Required by the random planners only.

    Raises
    ------
    DataError
        If no beacon is estimated yet, or a yaw-rate planner has no heading.
    """
    est = survey_estimates(records, settings) if estimates is None else estimates
    est = with_drop_priors(est, settings)
    if est.n_beacons == 0:
        waiting = ", ".join(f"{b}: {c}" for b, c in zip(est.waiting_beacons, est.waiting_ranges, strict=True))
        raise DataError(
            f"no beacon estimated yet (each needs {MIN_RANGES} ranges with GPS; so far {waiting or 'none'})"
        )
    kind = settings.planner.kind
    if kind in ("lookahead", "random-yaw"):
        yaw, source = vehicle_yaw(records, settings, est.origin)
    else:
        yaw, source = 0.0, "unused"
    start = est.track_enu_m[-1]
    planner = make_site_planner(
        settings.planner,
        max_yaw_rate_rad_s=settings.max_yaw_rate_rad_s,
        speed_mps=settings.speed_mps,
        period_s=settings.period_s,
        sigma_range_m=settings.sigma_range_m,
    )
    state = PlanningState(
        pos_enu_m=start[None].copy(),
        yaw_rad=np.array([yaw]),
        estimates_m=est.positions_enu_m[None],
        covariances_m2=est.covariances_m2[None],
    )
    plan = planner.plan(state, rng)
    nxt = plan.next_pos_enu_m[0]
    step = nxt - start
    return Waypoint(
        planner=site_planner_name(settings.planner),
        from_t_unix_s=float(records.fix_t_unix_s[-1]),
        from_enu_m=start.copy(),
        yaw_rad=float(yaw),
        heading_source=source,
        next_enu_m=nxt,
        next_geodetic=enu_to_geodetic(nxt, est.origin),
        next_heading_deg=_yaw_to_true_heading(float(plan.next_yaw_rad[0])),
        distance_m=float(np.hypot(step[0], step[1])),
        bearing_deg=_yaw_to_true_heading(float(np.arctan2(step[1], step[0]))),
        waypoints_enu_m=plan.waypoints_enu_m[0],
        waypoints_geodetic=enu_to_geodetic(plan.waypoints_enu_m[0], est.origin),
        yaw_rates_rad_s=None if plan.yaw_rates_rad_s is None else plan.yaw_rates_rad_s[0],
        objective_nats=float(plan.objective[0]),
        beacons=est.beacons.copy(),
        status=plan.status,
        origin=est.origin,
        untrusted_beacons=est.beacons[~est.trusted],
    )


def with_drop_priors(est: SurveyEstimates, settings: JournalSettings) -> SurveyEstimates:
    """The estimates to plan with: those of :func:`survey_estimates`, plus, for each survey beacon with a
    drop position but too few ranges yet, its prior (mean at the drop, covariance
    ``diag(prior_sigma_enu_m^2)``, not trusted), so that the first sites are planned from the first fix."""
    have = set(est.beacons.tolist())
    extra = [d for d in settings.drops if d[0] not in have]
    if not extra:
        return est
    surface = float(np.median(est.track_enu_m[:, 2])) if est.track_enu_m.size else 0.0
    means = drop_means_enu_m(settings, est.origin, surface)
    ids = np.array([d[0] for d in extra], dtype=np.int64)
    pos = np.array([means[int(b)] for b in ids])
    cov = np.broadcast_to(np.diag(np.square(settings.prior_sigma_enu_m)), (ids.size, 3, 3))
    order = np.argsort(np.concatenate([est.beacons, ids]), kind="stable")
    return dataclasses.replace(
        est,
        beacons=np.concatenate([est.beacons, ids])[order],
        positions_enu_m=np.concatenate([est.positions_enu_m, pos])[order],
        covariances_m2=np.concatenate([est.covariances_m2, cov])[order],
        trusted=np.concatenate([est.trusted, np.zeros(ids.size, dtype=bool)])[order],
    )


def _select(aligned: AlignedRanges, mask: np.ndarray) -> AlignedRanges:
    return AlignedRanges(
        t_unix_s=aligned.t_unix_s[mask],
        beacon=aligned.beacon[mask],
        range_m=aligned.range_m[mask],
        vehicle_enu_m=aligned.vehicle_enu_m[mask],
        origin=aligned.origin,
        dropped_no_gps=aligned.dropped_no_gps,
        line=aligned.line[mask],
    )


def _true_heading_to_yaw(heading_deg: float) -> float:
    """True heading (degrees clockwise from north) to yaw (radians counter-clockwise from east)."""
    yaw = np.deg2rad(90.0 - heading_deg)
    return float(np.arctan2(np.sin(yaw), np.cos(yaw)))


def _yaw_to_true_heading(yaw_rad: float) -> float:
    """Yaw (radians counter-clockwise from east) to true heading in ``[0, 360)`` degrees."""
    return float((90.0 - np.rad2deg(yaw_rad)) % 360.0)


# -- the survey commands' operations on a journal file (one call per command) --------------------------

MAX_RANGE_M = 10_000.0
"""Longest range accepted on the command line, metres."""


@dataclass(frozen=True, slots=True, kw_only=True)
class JournalAddition:
    """What ``survey add`` appended.

    Attributes
    ----------
    sources : tuple of (str, str)
        Per file (or ``--fix``/``--range``), its name and the counts appended (``AppendCounts`` text).
    conflicts : tuple of str
        Records given on the command line whose key is stored with another value (kept as stored).
    qc : QcReport
        Lines skipped in the files read.
    n_fixes, n_headings, n_ranges : int
        The journal's totals afterwards.
    """

    sources: tuple[tuple[str, str], ...]
    conflicts: tuple[str, ...]
    qc: QcReport
    n_fixes: int
    n_headings: int
    n_ranges: int

    def to_record(self) -> dict:
        return {
            "sources": [{"source": a, "counts": b} for a, b in self.sources],
            "conflicts": list(self.conflicts),
            "qc": self.qc.counts(),
            "fixes": self.n_fixes,
            "headings": self.n_headings,
            "ranges": self.n_ranges,
        }


def add_to_journal(
    path: str | Path,
    *,
    nmea: Sequence[str | Path] = (),
    ranges: Sequence[str | Path] = (),
    fixes: Sequence[tuple[float, float, float, float]] = (),
    manual_ranges: Sequence[tuple[float, int, float]] = (),
) -> JournalAddition:
    """Append GPS logs, range logs, fixes ``(t, lat, lon, h)`` and ranges ``(t, beacon, r)`` to a started
    journal: files in transactions of :data:`~.journal.APPEND_CHUNK` records in file order (a
    killed process leaves a prefix of the files committed), ``fixes``/``manual_ranges`` one transaction
    per record. Everything is read and checked before the first write, so an error leaves the journal as
    it was; records already stored change nothing. Then the estimates of the journal's records are
    computed and stored in it (:func:`stored_survey_estimates`), for ``survey status`` and ``next``.

    Raises
    ------
    ConfigError
        If nothing is given, a range is out of ``(0, MAX_RANGE_M]`` or names a beacon the survey does not
        have.
    """
    if not (nmea or ranges or fixes or manual_ranges):
        raise ConfigError(
            "nothing to add: give --nmea FILE, --ranges FILE, --fix T,LAT,LON,H or --range T,BEACON,R"
        )
    with Journal.open(path) as j:
        settings = JournalSettings.from_meta(j.meta(), str(path))
        known = settings.beacons or None
        for t, beacon, r in manual_ranges:
            where = f"--range {t:.3f},{beacon},{r:g}"
            if not 0.0 < r <= MAX_RANGE_M:
                raise ConfigError(f"{where}: R {r} m is not in (0, {MAX_RANGE_M:g}]")
            if known is not None and beacon not in known:
                beacons = ", ".join(map(str, known))
                raise ConfigError(f"{where}: beacon {beacon} is not one of the survey's beacons {beacons}")
        qc = QcReport()
        gps_logs = [(p, read_nmea(p, qc=qc)) for p in nmea]
        range_logs = [
            (p, read_usbl(p, sound_speed_mps=settings.sound_speed_mps, beacons=known, qc=qc)) for p in ranges
        ]
        sources: list[tuple[str, str]] = []
        for p, log in gps_logs:
            fix_counts, head_counts = append_gps_log(j, log, p, qc)
            sources.append((str(p), f"{fix_counts}, {head_counts}"))
        for p, log in range_logs:
            sources.append((str(p), str(append_range_log(j, log, p, qc))))
        conflicts: list[str] = []
        if fixes:
            same_fix = lambda f: j.fix_at(f[0]) == f[1:]  # noqa: E731
            sources.append(("--fix", str(_add_manual(fixes, j.add_fix, same_fix, "fixes", conflicts))))
        if manual_ranges:
            same_range = lambda r: j.range_at(r[0], r[1]) == r[2]  # noqa: E731
            counts = _add_manual(manual_ranges, j.add_range, same_range, "ranges", conflicts)
            sources.append(("--range", str(counts)))
        n = {table: j.count_valid(table) for table in ("fixes", "headings", "ranges")}
        if n["fixes"]:  # for the next `survey status` / `survey next` (a cache: never blocks the add)
            stored_survey_estimates(j, settings)
    return JournalAddition(
        sources=tuple(sources), conflicts=tuple(conflicts), qc=qc, n_fixes=n["fixes"],
        n_headings=n["headings"], n_ranges=n["ranges"],
    )  # fmt: skip


def _add_manual(
    records: Sequence[tuple],
    add: Callable[..., bool],
    same: Callable[[tuple], bool],
    kind: str,
    out: list[str],
) -> AppendCounts:
    """Append records given on the command line; one already stored with other values is kept as stored
    (and named in ``out``)."""
    new = old = 0
    for rec in records:
        if add(*rec):
            new += 1
        elif same(rec):
            old += 1
        else:
            out.append(f"{kind[:-1]} {rec}: another value is stored for this key; kept as stored")
    return AppendCounts(kind=kind, new=new, already_stored=old, conflicting=len(records) - new - old)


@dataclass(frozen=True, slots=True, kw_only=True)
class JournalStatus:
    """A journal's settings, record counts and current estimates (None before the first fix)."""

    path: str
    settings: JournalSettings
    records: RecordSummary
    estimates: SurveyEstimates | None

    def to_record(self) -> dict:
        rec = self.records
        base = {
            "journal": self.path,
            "fixes": rec.n_fixes,
            "headings": rec.n_headings,
            "ranges_recorded": rec.n_ranges,
        }
        return base | (self.estimates.to_record() if self.estimates is not None else {"beacons": []})


ESTIMATES_NAME = "survey-estimates"
"""Name under which the journal keeps its estimates (:meth:`~.journal.Journal.derived`)."""

_ESTIMATES_REVISION = 1
"""Bumped when :func:`survey_estimates` changes its numbers, so estimates stored before are recomputed."""


def _estimates_key(journal: Journal, fingerprint: str | None = None) -> str:
    """What stored estimates must have been computed from: this version of the estimator, the journal's
    settings and its records (:meth:`~.journal.Journal.fingerprint`, read here unless
    given)."""
    meta = json.dumps(journal.meta(), sort_keys=True)
    fingerprint = journal.fingerprint() if fingerprint is None else fingerprint
    return f"oceanloc {__version__} r{_ESTIMATES_REVISION}|{meta}|{fingerprint}"


def pack_estimates(est: SurveyEstimates) -> bytes:
    """:class:`SurveyEstimates` as bytes (an ``.npz`` archive, no pickles; every number exact)."""
    o, e = est.origin, est.ellipses
    arrays = {
        "origin": np.array([o.lat_deg, o.lon_deg, o.h_m]),
        "ellipse_center_m": e.center_m,
        "ellipse_semi_major_m": e.semi_major_m,
        "ellipse_semi_minor_m": e.semi_minor_m,
        "ellipse_angle_rad": e.angle_rad,
        "ellipse_confidence": np.array(e.confidence),
        "trust_messages": np.array(est.trust_messages, dtype=str),
    }
    for f in dataclasses.fields(est):
        if f.name not in ("origin", "ellipses", "trust_messages"):
            arrays[f.name] = getattr(est, f.name)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def unpack_estimates(payload: bytes) -> SurveyEstimates:
    """The inverse of :func:`pack_estimates`."""
    with np.load(io.BytesIO(payload), allow_pickle=False) as z:
        a = {k: z[k] for k in z.files}
    lat, lon, h = (float(v) for v in a.pop("origin"))
    ellipses = ConfidenceEllipse(
        center_m=a.pop("ellipse_center_m"),
        semi_major_m=a.pop("ellipse_semi_major_m"),
        semi_minor_m=a.pop("ellipse_semi_minor_m"),
        angle_rad=a.pop("ellipse_angle_rad"),
        confidence=float(a.pop("ellipse_confidence")),
    )
    messages = tuple(str(m) for m in a.pop("trust_messages"))
    return SurveyEstimates(
        origin=EnuOrigin(lat_deg=lat, lon_deg=lon, h_m=h), ellipses=ellipses, trust_messages=messages, **a
    )


def stored_survey_estimates(
    journal: Journal,
    settings: JournalSettings,
    records: JournalRecords | None = None,
    *,
    fingerprint: str | None = None,
) -> SurveyEstimates:
    """:func:`survey_estimates` of the journal's records: the stored ones if the records are those they
    were computed from, else computed (from ``records`` when given: the journal's, read by the caller;
    else read here without warning of invalid rows, which :meth:`~.journal.Journal.summary`
    reports) and stored for the next reader, where the journal can be written without waiting.
    ``fingerprint``: the journal's, if just read (:attr:`~.journal.RecordSummary.fingerprint`).

    Raises
    ------
    DataError
        If the journal holds no GPS fix yet.
    """
    key = _estimates_key(journal, fingerprint)
    payload = journal.derived(ESTIMATES_NAME, key)
    if payload is not None:
        return unpack_estimates(payload)
    rec = journal.records(headings=False, warn=False) if records is None else records
    est = survey_estimates(rec, settings)
    journal.store_derived(ESTIMATES_NAME, key, pack_estimates(est))
    return est


def journal_status(path: str | Path) -> JournalStatus:
    """A journal's settings, counts and estimates (``survey status``): the records are counted by SQL
    and the estimates read from the journal where they are stored for its current records
    (:func:`stored_survey_estimates`)."""
    with Journal.open(path) as j:
        settings = JournalSettings.from_meta(j.meta(), str(path))
        summary = j.summary()
        est = (
            stored_survey_estimates(j, settings, fingerprint=summary.fingerprint) if summary.n_fixes else None
        )
    return JournalStatus(path=str(path), settings=settings, records=summary, estimates=est)


def journal_next_waypoint(path: str | Path, *, seed: int = 0) -> Waypoint:
    """The next waypoint of a journal's survey (``survey next``): the planner from the last fix with the
    estimates of :func:`stored_survey_estimates`. The random planners draw from a generator seeded by
    ``seed`` and the record counts, so a re-run on the same journal repeats."""
    with Journal.open(path) as j:
        settings = JournalSettings.from_meta(j.meta(), str(path))
        summary = j.summary()
        if summary.n_fixes == 0:
            raise DataError("no GPS fix in the journal yet: nothing to estimate")
        est = stored_survey_estimates(j, settings, fingerprint=summary.fingerprint)
        tail = j.tail()
    rng = np.random.default_rng([seed, summary.n_fixes, summary.n_ranges])
    return next_waypoint(tail, settings, estimates=est, rng=rng)
