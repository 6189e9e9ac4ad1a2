"""GeoJSON (RFC 7946) features and FeatureCollection files.

Positions are ``[longitude, latitude]`` or ``[longitude, latitude, height]`` in WGS84 degrees and
metres, in that order (RFC 7946 Section 3.1.1). Polygon rings are closed (the last position equals the
first, exactly) and exterior rings run counter-clockwise (the right-hand rule, Section 3.1.6); the
builders enforce both. Non-finite numbers have no JSON form and are rejected, naming the feature.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError, DataError


def point_feature(lon_deg: float, lat_deg: float, h_m: float | None, properties: Mapping[str, Any]) -> dict:
    """A Point feature at one position (height optional)."""
    coords = [float(lon_deg), float(lat_deg)] + ([] if h_m is None else [float(h_m)])
    _check_finite(np.asarray(coords), properties)
    return {
        "type": "Feature",
        "geometry": {"type": "Point", "coordinates": coords},
        "properties": dict(properties),
    }


def polygon_feature(ring_lon_lat: ArrayLike, properties: Mapping[str, Any]) -> dict:
    """A Polygon feature with one exterior ring.

    Parameters
    ----------
    ring_lon_lat : (n, 2) or (n, 3) float
        Longitude, latitude (degrees) and optionally height (metres) along the boundary; closed here if
        it is not (the first position repeated last), reversed if clockwise.
    """
    ring = np.array(ring_lon_lat, dtype=float)
    if ring.ndim != 2 or ring.shape[1] not in (2, 3) or ring.shape[0] < 3:
        raise ConfigError(
            f"a polygon ring needs at least 3 positions of 2 or 3 values, got shape {ring.shape}"
        )
    _check_finite(ring, properties)
    if not np.array_equal(ring[0], ring[-1]):
        ring = np.vstack([ring, ring[:1]])
    if ring.shape[0] < 4:
        raise ConfigError("a polygon ring needs at least 4 positions (3 distinct), RFC 7946 3.1.6")
    if ring_signed_area(ring[:, :2]) < 0.0:
        ring = ring[::-1].copy()
    return {
        "type": "Feature",
        "geometry": {"type": "Polygon", "coordinates": [ring.tolist()]},
        "properties": dict(properties),
    }


def line_feature(coords_lon_lat: ArrayLike, properties: Mapping[str, Any]) -> dict:
    """A LineString feature; ``coords_lon_lat`` is ``(n, 2)`` or ``(n, 3)``, at least 2 positions."""
    line = np.asarray(coords_lon_lat, dtype=float)
    if line.ndim != 2 or line.shape[1] not in (2, 3) or line.shape[0] < 2:
        raise ConfigError(f"a line needs at least 2 positions of 2 or 3 values, got shape {line.shape}")
    _check_finite(line, properties)
    return {
        "type": "Feature",
        "geometry": {"type": "LineString", "coordinates": line.tolist()},
        "properties": dict(properties),
    }


def feature_collection(features: Sequence[dict]) -> dict:
    """A FeatureCollection of the given features."""
    return {"type": "FeatureCollection", "features": list(features)}


def write_geojson(path: str | Path, features: Sequence[dict]) -> Path:
    """Write a FeatureCollection, creating parent folders; an unwritable path is a ConfigError."""
    p = Path(path)
    text = json.dumps(feature_collection(features), indent=1, allow_nan=False)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text + "\n", encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{p}: cannot write GeoJSON ({exc})") from None
    return p


def ring_signed_area(ring_xy: ArrayLike) -> float:
    """Shoelace area of a closed ring ``(n, 2)``: positive counter-clockwise, in the ring's units squared."""
    xy = np.asarray(ring_xy, dtype=float)
    x, y = xy[:, 0], xy[:, 1]
    return float(0.5 * np.sum(x[:-1] * y[1:] - x[1:] * y[:-1]))


def _check_finite(values: FloatArray, properties: Mapping[str, Any]) -> None:
    if not np.all(np.isfinite(values)):
        name = properties.get("name", properties.get("kind", "feature"))
        raise DataError(f"GeoJSON {name}: NaN or infinite coordinate")
    for key, value in properties.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise DataError(f"GeoJSON property {key!r}: NaN or infinite value")
