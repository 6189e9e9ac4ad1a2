"""The report of a survey journal: track, ranges as taken, beacon estimates, residuals, checks.

Everything comes from the journal's library API: :meth:`Journal.records` (one consistent snapshot),
:func:`survey_estimates` and :func:`next_waypoint` of :mod:`oceanloc.field.survey.estimates`. The residual of
each range is ``r - |p_V - p_B|`` with ``p_V`` the vehicle's interpolated position (:func:`align_ranges`,
as the estimator uses it) and ``p_B`` its beacon's estimate; the used ones are tested against the
chi-square interval with ``used - 3`` degrees of freedom at the survey's range sigma.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
from scipy import stats

from oceanloc.errors import DataError
from oceanloc.field.survey.estimates import RANGE_STATUS, SurveyEstimates, next_waypoint, survey_estimates
from oceanloc.field.survey.journal import Journal, JournalRecords
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.io.records import file_sha256
from oceanloc.io.usbl import AlignedRanges, align_ranges
from oceanloc.report.html.model import Check, Estimate, MapLayers, Report, Series, Table

SIGMA_CUTS = 6
"""Times at which the estimates are recomputed from the journal's records so far (sigma by time)."""
SIGMA_MAX_RANGES = 1500
"""Above this many ranges the sigma-by-time panel is skipped (each cut is a full estimate)."""

_REASONS = {
    "outlier": "excluded by the outlier rule",
    "no-gps": "no GPS fix within max_gap_s",
    "waiting": "beacon has too few ranges to estimate",
}


def read_journal(path: str | Path) -> tuple[JournalRecords, JournalSettings, dict[str, str]]:
    """The journal's records, settings and raw meta, in one read."""
    with Journal.open(path) as j:
        meta = j.meta()
        records = j.records()
    return records, JournalSettings.from_meta(meta, source=str(path)), meta


def _utc(t: float) -> str:
    return dt.datetime.fromtimestamp(t, dt.UTC).strftime("%Y-%m-%d %H:%M:%S")


def range_geometry(
    records: JournalRecords, settings: JournalSettings, est: SurveyEstimates
) -> tuple[AlignedRanges, np.ndarray, np.ndarray, np.ndarray]:
    """The ranges aligned with the track, whether their beacon is estimated, their residuals (m) and
    each as a segment from the vehicle to its beacon's estimate, ``(k, 2, 2)`` east-north metres."""
    aligned = align_ranges(
        records.gps_log(), records.range_log(), origin=est.origin, max_gap_s=settings.max_gap_s
    )
    has = np.isin(aligned.beacon, est.beacons)
    order = np.argsort(est.beacons)
    at = np.clip(np.searchsorted(est.beacons[order], aligned.beacon), 0, max(est.n_beacons - 1, 0))
    rows = order[at] if est.n_beacons else at
    p_b = est.positions_enu_m[rows] if est.n_beacons else np.zeros((aligned.beacon.size, 3))
    residual = aligned.range_m - np.linalg.norm(aligned.vehicle_enu_m - p_b, axis=1)
    segs = np.stack([aligned.vehicle_enu_m[has, :2], p_b[has, :2]], axis=1)
    return aligned, has, residual, segs


def beacon_markers(est: SurveyEstimates) -> tuple[Estimate, ...]:
    """Each estimated beacon as a map marker with its 95 % ellipse (east-north metres) and a detail line:
    latitude, longitude, ranges used and excluded (the journal report and the live page)."""
    return tuple(
        Estimate(
            label=f"beacon {b}",
            east_m=float(est.positions_enu_m[i, 0]),
            north_m=float(est.positions_enu_m[i, 1]),
            semi_major_m=float(est.ellipses.semi_major_m[i]),
            semi_minor_m=float(est.ellipses.semi_minor_m[i]),
            angle_rad=float(est.ellipses.angle_rad[i]),
            detail=f"lat {est.positions_geodetic[i, 0]:.7f}°, lon {est.positions_geodetic[i, 1]:.7f}°, "
            f"{est.ranges_used[i]} ranges used, {est.ranges_excluded[i]} excluded",
        )
        for i, b in enumerate(est.beacons)
    )


