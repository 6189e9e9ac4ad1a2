"""Drift/flight paths: a polyline whose edges are either drift steps or straight flights.

A :class:`DriftPath` holds every drift step (so a follower or a figure sees the real track) and marks the
edges flown; its flight energy is that of the distance flown (IV.14). :meth:`DriftPath.merged` joins
consecutive flights into one straight flight, as the thesis does at the end of DR-RRT* ("sequential hop
segments were joined into a single period of flight", V.A.1); a planner that keeps flights to legs of at
most one hop does not merge them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray
from oceanloc.errors import ArgumentError
from oceanloc.models.energy import EnergyBudget


@dataclass(frozen=True, slots=True, kw_only=True)
class PathEnergy:
    """Energy account of a path (IV.14), Wh.

    Attributes
    ----------
    flight_wh : float
        Energy spent flying.
    solar_wh : float
        Mean solar income over the whole duration.
    loads_wh : float
        Base and duty-cycled sensing loads over the whole duration.
    net_wh : float
        ``solar - flight - loads``: positive when the path ends with more energy than it started with.
    duration_s : float
        Drift plus flight time.
    """

    flight_wh: float
    solar_wh: float
    loads_wh: float
    net_wh: float
    duration_s: float

    def to_record(self) -> dict[str, Any]:
        return {
            "flight_wh": self.flight_wh,
            "solar_wh": self.solar_wh,
            "loads_wh": self.loads_wh,
            "net_wh": self.net_wh,
            "duration_s": self.duration_s,
        }


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftPath:
    """A path of drift steps and flights.

    Attributes
    ----------
    points_m : (W, 2) float
        Vertices, metres: every drift step and every take-off and landing point.
    times_s : (W,) float
        Time at each vertex (drift steps take the propagator's step; flights take distance / speed).
    flight : (W - 1,) bool
        Whether edge ``i`` (``points_m[i] -> points_m[i + 1]``) is flown; otherwise it is drifted.
    """

    points_m: FloatArray
    times_s: FloatArray
    flight: BoolArray

    def __post_init__(self) -> None:
        p = np.asarray(self.points_m, dtype=float).reshape(-1, 2)
        t = np.asarray(self.times_s, dtype=float).reshape(-1)
        f = np.asarray(self.flight, dtype=bool).reshape(-1)
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(t))):
            raise ArgumentError("DriftPath: points_m and times_s must be finite")
        if t.shape[0] != p.shape[0] or f.shape[0] != max(p.shape[0] - 1, 0):
            raise ArgumentError(
                f"inconsistent path arrays: {p.shape[0]} points, {t.shape[0]} times, {f.shape[0]} edges"
            )
        for name, value in (("points_m", p), ("times_s", t), ("flight", f)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @classmethod
    def from_segments(
        cls, segments: list[tuple[FloatArray, bool]], *, t0_s: float, dt_s: float, flight_speed_mps: float
    ) -> DriftPath:
        """Assemble from ``(points (n, 2), is_flight)`` segments whose ends and starts coincide.

        A drift segment's points are consecutive drift steps ``dt_s`` apart; a flight segment is
        ``[take-off, landing]``.
        """
        pts: list[FloatArray] = []
        flags: list[bool] = []
        times: list[float] = [t0_s]
        for seg, is_flight in segments:
            seg = np.asarray(seg, dtype=float).reshape(-1, 2)
            if seg.shape[0] < 2:
                continue
            if not pts:
                pts.append(seg[:1])
            body = seg[1:]
            pts.append(body)
            flags.extend([is_flight] * body.shape[0])
            if is_flight:
                hops = np.linalg.norm(np.diff(seg, axis=0), axis=1) / flight_speed_mps
                times.extend((times[-1] + np.cumsum(hops)).tolist())
            else:
                times.extend((times[-1] + dt_s * np.arange(1, body.shape[0] + 1)).tolist())
        if not pts:
            return cls(points_m=np.zeros((0, 2)), times_s=np.zeros(0), flight=np.zeros(0, dtype=bool))
        return cls(
            points_m=np.concatenate(pts), times_s=np.asarray(times), flight=np.asarray(flags, dtype=bool)
        )

    @property
    def n_points(self) -> int:
        return int(self.points_m.shape[0])

    @property
    def start_m(self) -> FloatArray:
        return self.points_m[0]

    @property
    def end_m(self) -> FloatArray:
        return self.points_m[-1]

    @property
    def duration_s(self) -> float:
        return float(self.times_s[-1] - self.times_s[0]) if self.n_points else 0.0

    def edge_lengths_m(self) -> FloatArray:
        """``(W - 1,)`` length of every edge."""
        return np.linalg.norm(np.diff(self.points_m, axis=0), axis=1)

    @property
    def flight_distance_m(self) -> float:
        """Distance flown: the sum of the flight edges (merge first for the thesis' accounting)."""
        return float(np.sum(self.edge_lengths_m()[self.flight])) if self.n_points > 1 else 0.0

    @property
    def flight_time_s(self) -> float:
        """Time spent on flight (powered) edges, seconds."""
        dt = np.diff(self.times_s)
        return float(np.sum(dt[self.flight])) if self.n_points > 1 else 0.0

    @property
    def drift_time_s(self) -> float:
        dt = np.diff(self.times_s)
        return float(np.sum(dt[~self.flight]))

    def hops_m(self) -> FloatArray:
        """``(H, 2, 2)`` take-off and landing point of every flight edge (a hop, or one leg of a chain)."""
        idx = np.flatnonzero(self.flight)
        return (
            np.stack([self.points_m[idx], self.points_m[idx + 1]], axis=1)
            if idx.size
            else np.zeros((0, 2, 2))
        )

    def merged(self) -> DriftPath:
        """The same path with each run of consecutive flights replaced by one straight flight."""
        if self.n_points < 3:
            return self
        inner_flight = self.flight[:-1] & self.flight[1:]
        keep = np.ones(self.n_points, dtype=bool)
        keep[1:-1] = ~inner_flight
        return DriftPath(
            points_m=self.points_m[keep], times_s=self.times_s[keep], flight=self.flight[keep[1:]]
        )

    def energy(self, budget: EnergyBudget, *, through_water: bool = False) -> PathEnergy:
        """Energy account (IV.14): distance flown (or, for powered legs through the water, the power times
        the powered time), solar income and loads over the duration."""
        if through_water:
            flight = budget.flight_power_w * self.flight_time_s / 3600.0
        else:
            flight = float(budget.flight_energy_wh(self.flight_distance_m))
        solar = float(budget.solar_energy_wh(self.duration_s))
        loads = float(budget.load_energy_wh(self.duration_s))
        return PathEnergy(
            flight_wh=flight,
            solar_wh=solar,
            loads_wh=loads,
            net_wh=solar - flight - loads,
            duration_s=self.duration_s,
        )

    def to_record(self) -> dict[str, Any]:
        """Plain JSON-ready vertices: times (s), east/north (m), whether each edge is flown, and totals."""
        return {
            "t_s": self.times_s.tolist(),
            "x_m": self.points_m[:, 0].tolist(),
            "y_m": self.points_m[:, 1].tolist(),
            "flight": self.flight.tolist(),
            "flights": int(self.hops_m().shape[0]),
            "flight_distance_m": self.flight_distance_m,
            "drift_time_s": self.drift_time_s if self.n_points else 0.0,
            "duration_s": self.duration_s,
        }

    def position_at(self, time_s: ArrayLike) -> FloatArray:
        """Planned position at ``time_s`` (linear between vertices); ``(...) -> (..., 2)``."""
        t = np.asarray(time_s, dtype=float)
        return np.stack([np.interp(t, self.times_s, self.points_m[:, i]) for i in range(2)], axis=-1)
