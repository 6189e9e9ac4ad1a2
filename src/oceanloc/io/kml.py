"""KML 2.2 (OGC 07-147r2) map layers for QGIS, Google Earth and chart plotters (standard library only).

A document holds folders (one per layer: track, sites, estimates, ellipses, ...) of placemarks; each
placemark is a Point, a LineString or a Polygon (one outer ring) with coordinates ``lon,lat[,h]`` in
WGS84 degrees and metres, as KML requires (longitude first). Styles are inline ``<Style>`` elements
with KML's ``aabbggrr`` colours, so the file needs nothing beside it.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.errors import DataError

KML_NS = "http://www.opengis.net/kml/2.2"
"""The KML 2.2 namespace (an identifier, never fetched)."""

GEOMETRIES = ("point", "line", "polygon")


@dataclass(frozen=True, slots=True, kw_only=True)
class Placemark:
    """One map feature.

    Attributes
    ----------
    name : str
    geometry : str
        ``point``, ``line`` or ``polygon``.
    lon_lat_h : (n, 2) or (n, 3) float
        Coordinates: longitude, latitude (degrees), optional height (metres). A polygon's ring is
        closed here if it is not already.
    description : str
        Plain text shown in the balloon.
    color : str
        ``#rrggbb`` colour of the line, marker or fill outline.
    """

    name: str
    geometry: str
    lon_lat_h: FloatArray
    description: str = ""
    color: str = "#1f77b4"


@dataclass(frozen=True, slots=True, kw_only=True)
class KmlFolder:
    """A layer: a named folder of placemarks."""

    name: str
    placemarks: tuple[Placemark, ...]


def kml_color(hex_rgb: str, alpha: float = 1.0) -> str:
    """``#rrggbb`` -> KML ``aabbggrr``."""
    h = hex_rgb.lstrip("#")
    if len(h) != 6:
        raise DataError(f"colour {hex_rgb!r}: expected #rrggbb")
    return f"{round(alpha * 255):02x}{h[4:6]}{h[2:4]}{h[0:2]}"


def _coordinates(p: Placemark) -> str:
    xy = np.asarray(p.lon_lat_h, dtype=float).reshape(-1, np.shape(p.lon_lat_h)[-1])
    if xy.shape[1] not in (2, 3) or xy.shape[0] == 0:
        raise DataError(f"placemark {p.name!r}: coordinates must be (n, 2) or (n, 3), got {xy.shape}")
    if not np.isfinite(xy).all():
        raise DataError(f"placemark {p.name!r}: non-finite coordinate")
    if p.geometry == "polygon" and not np.array_equal(xy[0], xy[-1]):
        xy = np.vstack([xy, xy[:1]])
    need = {"point": 1, "line": 2, "polygon": 4}[p.geometry]
    if xy.shape[0] < need:
        raise DataError(f"placemark {p.name!r}: a {p.geometry} needs at least {need} coordinates")
    return " ".join(",".join(f"{v:.9f}" if i < 2 else f"{v:.3f}" for i, v in enumerate(row)) for row in xy)


def kml_document(name: str, folders: Sequence[KmlFolder]) -> ET.Element:
    """The KML tree: ``<kml><Document>`` with one style per colour used and one ``<Folder>`` per layer."""
    ET.register_namespace("", KML_NS)
    q = f"{{{KML_NS}}}"
    root = ET.Element(f"{q}kml")
    doc = ET.SubElement(root, f"{q}Document")
    ET.SubElement(doc, f"{q}name").text = name
    colours = sorted({p.color for f in folders for p in f.placemarks})
    for c in colours:
        style = ET.SubElement(doc, f"{q}Style", id=f"c{c.lstrip('#')}")
        ET.SubElement(ET.SubElement(style, f"{q}IconStyle"), f"{q}color").text = kml_color(c)
        line = ET.SubElement(style, f"{q}LineStyle")
        ET.SubElement(line, f"{q}color").text = kml_color(c)
        ET.SubElement(line, f"{q}width").text = "2"
        poly = ET.SubElement(style, f"{q}PolyStyle")
        ET.SubElement(poly, f"{q}color").text = kml_color(c, 0.25)
    for folder in folders:
        fe = ET.SubElement(doc, f"{q}Folder")
        ET.SubElement(fe, f"{q}name").text = folder.name
        for p in folder.placemarks:
            if p.geometry not in GEOMETRIES:
                raise DataError(f"placemark {p.name!r}: geometry must be one of {', '.join(GEOMETRIES)}")
            pe = ET.SubElement(fe, f"{q}Placemark")
            ET.SubElement(pe, f"{q}name").text = p.name
            if p.description:
                ET.SubElement(pe, f"{q}description").text = p.description
            ET.SubElement(pe, f"{q}styleUrl").text = f"#c{p.color.lstrip('#')}"
            coords = _coordinates(p)
            if p.geometry == "point":
                geom = ET.SubElement(pe, f"{q}Point")
            elif p.geometry == "line":
                geom = ET.SubElement(pe, f"{q}LineString")
                ET.SubElement(geom, f"{q}tessellate").text = "1"
            else:
                poly = ET.SubElement(pe, f"{q}Polygon")
                geom = ET.SubElement(ET.SubElement(poly, f"{q}outerBoundaryIs"), f"{q}LinearRing")
            ET.SubElement(geom, f"{q}coordinates").text = coords
    return root


def write_kml(path: str | Path, name: str, folders: Sequence[KmlFolder]) -> Path:
    """Write :func:`kml_document` as UTF-8 XML; returns the path."""
    out = Path(path)
    if not out.parent.is_dir():
        raise DataError(f"{out}: folder {out.parent} does not exist")
    tree = ET.ElementTree(kml_document(name, folders))
    ET.indent(tree, space=" ")
    tree.write(out, encoding="utf-8", xml_declaration=True)
    return out


def circle_lon_lat(lon_deg: float, lat_deg: float, radius_m: float, n: int = 73) -> FloatArray:
    """A closed ring of ``n`` points at ``radius_m`` around a point (small-circle, spherical Earth)."""
    theta = np.linspace(0.0, 2.0 * math.pi, n)
    r_earth = 6_371_008.8
    dlat = np.rad2deg(radius_m * np.sin(theta) / r_earth)
    dlon = np.rad2deg(radius_m * np.cos(theta) / (r_earth * math.cos(math.radians(lat_deg))))
    return np.stack([lon_deg + dlon, lat_deg + dlat], axis=1)