def journal_report(path: str | Path) -> Report:
    """The report of the journal at ``path`` (see the module docstring)."""
    records, settings, meta = read_journal(path)
    est = survey_estimates(records, settings)
    aligned, has, residual, segs = range_geometry(records, settings, est)
    status = est.range_status[aligned.line]

    estimates = beacon_markers(est)
    planned = np.zeros((0, 2))
    plan_note = ""
    try:
        wp = next_waypoint(records, settings, estimates=est, rng=np.random.default_rng(0))
        planned = np.vstack([wp.from_enu_m[:2], wp.waypoints_enu_m[:, :2]])
        plan_note = (
            f"next site ({wp.planner}): {wp.distance_m:.1f} m at {wp.bearing_deg:.0f}° true, "
            f"lat {wp.next_geodetic[0]:.7f}°, lon {wp.next_geodetic[1]:.7f}°"
        )
    except DataError as exc:
        plan_note = f"no next site: {exc}"
    layers = MapLayers(
        track_en_m=est.track_enu_m[:, :2],
        track_t_s=records.fix_t_unix_s,
        track_label="GPS track",
        range_segments_en_m=segs,
        sites_en_m=planned,
        sites_label="last fix (1) and planned sites in order",
        estimates=estimates,
        origin=est.origin,
    )
    t0 = float(records.fix_t_unix_s[0])
    series = [_residual_series(aligned.t_unix_s - t0, aligned.beacon, residual, status, has, t0)]
    notes = []
    if records.n_ranges <= SIGMA_MAX_RANGES:
        series.insert(0, _sigma_series(records, settings, t0))
    else:
        notes.append(
            f"Sigma by time skipped: {records.n_ranges} ranges (over {SIGMA_MAX_RANGES}); each point is a "
            "full re-estimate from the records up to that time."
        )
    checks = _checks(est, residual, status, aligned.beacon, settings.sigma_range_m)
    counts = {name: int(np.sum(est.range_status == k)) for k, name in enumerate(RANGE_STATUS)}
    summary = (
        f"{records.n_fixes} fixes {_utc(t0)} to {_utc(float(records.fix_t_unix_s[-1]))} UTC, "
        f"{records.n_ranges} ranges, {records.heading_t_unix_s.size} headings",
        "ranges: " + ", ".join(f"{v} {k}" for k, v in counts.items()),
        f"ENU origin lat {est.origin.lat_deg:.7f}°, lon {est.origin.lon_deg:.7f}°, h {est.origin.h_m:.2f} m",
        f"beacons estimated: {', '.join(str(b) for b in est.beacons) or 'none'}; waiting: "
        + (
            ", ".join(
                f"{b} ({n} ranges)" for b, n in zip(est.waiting_beacons, est.waiting_ranges, strict=True)
            )
            or "none"
        ),
        plan_note,
    )
    sig = est.sigma_enu_m
    table = Table(
        title="Beacon estimates",
        header=(
            "beacon",
            "lat (deg)",
            "lon (deg)",
            "h (m)",
            "E (m)",
            "N (m)",
            "U (m)",
            "sd E (m)",
            "sd N (m)",
            "sd U (m)",
            "95% a x b (m)",
            "major axis (deg true)",
            "used",
            "excluded",
            "residual RMS (m)",
        ),
        rows=tuple(
            (
                str(b),
                f"{est.positions_geodetic[i, 0]:.7f}",
                f"{est.positions_geodetic[i, 1]:.7f}",
                f"{est.positions_geodetic[i, 2]:.2f}",
                *(f"{v:.3f}" for v in est.positions_enu_m[i]),
                *(f"{v:.4f}" for v in sig[i]),
                f"{est.ellipses.semi_major_m[i]:.4f} x {est.ellipses.semi_minor_m[i]:.4f}",
                f"{est.ellipse_azimuth_deg[i]:.1f}",
                str(est.ranges_used[i]),
                str(est.ranges_excluded[i]),
                f"{est.residual_rms_m[i]:.4f}",
            )
            for i, b in enumerate(est.beacons)
        ),
    )
    prov = {
        "source": str(path),
        "inputs": [{"path": str(path), "sha256": file_sha256(path)}],
        "journal_format": meta.get("format", "?"),
        "settings": {k: v for k, v in meta.items() if k != "format"},
    }
    return Report(
        kind="journal",
        title=f"Survey journal {Path(path).name}",
        summary=summary,
        map=layers,
        series=tuple(series),
        tables=(table,),
        checks=checks,
        provenance=prov,
        notes=tuple(notes),
    )


