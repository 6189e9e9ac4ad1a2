"""What an HTML report holds, independent of where it came from: map layers, series, checks, provenance.

Every source kind (survey journal, simulated survey, Monte Carlo, GNSS-A, reproduction, drift plan) is
read into one :class:`Report`; :mod:`oceanloc.report.html.page` draws it and
:func:`oceanloc.report.html.kml_layers.report_kml` writes its map layers as KML.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import FloatArray
from oceanloc.geo.enu import EnuOrigin


@dataclass(frozen=True, slots=True, kw_only=True)
class Estimate:
    """One estimated position with its 95 % east-north confidence ellipse (metres, ENU).

    ``angle_rad`` is the major axis's direction, counter-clockwise from east.
    """

    label: str
    east_m: float
    north_m: float
    semi_major_m: float
    semi_minor_m: float
    angle_rad: float
    truth_en_m: tuple[float, float] | None = None
    detail: str = ""

    def ring_en_m(self, n: int = 73) -> FloatArray:
        """The ellipse as a closed ring, ``(n, 2)`` east, north, metres."""
        t = np.linspace(0.0, 2.0 * np.pi, n)
        x, y = self.semi_major_m * np.cos(t), self.semi_minor_m * np.sin(t)
        c, s = np.cos(self.angle_rad), np.sin(self.angle_rad)
        ring = np.stack([self.east_m + c * x - s * y, self.north_m + s * x + c * y], axis=1)
        ring[-1] = ring[0]
        return ring


@dataclass(frozen=True, slots=True, kw_only=True)
class Circle:
    """A circle on the map (obstacle, watch circle, goal tolerance), metres."""

    label: str
    east_m: float
    north_m: float
    radius_m: float


@dataclass(frozen=True, slots=True, kw_only=True)
class MapLayers:
    """The map: everything in one ENU frame (metres), optionally georeferenced by ``origin``.

    Attributes
    ----------
    track_en_m : (n, 2) float
        The vehicle track, every point (the page thins what it draws, never this).
    track_t_s : (n,) float or None
        Time of each track point, seconds (Unix or from start).
    range_segments_en_m : (k, 2, 2) float
        Each range as taken: from the vehicle to the estimate of its beacon.
    sites_en_m : (s, 2) float
        Measurement sites in the order visited (or planned).
    sites_label : str
    sites_connect : bool
        Join the sites with a dotted line (their order); False for start and goal.
    estimates : tuple of Estimate
    legs : tuple of (label, (p, 2) float)
        Extra polylines (drift and flight legs).
    circles : tuple of Circle
    polygons : tuple of (label, (p, 2) float)
        Obstacles.
    current : (q, 4) float or None
        Current field arrows: east, north, u, v (m, m/s).
    origin : EnuOrigin or None
    """

    track_en_m: FloatArray = dataclasses.field(default_factory=lambda: np.zeros((0, 2)))
    track_t_s: FloatArray | None = None
    track_label: str = "track"
    range_segments_en_m: FloatArray = dataclasses.field(default_factory=lambda: np.zeros((0, 2, 2)))
    sites_en_m: FloatArray = dataclasses.field(default_factory=lambda: np.zeros((0, 2)))
    sites_label: str = "sites (in order)"
    sites_connect: bool = True
    estimates: tuple[Estimate, ...] = ()
    legs: tuple[tuple[str, FloatArray], ...] = ()
    circles: tuple[Circle, ...] = ()
    polygons: tuple[tuple[str, FloatArray], ...] = ()
    current: FloatArray | None = None
    origin: EnuOrigin | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Check:
    """One row of the checks table: a value against its bound, passed or not."""

    name: str
    passed: bool
    value: str = ""
    bound: str = ""
    detail: str = ""


@dataclass(frozen=True, slots=True, kw_only=True)
class Series:
    """One time-series panel: named lines over a shared x axis (plotly-free description).

    ``lines`` holds (name, x, y, mode, hover) tuples; ``mode`` is ``lines``, ``markers`` or
    ``lines+markers``; ``hover`` is None or one text per point.
    """

    title: str
    x_label: str
    y_label: str
    lines: tuple[tuple[str, FloatArray, FloatArray, str, list[str] | None], ...]
    log_y: bool = False
    bands: tuple[tuple[str, float, float], ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class Table:
    """A plain table (every numeric header carries its unit)."""

    title: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


@dataclass(frozen=True, slots=True, kw_only=True)
class Report:
    """One report: its kind, title, summary lines, map, series, tables, checks and provenance."""

    kind: str
    title: str
    summary: tuple[str, ...] = ()
    map: MapLayers | None = None
    series: tuple[Series, ...] = ()
    tables: tuple[Table, ...] = ()
    checks: tuple[Check, ...] = ()
    provenance: dict = dataclasses.field(default_factory=dict)
    notes: tuple[str, ...] = ()
