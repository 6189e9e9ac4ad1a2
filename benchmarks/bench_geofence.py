"""Loading a coastline-sized geofence: a GeoJSON ring of 200,000 vertices (issue 22).

Target: under 2 s of CPU from the file to a checked fence (parse, projection, the self-crossing sweep,
area). The earlier all-pairs crossing check had not finished after 200 s. CPU time of this process, so
the figure does not depend on the machine's other load. Run: ``python benchmarks/run.py geofence``.
"""

from __future__ import annotations

import json
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from oceanloc.field.geofence import read_geofence

TARGET_CPU_S = 2.0
VERTICES = 200_000
REPEATS = 3


def coastline_geojson(path: Path, n: int, seed: int = 1) -> None:
    """A star-shaped ring of ``n`` vertices about 32.7 N, 117.2 W, its radius a closed random walk."""
    rng = np.random.default_rng(seed)
    theta = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    walk = np.cumsum(rng.standard_normal(n))
    walk -= np.linspace(0.0, walk[-1], n)
    radius_m = 8000.0 + 1500.0 * walk / np.abs(walk).max()
    lat = 32.7 + radius_m * np.sin(theta) / 111_000.0
    lon = -117.2 + radius_m * np.cos(theta) / (111_000.0 * math.cos(math.radians(32.7)))
    ring = np.stack([lon, lat], axis=-1)
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [np.vstack([ring, ring[:1]]).tolist()]}))


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "coast.geojson"
        coastline_geojson(path, VERTICES)
        times = []
        for _ in range(REPEATS):
            start = time.process_time()
            fence = read_geofence(path)
            times.append(time.process_time() - start)
    assert fence.ring_en_m.shape == (VERTICES, 2)
    median = statistics.median(times)
    verdict = "met" if median <= TARGET_CPU_S else "NOT met"
    print(
        f"load a {VERTICES:,}-vertex GeoJSON fence: median {median:.2f} s CPU "
        f"(min {min(times):.2f}, {REPEATS} runs); target <= {TARGET_CPU_S:.1f} s: {verdict}"
    )


if __name__ == "__main__":
    main()
