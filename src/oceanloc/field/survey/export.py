"""Exports of a survey journal: GeoJSON for a map, CSV for a spreadsheet.

* GeoJSON FeatureCollection (RFC 7946, longitude before latitude): each estimated beacon as a Point
  (height included) with its ENU position, 1-sigma and ellipse in the properties; its 95 % confidence
  ellipse as a closed counter-clockwise Polygon; the vehicle track as a LineString.
* CSV, one file per table in a folder: ``fixes.csv``, ``headings.csv``, ``ranges.csv`` (each range's
  status: used, outlier, no-gps, waiting) and ``estimates.csv``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc.errors import ConfigError, DataError
from oceanloc.field.survey.estimates import (
    ELLIPSE_CONFIDENCE,
    RANGE_STATUS,
    SurveyEstimates,
    stored_survey_estimates,
)
from oceanloc.field.survey.journal import Journal, JournalRecords
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.io.csv_tables import write_csv
from oceanloc.io.geojson import line_feature, point_feature, polygon_feature, write_geojson
from oceanloc.io.usbl import format_utc

CSV_FILES: tuple[str, ...] = ("fixes.csv", "headings.csv", "ranges.csv", "estimates.csv")


def survey_features(
    records: JournalRecords, estimates: SurveyEstimates, ring_points: int = 129
) -> list[dict]:
    """GeoJSON features: per beacon a Point and its 95 % ellipse Polygon, then the track LineString."""
    features = []
    rings = estimates.ellipse_rings_geodetic(ring_points)
    columns = estimate_columns(estimates)
    for i, beacon in enumerate(estimates.beacons):
        props = {name: _plain(col[i]) for name, col in columns.items()}
        lat, lon, h = estimates.positions_geodetic[i]
        features.append(point_feature(lon, lat, h, {"kind": "beacon", "name": f"beacon {beacon}", **props}))
        features.append(
            polygon_feature(
                rings[i][:, [1, 0]],
                {
                    "kind": "ellipse",
                    "name": f"beacon {beacon} {ELLIPSE_CONFIDENCE:.0%} ellipse",
                    "beacon": int(beacon),
                    "confidence": ELLIPSE_CONFIDENCE,
                    "semi_major_m": float(estimates.ellipses.semi_major_m[i]),
                    "semi_minor_m": float(estimates.ellipses.semi_minor_m[i]),
                    "major_azimuth_deg": float(estimates.ellipse_azimuth_deg[i]),
                    "area_m2": float(estimates.ellipse_area_m2[i]),
                },
            )
        )
    if records.n_fixes >= 2:
        coords = np.stack([records.lon_deg, records.lat_deg, records.h_m], axis=1)
        features.append(
            line_feature(
                coords,
                {
                    "kind": "track",
                    "name": "vehicle track",
                    "fixes": records.n_fixes,
                    "start_utc": format_utc(float(records.fix_t_unix_s[0])),
                    "end_utc": format_utc(float(records.fix_t_unix_s[-1])),
                },
            )
        )
    return features


def export_geojson(path: str | Path, records: JournalRecords, estimates: SurveyEstimates) -> Path:
    """Write :func:`survey_features` as a GeoJSON FeatureCollection file."""
    return write_geojson(path, survey_features(records, estimates))


def estimate_columns(estimates: SurveyEstimates) -> dict[str, np.ndarray]:
    """One column per quantity, one row per estimated beacon (the ``estimates.csv`` table)."""
    e = estimates
    sig = e.sigma_enu_m
    return {
        "beacon": e.beacons,
        "e_m": e.positions_enu_m[:, 0],
        "n_m": e.positions_enu_m[:, 1],
        "u_m": e.positions_enu_m[:, 2],
        "lat_deg": e.positions_geodetic[:, 0],
        "lon_deg": e.positions_geodetic[:, 1],
        "h_m": e.positions_geodetic[:, 2],
        "sigma_e_m": sig[:, 0],
        "sigma_n_m": sig[:, 1],
        "sigma_u_m": sig[:, 2],
        "cov_en_m2": e.covariances_m2[:, 0, 1],
        "ellipse95_semi_major_m": e.ellipses.semi_major_m,
        "ellipse95_semi_minor_m": e.ellipses.semi_minor_m,
        "ellipse95_major_azimuth_deg": e.ellipse_azimuth_deg,
        "ranges_used": e.ranges_used,
        "ranges_excluded": e.ranges_excluded,
        "residual_rms_m": e.residual_rms_m,
    }


def export_csv(folder: str | Path, records: JournalRecords, estimates: SurveyEstimates) -> list[Path]:
    """Write the :data:`CSV_FILES` tables into ``folder`` (created if needed); returns their paths."""
    out = Path(folder)
    r, e = records, estimates
    utc = [format_utc(float(t)) for t in r.fix_t_unix_s]
    fixes = write_csv(
        out / "fixes.csv",
        {
            "t_unix_s": r.fix_t_unix_s,
            "utc": utc,
            "lat_deg": r.lat_deg,
            "lon_deg": r.lon_deg,
            "h_m": r.h_m,
            "e_m": e.track_enu_m[:, 0],
            "n_m": e.track_enu_m[:, 1],
            "u_m": e.track_enu_m[:, 2],
        },
    )
    headings = write_csv(
        out / "headings.csv",
        {
            "t_unix_s": r.heading_t_unix_s,
            "utc": [format_utc(float(t)) for t in r.heading_t_unix_s],
            "heading_deg": r.heading_deg,
        },
    )
    ranges = write_csv(
        out / "ranges.csv",
        {
            "t_unix_s": r.range_t_unix_s,
            "utc": [format_utc(float(t)) for t in r.range_t_unix_s],
            "beacon": r.beacon,
            "range_m": r.range_m,
            "status": [RANGE_STATUS[s] for s in e.range_status],
        },
    )
    table = write_csv(out / "estimates.csv", estimate_columns(e))
    return [fixes, headings, ranges, table]


def _plain(value: object) -> object:
    return value.item() if isinstance(value, np.generic) else value


@dataclass(frozen=True, slots=True, kw_only=True)
class JournalExport:
    """What ``survey export`` wrote: the GeoJSON file and the CSV tables (paths), and what they hold."""

    geojson: Path | None
    csv: tuple[Path, ...]
    csv_folder: Path | None
    n_beacons: int
    n_fixes: int


def export_journal(
    path: str | Path, *, geojson: str | Path | None = None, csv: str | Path | None = None
) -> JournalExport:
    """Export a journal's estimates with their 95 % ellipses and the track (GeoJSON) and every table (CSV).

    Raises
    ------
    ConfigError
        If neither output is given.
    """
    if geojson is None and csv is None:
        raise ConfigError("nothing to export: give --geojson PATH and/or --csv DIR")
    with Journal.open(path) as j:
        settings = JournalSettings.from_meta(j.meta(), str(path))
        rec = j.records(headings=False)
        if rec.n_fixes == 0:
            raise DataError("no GPS fix in the journal yet: nothing to export")
        est = stored_survey_estimates(j, settings, rec)
    return JournalExport(
        geojson=None if geojson is None else export_geojson(geojson, rec, est),
        csv=() if csv is None else tuple(export_csv(csv, rec, est)),
        csv_folder=None if csv is None else Path(csv),
        n_beacons=est.n_beacons,
        n_fixes=rec.n_fixes,
    )
