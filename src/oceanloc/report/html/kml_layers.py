"""The report's map layers as KML: track, ranges, sites, estimates and their 95 % ellipses as polygons."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from oceanloc.errors import DataError
from oceanloc.geo.enu import EnuOrigin, enu_to_geodetic
from oceanloc.io.kml import KmlFolder, Placemark, write_kml
from oceanloc.report.html.model import MapLayers, Report
from oceanloc.report.html.page import COLORS


def _lon_lat(en: np.ndarray, origin: EnuOrigin) -> np.ndarray:
    en = np.asarray(en, dtype=float).reshape(-1, 2)
    geo = enu_to_geodetic(np.concatenate([en, np.zeros((en.shape[0], 1))], axis=1), origin).reshape(-1, 3)
    return geo[:, [1, 0]]


def map_folders(layers: MapLayers, origin: EnuOrigin) -> list[KmlFolder]:
    """One folder per layer present (every track point is written: KML is for data, not drawing)."""
    folders = []
    if layers.track_en_m.shape[0] >= 2:
        folders.append(
            KmlFolder(
                name="track",
                placemarks=(
                    Placemark(
                        name=layers.track_label,
                        geometry="line",
                        lon_lat_h=_lon_lat(layers.track_en_m, origin),
                        description=f"{layers.track_en_m.shape[0]} points",
                    ),
                ),
            )
        )
    for label, leg in layers.legs:
        parts = np.split(leg, np.flatnonzero(np.isnan(leg[:, 0])))
        marks = tuple(
            Placemark(
                name=f"{label} {i + 1}",
                geometry="line",
                lon_lat_h=_lon_lat(p, origin),
                color="#d62728" if "flight" in label else "#2ca02c",
            )
            for i, p in enumerate(q[~np.isnan(q[:, 0])] for q in parts)
            if p.shape[0] >= 2
        )
        folders.append(KmlFolder(name=label, placemarks=marks))
    if layers.sites_en_m.size:
        folders.append(
            KmlFolder(
                name="sites",
                placemarks=tuple(
                    Placemark(
                        name=f"site {i + 1}",
                        geometry="point",
                        lon_lat_h=_lon_lat(s, origin),
                        color="#ff7f0e",
                        description=layers.sites_label,
                    )
                    for i, s in enumerate(layers.sites_en_m)
                ),
            )
        )
    if layers.polygons:
        folders.append(
            KmlFolder(
                name="obstacles",
                placemarks=tuple(
                    Placemark(
                        name=f"{label} {i + 1}",
                        geometry="polygon",
                        lon_lat_h=_lon_lat(p, origin),
                        color="#555555",
                    )
                    for i, (label, p) in enumerate(layers.polygons)
                ),
            )
        )
    if layers.circles:
        t = np.linspace(0, 2 * np.pi, 73)
        folders.append(
            KmlFolder(
                name="circles",
                placemarks=tuple(
                    Placemark(
                        name=c.label,
                        geometry="polygon",
                        color="#7f7f7f",
                        lon_lat_h=_lon_lat(
                            np.column_stack(
                                [c.east_m + c.radius_m * np.cos(t), c.north_m + c.radius_m * np.sin(t)]
                            ),
                            origin,
                        ),
                    )
                    for c in layers.circles
                ),
            )
        )
    if layers.estimates:
        folders.append(
            KmlFolder(
                name="estimates",
                placemarks=tuple(
                    Placemark(
                        name=e.label,
                        geometry="point",
                        lon_lat_h=_lon_lat([e.east_m, e.north_m], origin),
                        color=COLORS[i % len(COLORS)],
                        description=e.detail,
                    )
                    for i, e in enumerate(layers.estimates)
                ),
            )
        )
        folders.append(
            KmlFolder(
                name="95% ellipses",
                placemarks=tuple(
                    Placemark(
                        name=f"{e.label} 95% ellipse",
                        geometry="polygon",
                        lon_lat_h=_lon_lat(e.ring_en_m(), origin),
                        color=COLORS[i % len(COLORS)],
                        description=f"semi-axes {e.semi_major_m:.4g} x {e.semi_minor_m:.4g} m",
                    )
                    for i, e in enumerate(layers.estimates)
                ),
            )
        )
    return folders


def report_kml(report: Report, path: str | Path, origin: EnuOrigin | None = None) -> Path:
    """Write the report's map as KML; a local frame needs ``origin`` (the map's own origin wins).

    Raises
    ------
    DataError
        If the report has no map, or its frame is local and no origin is given.
    """
    if report.map is None:
        raise DataError(f"a {report.kind} report has no map: nothing to write as KML")
    o = report.map.origin or origin
    if o is None:
        raise DataError(
            f"the {report.kind} record is in a local frame: pass --origin LAT,LON to place it for KML"
        )
    return write_kml(path, report.title, map_folders(report.map, o))
