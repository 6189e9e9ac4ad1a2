import csv
import json

import numpy as np

from oceanloc.geo.projection import LocalProjection
from oceanloc.io.paths import path_geojson, write_path_csv, write_path_geojson
from oceanloc.models.paths import DriftPath

PATH = DriftPath(
    points_m=np.array([[0.0, 0.0], [30.0, 0.0], [60.0, 0.0], [60.0, 500.0], [90.0, 500.0]]),
    times_s=np.array([0.0, 60.0, 120.0, 170.0, 230.0]),
    flight=np.array([False, False, True, False]),
)


def test_csv_has_every_vertex_and_mode(tmp_path):
    out = write_path_csv(tmp_path / "p.csv", PATH, LocalProjection(lat0_deg=32.7, lon0_deg=-117.2))
    rows = list(csv.DictReader(out.open()))
    assert [r["mode"] for r in rows] == ["start", "drift", "drift", "flight", "drift"]
    assert float(rows[3]["y_m"]) == 500.0
    assert abs(float(rows[0]["lon_deg"]) + 117.2) < 1e-9


def test_geojson_is_lonlat_with_legs_and_hop_points(tmp_path):
    proj = LocalProjection(lat0_deg=32.7, lon0_deg=-117.2)
    data = path_geojson(PATH, proj, {"planner": "x"})
    lines = [f for f in data["features"] if f["geometry"]["type"] == "LineString"]
    points = [f for f in data["features"] if f["geometry"]["type"] == "Point"]
    assert [f["properties"]["mode"] for f in lines] == ["drift", "flight", "drift"]
    assert len(points) == 2 and points[0]["properties"]["role"] == "take-off"
    lon, lat = lines[1]["geometry"]["coordinates"][1]
    x, y = proj.to_local(lon, lat)
    assert abs(float(y) - 500.0) < 0.05 and abs(float(x) - 60.0) < 0.05
    out = write_path_geojson(tmp_path / "p.geojson", PATH, proj)
    assert json.loads(out.read_text())["type"] == "FeatureCollection"


def test_safe_file_stem_keeps_names_in_one_folder():
    from oceanloc.io.paths import safe_file_stem

    assert safe_file_stem("dillard-drift-fixed-oceanloc") == "dillard-drift-fixed-oceanloc"
    assert safe_file_stem("odd[/x] name") == "odd__x__name"
    assert safe_file_stem("..") == "unnamed"
