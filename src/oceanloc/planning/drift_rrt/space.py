"""The state space of drift planning (OMPL's ``StateSpace`` plus ``StateValidityChecker``).

States are horizontal positions in the local metric frame. A state is valid when it lies inside the map
bounds and outside every (inflated) obstacle. Flights go over obstacles unless the space is told that
obstacles are no-fly zones (``flights_avoid_obstacles``): the thesis only checks where a hop lands (its
extend step tests the new node's cell), an island or a buoy does not block a quadrotor in the air, while a
restricted airspace does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray
from oceanloc.models.obstacles import ObstacleMap


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftSpace:
    """Bounds, obstacles, sampling and distance.

    Attributes
    ----------
    obstacles : ObstacleMap
        Bounds and obstacles (with their inflation margin).
    flights_avoid_obstacles : bool
        If true, a flight is valid only if its straight segment clears every obstacle.
    """

    obstacles: ObstacleMap
    flights_avoid_obstacles: bool = False

    @property
    def bounds_m(self) -> tuple[float, float, float, float]:
        return self.obstacles.bounds_m

    @property
    def diagonal_m(self) -> float:
        x0, x1, y0, y1 = self.bounds_m
        return float(np.hypot(x1 - x0, y1 - y0))

    def sample_uniform(self, rng: np.random.Generator, n: int) -> FloatArray:
        """``(n, 2)`` states uniform over the bounds (valid or not, as RRT samples targets)."""
        x0, x1, y0, y1 = self.bounds_m
        u = rng.random((n, 2))
        return np.column_stack([x0 + (x1 - x0) * u[:, 0], y0 + (y1 - y0) * u[:, 1]])

    @staticmethod
    def distance(a_m: ArrayLike, b_m: ArrayLike) -> FloatArray:
        """Euclidean distance, broadcast over ``(..., 2)``."""
        return np.linalg.norm(np.asarray(b_m, dtype=float) - np.asarray(a_m, dtype=float), axis=-1)

    def is_valid(self, points_m: ArrayLike) -> BoolArray:
        """``(...)`` bool for ``(..., 2)`` states."""
        return self.obstacles.is_free(points_m)

    def is_valid_xy(self, x_m, y_m):
        return self.obstacles.is_free_xy(x_m, y_m)

    def flight_valid(self, takeoff_m: ArrayLike, landing_m: ArrayLike) -> BoolArray:
        """``(...)`` bool: the landing point is valid, and the segment too if flights avoid obstacles."""
        if self.flights_avoid_obstacles:
            return self.obstacles.segment_free(takeoff_m, landing_m)
        return self.obstacles.is_free(landing_m)
