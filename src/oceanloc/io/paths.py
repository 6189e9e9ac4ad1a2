"""Writers for drift/flight plans: CSV (every vertex), GeoJSON (RFC 7946) and KML (longitude/latitude).

CSV columns: ``t_s, x_m, y_m, mode`` (``drift`` or ``flight`` for the edge that *ends* at the vertex,
``start`` for the first) and, when the plan is georeferenced, ``lon_deg, lat_deg``. GeoJSON needs WGS84
coordinates, so it is written only with a :class:`~oceanloc.geo.projection.LocalProjection` (from a
longitude/latitude current product, or an origin the user gives): a FeatureCollection with one LineString
per drift leg and per flight (``properties.mode``) and one Point per take-off and landing, built with
:mod:`oceanloc.io.geojson`. The KML file (:mod:`oceanloc.io.kml`) has the same layers: drifts, flights and
the take-off and landing points, with the time of each. Vehicle missions are :mod:`oceanloc.io.missions`.
"""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from typing import Any

import numpy as np

from oceanloc.errors import ConfigError
from oceanloc.geo.projection import LocalProjection
from oceanloc.io.geojson import feature_collection, line_feature, point_feature
from oceanloc.io.kml import KmlFolder, Placemark, write_kml
from oceanloc.models.paths import DriftPath


def safe_file_stem(name: str) -> str:
    """``name`` (a scenario or planner name from a file) made safe as one file name: every character
    other than letters, digits, ``.``, ``_`` and ``-`` becomes ``_`` (no folder separators, no markup)."""
    stem = re.sub(r"[^A-Za-z0-9._-]", "_", name).strip(".")
    return stem or "unnamed"


def write_path_csv(path: str | Path, plan: DriftPath, projection: LocalProjection | None = None) -> Path:
    """Every vertex of ``plan`` as CSV (see the module docstring)."""
    p = Path(path)
    modes = ["start"] + ["flight" if f else "drift" for f in plan.flight]
    header = ["t_s", "x_m", "y_m", "mode"]
    lonlat = None
    if projection is not None:
        header += ["lon_deg", "lat_deg"]
        lonlat = projection.to_lonlat(plan.points_m[:, 0], plan.points_m[:, 1])
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        with p.open("w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(header)
            for i in range(plan.n_points):
                row: list[Any] = [
                    f"{plan.times_s[i]:.1f}",
                    f"{plan.points_m[i, 0]:.2f}",
                    f"{plan.points_m[i, 1]:.2f}",
                    modes[i],
                ]
                if lonlat is not None:
                    row += [f"{lonlat[0][i]:.7f}", f"{lonlat[1][i]:.7f}"]
                w.writerow(row)
    except OSError as exc:
        raise ConfigError(f"{p}: cannot write CSV ({exc})") from None
    return p


def _legs(plan: DriftPath) -> list[tuple[int, int, str]]:
    """``(first vertex, last vertex, "drift" | "flight")`` of every run of equal edges."""
    if plan.n_points < 2:
        return []
    change = np.flatnonzero(np.diff(plan.flight.astype(np.int8)) != 0) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [plan.flight.size]])
    return [
        (int(a), int(b), "flight" if plan.flight[a] else "drift") for a, b in zip(starts, ends, strict=True)
    ]


def path_geojson(
    plan: DriftPath, projection: LocalProjection, properties: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The plan as a GeoJSON FeatureCollection (longitude, latitude)."""
    lon, lat = projection.to_lonlat(plan.points_m[:, 0], plan.points_m[:, 1])
    coords = np.column_stack([lon, lat]).round(7)
    features: list[dict[str, Any]] = [
        line_feature(
            coords[a : b + 1],
            {"mode": mode, "t_start_s": float(plan.times_s[a]), "t_end_s": float(plan.times_s[b])},
        )
        for a, b, mode in _legs(plan)
    ]
    for k, hop in enumerate(plan.hops_m()):
        for role, point in (("take-off", hop[0]), ("landing", hop[1])):
            plon, plat = projection.to_lonlat(point[0], point[1])
            features.append(
                point_feature(round(float(plon), 7), round(float(plat), 7), None, {"role": role, "hop": k})
            )
    return {**feature_collection(features), "properties": properties or {}}


def path_kml_folders(plan: DriftPath, projection: LocalProjection) -> list[KmlFolder]:
    """KML layers of the plan: drift legs, flights, take-off and landing points (times in the names)."""
    lon, lat = projection.to_lonlat(plan.points_m[:, 0], plan.points_m[:, 1])
    coords = np.column_stack([lon, lat])
    legs = {"drift": [], "flight": []}
    for a, b, mode in _legs(plan):
        t0, t1 = float(plan.times_s[a]), float(plan.times_s[b])
        legs[mode].append(
            Placemark(
                name=f"{mode} {t0 / 3600:.2f}-{t1 / 3600:.2f} h",
                geometry="line",
                lon_lat_h=coords[a : b + 1],
                description=f"{mode} from {t0:.0f} s to {t1:.0f} s ({(t1 - t0) / 60:.1f} min)",
                color="#0072b2" if mode == "drift" else "#d55e00",
            )
        )
    points = []
    idx = np.flatnonzero(plan.flight)
    for k, i in enumerate(idx):
        for role, j in (("take-off", i), ("landing", i + 1)):
            points.append(
                Placemark(
                    name=f"{role} {k + 1}",
                    geometry="point",
                    lon_lat_h=coords[j],
                    description=f"{role} {k + 1} at {float(plan.times_s[j]):.0f} s",
                    color="#009e73" if role == "landing" else "#e69f00",
                )
            )
    return [
        KmlFolder(name="drift legs", placemarks=tuple(legs["drift"])),
        KmlFolder(name="powered legs", placemarks=tuple(legs["flight"])),
        KmlFolder(name="take-off and landing points", placemarks=tuple(points)),
    ]


def write_path_kml(path: str | Path, plan: DriftPath, projection: LocalProjection, name: str) -> Path:
    """Write :func:`path_kml_folders` as a KML document."""
    p = Path(path)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{p}: cannot write KML ({exc})") from None
    return write_kml(p, name, path_kml_folders(plan, projection))


def write_path_geojson(
    path: str | Path, plan: DriftPath, projection: LocalProjection, properties: dict[str, Any] | None = None
) -> Path:
    """Write :func:`path_geojson` to ``path``."""
    p = Path(path)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(
            json.dumps(path_geojson(plan, projection, properties), indent=1) + "\n", encoding="utf-8"
        )
    except OSError as exc:
        raise ConfigError(f"{p}: cannot write GeoJSON ({exc})") from None
    return p
