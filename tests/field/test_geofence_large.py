"""Geofence files as exported from a GIS: coastlines of 10^5 vertices, and hostile nesting."""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from oceanloc.errors import ConfigError
from oceanloc.field.geofence import _segments_cross, _self_crossing, contains, fence_from_ring, read_geofence


def _brute_force_crossing(ring_en: np.ndarray) -> tuple[int, int] | None:
    """Every pair of non-adjacent edges, the first (i, j) in lexicographic order (the reference)."""
    a, b = ring_en, np.roll(ring_en, -1, axis=0)
    n = a.shape[0]
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            if _segments_cross(a[i], b[i], a[j], b[j]):
                return i, j
    return None


@pytest.mark.parametrize("seed", range(40))
def test_the_sweep_finds_the_same_first_crossing_as_every_pair(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 40))
    if seed % 2:
        ring = rng.uniform(-100, 100, (n, 2))  # random vertices: most rings cross themselves
    else:  # star-shaped with a few spikes pulled across: some cross, some do not
        theta = np.sort(rng.uniform(0, 2 * math.pi, n))
        radius = 50 + 30 * rng.standard_normal(n) * (rng.uniform(size=n) < 0.2)
        ring = np.stack([radius * np.cos(theta), radius * np.sin(theta)], axis=-1)
    assert _self_crossing(ring) == _brute_force_crossing(ring)


def _coastline(n: int, seed: int = 7) -> np.ndarray:
    """A star-shaped ring of ``n`` vertices with a wiggly radius (a coastline's scale of detail), lon/lat."""
    rng = np.random.default_rng(seed)
    theta = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    wiggle = np.cumsum(rng.standard_normal(n))
    wiggle -= np.linspace(0.0, wiggle[-1], n)  # closes smoothly
    radius_m = 5000.0 + 400.0 * wiggle / np.abs(wiggle).max()
    east, north = radius_m * np.cos(theta), radius_m * np.sin(theta)
    lat = 32.7 + north / 111_000.0
    lon = -117.2 + east / (111_000.0 * math.cos(math.radians(32.7)))
    ring = np.stack([lon, lat], axis=-1)
    return np.vstack([ring, ring[:1]])


def test_a_coastline_of_50000_vertices_loads(tmp_path: Path):
    """The all-pairs check had not finished after 200 s at 200,000 vertices; the speed at that size is in
    `make bench` (geofence), as timing is not a test's business."""
    ring = _coastline(50_000)
    path = tmp_path / "coast.geojson"
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [ring.tolist()]}))
    fence = read_geofence(path)
    assert fence.ring_en_m.shape == (50_000, 2)
    assert contains(fence, 32.7, -117.2) and not contains(fence, 32.8, -117.2)


def test_a_coastline_that_crosses_itself_once_is_refused_naming_the_edges():
    ring = _coastline(20_000)
    ring[100] = ring[110] + (ring[110] - ring[100])  # one spike across the following edges
    ring[-1] = ring[0]
    with pytest.raises(ConfigError, match=r"crosses itself \(edges (\d+) and (\d+)\)") as info:
        fence_from_ring(ring)
    i, j = (int(k) for k in info.value.args[0].split("edges ")[1].rstrip(")").split(" and "))
    assert 99 <= i <= 101 and 100 <= j <= 112


SOURCES = ("--position", "udp://127.0.0.1:10110", "--ranges", "udp://127.0.0.1:10111")


def _survey(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "oceanloc", "survey", *args], capture_output=True, text=True, env=os.environ,
        timeout=120,
    )  # fmt: skip


def test_geojson_nested_100000_deep_is_a_one_line_error_through_the_command(tmp_path: Path):
    deep = tmp_path / "deep.geojson"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    nested = tmp_path / "nested.geojson"
    doc: dict = {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 0]]]}
    for _ in range(40):
        doc = {"type": "GeometryCollection", "geometries": [doc]}
    nested.write_text(json.dumps(doc))
    journal = tmp_path / "j.db"
    assert _survey("start", str(journal), "--beacon", "1").returncode == 0
    for path, reason in ((deep, "JSON nested too deeply"), (nested, "nested deeper than 16 levels")):
        with pytest.raises(ConfigError, match=reason):
            read_geofence(path)
        res = _survey("run", str(journal), *SOURCES, "--goal", "1", "--fence", str(path))
        assert res.returncode == 2, res.stderr
        assert "Traceback" not in res.stderr and "RecursionError" not in res.stderr
        assert f"{path.name}: " in res.stderr and reason in " ".join(res.stderr.split())
