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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import FloatArray, IntArray
from oceanloc.config.survey_journal import JournalSettings
from oceanloc.errors import DataError
from oceanloc.estimation.consistency import ConfidenceEllipse, confidence_ellipse
from oceanloc.estimation.range_logs import localize_beacons
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic, geodetic_to_enu
from oceanloc.io.journal import JournalRecords
from oceanloc.io.usbl import AlignedRanges, align_ranges
from oceanloc.planning.measurement_sites import PlanningState
from oceanloc.planning.site_planners import make_site_planner
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
        Planner kind.
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
    aligned = align_ranges(
        records.gps_log(), records.range_log(), origin=origin, max_gap_s=settings.max_gap_s
    )
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
    found = (
        localize_beacons(
            subset,
            sigma_range_m=settings.sigma_range_m,
            prior_sigma_enu_m=settings.prior_sigma_enu_m,
            prior_depth_m=settings.prior_depth_m,
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
        track_enu_m=geodetic_to_enu(records.lat_deg, records.lon_deg, records.h_m, origin).reshape(-1, 3),
        range_status=status,
    )


def vehicle_yaw(records: JournalRecords, settings: JournalSettings) -> tuple[float, str]:
    """The vehicle's heading for planning, radians counter-clockwise from east, and its source.

    The latest HDT heading if it was recorded at or after the previous fix (``HDT``); else the course
    between the last two fixes if they are apart (``fixes``); else the start setting (``start``).

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
        origin = survey_origin(records, settings)
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
    if est.n_beacons == 0:
        waiting = ", ".join(f"{b}: {c}" for b, c in zip(est.waiting_beacons, est.waiting_ranges, strict=True))
        raise DataError(
            f"no beacon estimated yet (each needs {MIN_RANGES} ranges with GPS; so far {waiting or 'none'})"
        )
    kind = settings.planner.kind
    if kind in ("lookahead", "random-yaw"):
        yaw, source = vehicle_yaw(records, settings)
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
        planner=kind,
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
