import json
from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import ConfigError, DataError
from oceanloc.io.csv_tables import write_csv
from oceanloc.io.geojson import line_feature, point_feature, polygon_feature, ring_signed_area, write_geojson


def test_polygon_ring_is_closed_and_counter_clockwise():
    square_cw = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]
    ring = np.array(polygon_feature(square_cw, {"name": "sq"})["geometry"]["coordinates"][0])
    assert ring.shape == (5, 2)
    assert np.array_equal(ring[0], ring[-1])
    assert ring_signed_area(ring) == pytest.approx(1.0)
    with pytest.raises(ConfigError, match="at least 4 positions"):
        polygon_feature([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]], {})


def test_non_finite_values_are_rejected_and_files_are_strict_json(tmp_path: Path):
    with pytest.raises(DataError, match="beacon 3: NaN"):
        point_feature(float("nan"), 32.0, None, {"name": "beacon 3"})
    with pytest.raises(DataError, match="property 'sigma_m'"):
        point_feature(-117.0, 32.0, 1.0, {"sigma_m": float("inf")})
    with pytest.raises(ConfigError, match="at least 2 positions"):
        line_feature([[0.0, 0.0]], {})
    path = write_geojson(tmp_path / "a" / "f.geojson", [point_feature(-117.2, 32.7, -1.0, {"beacon": 1})])
    data = json.loads(path.read_text())
    assert data["type"] == "FeatureCollection"
    assert data["features"][0]["geometry"]["coordinates"] == [-117.2, 32.7, -1.0]


def test_csv_floats_round_trip_exactly(tmp_path: Path):
    x = np.array([0.1 + 0.2, 1e-300, np.nan])
    path = write_csv(tmp_path / "t.csv", {"x_m": x, "name": ["a", "b", "c"], "ok": [True, False, True]})
    lines = path.read_text().splitlines()
    assert lines[0] == "x_m,name,ok" and lines[3] == ",c,true"
    assert float(lines[1].split(",")[0]) == x[0]
    with pytest.raises(ConfigError, match="different lengths"):
        write_csv(tmp_path / "u.csv", {"a": [1, 2], "b": [1]})
