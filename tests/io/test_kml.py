import xml.etree.ElementTree as ET

import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.io.kml import KML_NS, KmlFolder, Placemark, circle_lon_lat, kml_color, write_kml

Q = {"k": KML_NS}


def _doc(tmp_path, folders):
    path = write_kml(tmp_path / "m.kml", "test", folders)
    return ET.parse(path).getroot()


def test_structure_namespace_styles_and_geometries(tmp_path):
    ring = circle_lon_lat(-117.2, 32.7, 50.0)
    root = _doc(
        tmp_path,
        [
            KmlFolder(
                name="track",
                placemarks=(
                    Placemark(name="t", geometry="line", lon_lat_h=[[-117.2, 32.7], [-117.3, 32.8]]),
                ),
            ),
            KmlFolder(
                name="ellipses",
                placemarks=(Placemark(name="e", geometry="polygon", lon_lat_h=ring[:-1], color="#d62728"),),
            ),
            KmlFolder(
                name="sites",
                placemarks=(Placemark(name="s", geometry="point", lon_lat_h=[[-117.25, 32.75, -5.0]]),),
            ),
        ],
    )
    assert root.tag == f"{{{KML_NS}}}kml"
    assert [f.findtext("k:name", namespaces=Q) for f in root.iterfind("k:Document/k:Folder", Q)] == [
        "track",
        "ellipses",
        "sites",
    ]
    styles = {s.get("id") for s in root.iterfind("k:Document/k:Style", Q)}
    urls = {u.text.lstrip("#") for u in root.iterfind(".//k:styleUrl", Q)}
    assert urls <= styles
    line = root.find(".//k:LineString/k:coordinates", Q).text.split()
    assert line[0] == "-117.200000000,32.700000000"  # longitude first
    coords = root.find(".//k:Polygon/k:outerBoundaryIs/k:LinearRing/k:coordinates", Q).text.split()
    assert coords[0] == coords[-1] and len(coords) == ring.shape[0]  # closed by the writer
    assert root.find(".//k:Point/k:coordinates", Q).text == "-117.250000000,32.750000000,-5.000"


def test_circle_radius_and_colour():
    ring = circle_lon_lat(0.0, 60.0, 1000.0)
    dy = np.deg2rad(ring[:, 1] - 60.0) * 6_371_008.8
    dx = np.deg2rad(ring[:, 0]) * 6_371_008.8 * np.cos(np.deg2rad(60.0))
    assert np.hypot(dx, dy) == pytest.approx(1000.0, rel=1e-3)
    assert kml_color("#102030", 0.5) == "80302010"


def test_bad_placemarks_are_data_errors(tmp_path):
    with pytest.raises(DataError, match="a line needs at least 2"):
        _doc(
            tmp_path,
            [KmlFolder(name="f", placemarks=(Placemark(name="x", geometry="line", lon_lat_h=[[0.0, 0.0]]),))],
        )
    with pytest.raises(DataError, match="non-finite"):
        _doc(
            tmp_path,
            [
                KmlFolder(
                    name="f", placemarks=(Placemark(name="x", geometry="point", lon_lat_h=[[np.nan, 0.0]]),)
                )
            ],
        )
    with pytest.raises(DataError, match="geometry must be one of"):
        _doc(
            tmp_path,
            [
                KmlFolder(
                    name="f", placemarks=(Placemark(name="x", geometry="circle", lon_lat_h=[[0.0, 0.0]]),)
                )
            ],
        )
    with pytest.raises(DataError, match="does not exist"):
        write_kml(tmp_path / "no" / "m.kml", "x", [])
