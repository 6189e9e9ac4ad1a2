"""The calibration patterns crews sail today, as ping-by-ping tracks: CASIUS's circle with crossing lines,
a box-in, and a single straight line (what cannot calibrate a head).

A track is sampled at the ping period: one position (the vessel's reference point, ENU metres) and one
heading per ping (clockwise from north, radians; the vessel heads along its course), so the same
simulator and estimator run every pattern and the planned one alike.

Readings (Sonardyne's CASIUS documentation describes the pattern in words and figures, not numbers):

* **CASIUS** (:func:`casius_track`): a circle of radius ``radius_m`` (about the water depth) around the
  beacon, sailed once clockwise, then four lines through the beacon at 0, 45, 90 and 135 degrees, each
  from the circle to the opposite side of it and back the other way ("four crossing lines sailed both
  ways"). Turns at the ends of a line are half circles of ``turn_radius_m`` outside the circle; the
  vessel reaches the next line along the circle. Pings all along, turns and transits included.
* **Box-in** (:func:`box_in_track`): a square of half side ``half_side_m`` centred on the beacon, sailed
  once clockwise and once anticlockwise (each side on two opposite headings).
* **Straight line** (:func:`line_track`): one pass over the beacon on one heading.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ConfigError


@dataclass(frozen=True, slots=True, kw_only=True)
class CalibrationTrack:
    """Vessel positions and headings at each ping.

    Attributes
    ----------
    pos_enu_m : (n, 3) float
    heading_rad : (n,) float
        Clockwise from north.
    t_s : (n,) float
        Ping times from the start, seconds.
    name : str
    """

    pos_enu_m: FloatArray
    heading_rad: FloatArray
    t_s: FloatArray
    name: str

    @property
    def pings(self) -> int:
        return int(self.t_s.size)

    @property
    def length_m(self) -> float:
        """Distance sailed, metres."""
        return float(np.sum(np.linalg.norm(np.diff(self.pos_enu_m[:, :2], axis=0), axis=1)))

    def head(self, count: int) -> CalibrationTrack:
        return CalibrationTrack(
            pos_enu_m=self.pos_enu_m[:count],
            heading_rad=self.heading_rad[:count],
            t_s=self.t_s[:count],
            name=self.name,
        )

    def length_at(self) -> FloatArray:
        """Distance sailed up to each ping, ``(n,)`` metres."""
        step = np.linalg.norm(np.diff(self.pos_enu_m[:, :2], axis=0), axis=1)
        return np.concatenate([[0.0], np.cumsum(step)])


def _sample(
    path: FloatArray, speed_mps: float, period_s: float, name: str, center: FloatArray
) -> CalibrationTrack:
    """Points every ``speed * period`` metres along a dense polyline ``(k, 2)``, headings along it."""
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    keep = np.concatenate([[True], seg > 1e-12])
    path = path[keep]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    step = speed_mps * period_s
    at = np.arange(0.0, s[-1] + 1e-9, step)
    x = np.interp(at, s, path[:, 0])
    y = np.interp(at, s, path[:, 1])
    # heading of the segment each sample lies on
    k = np.clip(np.searchsorted(s, at, side="right") - 1, 0, path.shape[0] - 2)
    d = path[k + 1] - path[k]
    heading = np.arctan2(d[:, 0], d[:, 1])
    pos = np.stack([x + center[0], y + center[1], np.full_like(x, center[2])], axis=-1)
    return CalibrationTrack(pos_enu_m=pos, heading_rad=heading, t_s=np.arange(at.size) * period_s, name=name)


def _check(speed_mps: float, period_s: float, *lengths: float) -> None:
    if not (speed_mps > 0 and period_s > 0 and all(v > 0 for v in lengths)):
        raise ConfigError("speed, ping period and pattern sizes must be positive")


def _arc(center: FloatArray, radius: float, a0: float, a1: float, step: float) -> FloatArray:
    """Points on a circle from polar angle ``a0`` to ``a1`` (math angles, counter-clockwise positive)."""
    n = max(2, int(np.ceil(abs(a1 - a0) * radius / step)) + 1)
    a = np.linspace(a0, a1, n)
    return center + radius * np.stack([np.cos(a), np.sin(a)], axis=-1)


def casius_track(
    radius_m: float,
    speed_mps: float,
    period_s: float,
    *,
    center_enu_m: ArrayLike = (0.0, 0.0, 0.0),
    turn_radius_m: float | None = None,
) -> CalibrationTrack:
    """CASIUS's pattern (module docstring): a clockwise circle, then four crossing lines both ways."""
    turn = radius_m / 8.0 if turn_radius_m is None else turn_radius_m
    _check(speed_mps, period_s, radius_m, turn)
    fine = min(radius_m, turn) / 50.0
    o = np.zeros(2)
    parts = [_arc(o, radius_m, 0.5 * np.pi, 0.5 * np.pi - 2.0 * np.pi, fine)]  # clockwise from north
    pos = np.array([0.0, radius_m])
    for bearing in np.deg2rad([0.0, 45.0, 90.0, 135.0]):
        u = np.array([np.sin(bearing), np.cos(bearing)])  # along the line, east-north
        start, end = -radius_m * u, radius_m * u
        a_now, a_start = np.arctan2(pos[1], pos[0]), np.arctan2(start[1], start[0])
        sweep = (a_now - a_start) % (2.0 * np.pi)  # clockwise along the circle to the line's start
        parts.append(_arc(o, radius_m, a_now, a_now - sweep, fine))
        parts.append(np.linspace(start, end, max(2, int(2 * radius_m / fine))))
        # half turn outside the circle, to starboard: centre a turn radius to starboard of the line's end
        right = np.array([u[1], -u[0]])
        c = end + turn * right
        a0 = np.arctan2(end[1] - c[1], end[0] - c[0])
        parts.append(_arc(c, turn, a0, a0 - np.pi, fine))
        back_start = end + 2.0 * turn * right
        back_end = back_start - 2.0 * radius_m * u
        parts.append(np.linspace(back_start, back_end, max(2, int(2 * radius_m / fine))))
        pos = back_end
    path = np.concatenate(parts)
    return _sample(
        path, speed_mps, period_s, "CASIUS circle + 4 lines both ways", np.asarray(center_enu_m, float)
    )