def _prefix(r: JournalRecords, t_end: float) -> JournalRecords:
    """The records up to ``t_end`` (inclusive), as the journal held them then."""
    f, g, h = r.fix_t_unix_s <= t_end, r.range_t_unix_s <= t_end, r.heading_t_unix_s <= t_end
    return JournalRecords(
        fix_t_unix_s=r.fix_t_unix_s[f],
        lat_deg=r.lat_deg[f],
        lon_deg=r.lon_deg[f],
        h_m=r.h_m[f],
        range_t_unix_s=r.range_t_unix_s[g],
        beacon=r.beacon[g],
        range_m=r.range_m[g],
        heading_t_unix_s=r.heading_t_unix_s[h],
        heading_deg=r.heading_deg[h],
    )


def _sigma_series(records: JournalRecords, settings: JournalSettings, t0: float) -> Series:
    """Semi-major axis of each beacon's 95 % ellipse, re-estimated at :data:`SIGMA_CUTS` times."""
    cuts = np.linspace(t0, float(records.fix_t_unix_s[-1]), SIGMA_CUTS + 1)[1:]
    by_beacon: dict[int, tuple[list[float], list[float]]] = {}
    for t in cuts:
        est = survey_estimates(_prefix(records, float(t)), settings)
        for b, a in zip(est.beacons, est.ellipses.semi_major_m, strict=True):
            by_beacon.setdefault(int(b), ([], []))
            by_beacon[int(b)][0].append(float(t - t0))
            by_beacon[int(b)][1].append(float(a))
    return Series(
        title="95 % ellipse semi-major axis by time (estimates from the records so far)",
        x_label=f"time from {_utc(t0)} UTC (s)",
        y_label="semi-major axis (m)",
        log_y=True,
        lines=tuple(
            (f"beacon {b}", np.asarray(x), np.asarray(y), "lines+markers", None)
            for b, (x, y) in by_beacon.items()
        ),
    )


def _residual_series(t_s, beacon, residual, status, has, t0) -> Series:
    """Residual per ping, one line per beacon for used ranges, and one per exclusion reason."""
    lines = []
    used = status == RANGE_STATUS.index("used")
    for b in np.unique(beacon[has]):
        sel = used & (beacon == b)
        lines.append((f"beacon {b} used", t_s[sel], residual[sel], "markers", None))
    for reason in ("outlier", "waiting"):
        sel = (status == RANGE_STATUS.index(reason)) & has
        if reason == "waiting":
            sel = status == RANGE_STATUS.index(reason)
        if sel.any():
            lines.append(
                (
                    f"excluded: {reason}",
                    t_s[sel],
                    np.where(has[sel], residual[sel], 0.0),
                    "markers",
                    [f"beacon {b}: {_REASONS[reason]}" for b in beacon[sel]],
                )
            )
    return Series(
        title=f"Range residuals per ping (time from {_utc(t0)} UTC)",
        x_label="time (s)",
        y_label="residual (m)",
        lines=tuple(lines),
    )


def _checks(est: SurveyEstimates, residual, status, beacon, sigma_m: float) -> tuple[Check, ...]:
    checks = []
    used = status == RANGE_STATUS.index("used")
    for i, b in enumerate(est.beacons):
        sel = used & (beacon == b)
        dof = int(sel.sum()) - 3
        if dof < 1:
            continue
        chi2 = float(np.sum(np.square(residual[sel] / sigma_m)))
        lo, hi = stats.chi2.ppf([0.025, 0.975], dof)
        checks.append(
            Check(
                name=f"beacon {b}: sum of squared normalized residuals within the 95 % chi-square interval",
                passed=bool(lo <= chi2 <= hi),
                value=f"{chi2:.4g}",
                bound=f"[{lo:.4g}, {hi:.4g}] ({dof} dof)",
                detail=f"sigma {sigma_m:g} m, residual RMS {est.residual_rms_m[i]:.3f} m",
            )
        )
        share = est.ranges_excluded[i] / max(est.ranges_excluded[i] + est.ranges_used[i], 1)
        checks.append(
            Check(
                name=f"beacon {b}: share of ranges excluded as outliers",
                passed=bool(share <= 0.1),
                value=f"{share:.3f}",
                bound="<= 0.10",
            )
        )
    return tuple(checks)