def box_in_track(
    half_side_m: float, speed_mps: float, period_s: float, *, center_enu_m: ArrayLike = (0.0, 0.0, 0.0)
) -> CalibrationTrack:
    """A box-in: the square of half side ``half_side_m`` around the beacon, clockwise then anticlockwise."""
    _check(speed_mps, period_s, half_side_m)
    h = half_side_m
    corners = np.array([[-h, h], [h, h], [h, -h], [-h, -h], [-h, h]])  # clockwise from the north-west
    path = np.concatenate([corners, corners[::-1][1:]])
    return _sample(path, speed_mps, period_s, "box-in both ways", np.asarray(center_enu_m, float))


def line_track(
    half_length_m: float,
    speed_mps: float,
    period_s: float,
    *,
    heading_rad: float = 0.0,
    offset_m: float = 0.0,
    center_enu_m: ArrayLike = (0.0, 0.0, 0.0),
) -> CalibrationTrack:
    """One straight pass of ``2 half_length_m`` on ``heading_rad``, ``offset_m`` to starboard of the
    beacon."""
    _check(speed_mps, period_s, half_length_m)
    u = np.array([np.sin(heading_rad), np.cos(heading_rad)])
    right = np.array([u[1], -u[0]])
    path = np.stack([-half_length_m * u, half_length_m * u]) + offset_m * right
    return _sample(path, speed_mps, period_s, "single straight line", np.asarray(center_enu_m, float))
