"""Obstacles and map bounds for drift planning: rectangles, polygons and occupancy grids, with inflation.

An :class:`ObstacleMap` answers two batched questions: is a point free (inside the bounds and outside every
obstacle grown by the inflation margin), and is a straight segment free. Rectangles are half-open
``[x0, x1) x [y0, y1)`` without inflation, which matches the thesis' cell-aligned occupancy grid exactly
(Dillard, Appendix C: an obstacle fills whole 500 m cells); with a margin ``m > 0`` a point is blocked when
its distance to the obstacle is at most ``m`` (the Minkowski sum with a disk, the "safety factor" the thesis
suggests after its lab test, V.D). Polygons use the even-odd rule. An :class:`OccupancyGrid` (for example
the land mask of a gridded current product) is inflated with a Euclidean distance transform.

All tests are vectorized over points and segments; :meth:`ObstacleMap.is_free_xy` also takes Python floats
for sequential planners.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray
from oceanloc.errors import ConfigError


@dataclass(frozen=True, slots=True, kw_only=True)
class OccupancyGrid:
    """Occupied cells on a regular grid.

    Attributes
    ----------
    x0_m, y0_m : float
        South-west corner of cell ``[0, 0]``.
    cell_m : float
        Cell size.
    occupied : (ny, nx) bool
        ``True`` where blocked. Points outside the grid are not blocked by it (map bounds handle those).
    """

    x0_m: float
    y0_m: float
    cell_m: float
    occupied: BoolArray

    def __post_init__(self) -> None:
        occ = np.asarray(self.occupied, dtype=bool)
        if occ.ndim != 2:
            raise ConfigError(f"occupancy grid must be two-dimensional, got shape {occ.shape}")
        if not self.cell_m > 0:
            raise ConfigError(f"occupancy grid cell size must be positive, got {self.cell_m}")
        occ = occ.copy()
        occ.setflags(write=False)
        object.__setattr__(self, "occupied", occ)

    def is_occupied_xy(self, x_m: FloatArray, y_m: FloatArray) -> BoolArray:
        """``True`` where the point falls in an occupied cell."""
        ny, nx = self.occupied.shape
        fx = np.floor((np.asarray(x_m, dtype=float) - self.x0_m) / self.cell_m)
        fy = np.floor((np.asarray(y_m, dtype=float) - self.y0_m) / self.cell_m)
        inside = (fx >= 0) & (fx < nx) & (fy >= 0) & (fy < ny)
        ix = np.where(inside, fx, 0).astype(np.intp)
        iy = np.where(inside, fy, 0).astype(np.intp)
        return inside & self.occupied[iy, ix]

    def inflated(self, margin_m: float) -> OccupancyGrid:
        """Cells whose centre lies within ``margin_m`` of an occupied cell's edge become occupied too."""
        if margin_m <= 0 or not self.occupied.any():
            return self
        # Distance from each free cell centre to the nearest occupied cell centre, minus half a cell.
        from scipy import ndimage

        dist = ndimage.distance_transform_edt(~self.occupied) * self.cell_m - 0.5 * self.cell_m
        return OccupancyGrid(
            x0_m=self.x0_m, y0_m=self.y0_m, cell_m=self.cell_m, occupied=self.occupied | (dist <= margin_m)
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class ObstacleMap:
    """Map bounds and obstacles.

    Attributes
    ----------
    bounds_m : (4,) float
        ``(x_min, x_max, y_min, y_max)``, closed.
    rectangles_m : (R, 4) float
        ``(x0, x1, y0, y1)`` per rectangle.
    polygons_m : tuple of (V, 2) float
        Simple polygons (vertex lists, not closed).
    grid : OccupancyGrid or None
        Additional occupied cells (land masks).
    inflation_m : float
        Safety margin added around every obstacle (not around the bounds).
    """

    bounds_m: tuple[float, float, float, float]
    rectangles_m: FloatArray = field(default_factory=lambda: np.zeros((0, 4)))
    polygons_m: tuple[FloatArray, ...] = ()
    grid: OccupancyGrid | None = None
    inflation_m: float = 0.0
    _rect_list: tuple = field(init=False, repr=False, compare=False)
    _grid_eff: OccupancyGrid | None = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        b = tuple(float(v) for v in self.bounds_m)
        if len(b) != 4 or not (b[0] < b[1] and b[2] < b[3]) or not np.all(np.isfinite(b)):
            raise ConfigError(
                f"map bounds must be (x_min, x_max, y_min, y_max) with min < max, got {self.bounds_m}"
            )
        rects = np.asarray(self.rectangles_m, dtype=float).reshape(-1, 4)
        if np.any(rects[:, 1] <= rects[:, 0]) or np.any(rects[:, 3] <= rects[:, 2]):
            raise ConfigError("every rectangle needs x0 < x1 and y0 < y1")
        polys = tuple(np.asarray(p, dtype=float) for p in self.polygons_m)
        for i, p in enumerate(polys):
            if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 3:
                raise ConfigError(f"polygon {i} needs at least three (x, y) vertices, got shape {p.shape}")
        if not (self.inflation_m >= 0 and np.isfinite(self.inflation_m)):
            raise ConfigError(f"inflation margin must be a non-negative number, got {self.inflation_m}")
        rects.setflags(write=False)
        object.__setattr__(self, "bounds_m", b)
        object.__setattr__(self, "rectangles_m", rects)
        object.__setattr__(self, "polygons_m", polys)
        grid = self.grid.inflated(self.inflation_m) if self.grid is not None else None
        object.__setattr__(self, "_grid_eff", grid)
        object.__setattr__(self, "_rect_list", tuple(tuple(r) for r in rects.tolist()))

    @property
    def has_obstacles(self) -> bool:
        grid = self._grid_eff
        return bool(len(self._rect_list) or self.polygons_m or (grid is not None and grid.occupied.any()))

    def with_inflation(self, margin_m: float) -> ObstacleMap:
        """The same obstacles grown by ``margin_m``."""
        return ObstacleMap(
            bounds_m=self.bounds_m,
            rectangles_m=self.rectangles_m,
            polygons_m=self.polygons_m,
            grid=self.grid,
            inflation_m=margin_m,
        )

    def in_bounds_xy(self, x_m: FloatArray, y_m: FloatArray) -> BoolArray:
        x0, x1, y0, y1 = self.bounds_m
        return (x_m >= x0) & (x_m <= x1) & (y_m >= y0) & (y_m <= y1)

    def is_free(self, points_m: ArrayLike) -> BoolArray:
        """``(...)`` bool: inside the bounds and clear of every (inflated) obstacle; ``points_m (..., 2)``."""
        p = np.asarray(points_m, dtype=float)
        return self.is_free_xy(p[..., 0], p[..., 1])

    def is_free_xy(self, x_m, y_m):
        """Like :meth:`is_free` on separate coordinates; Python floats give a Python bool (fast path)."""
        if isinstance(x_m, float | int) and isinstance(y_m, float | int):
            return self._is_free_scalar(float(x_m), float(y_m))
        x = np.asarray(x_m, dtype=float)
        y = np.asarray(y_m, dtype=float)
        free = self.in_bounds_xy(x, y)
        m = self.inflation_m
        m2 = m * m
        # One rectangle at a time on flat arrays: cheaper than broadcasting (P, R) and reducing.
        for a, b, c, d in self._rect_list:
            if m == 0.0:
                hit = (x >= a) & (x < b) & (y >= c) & (y < d)
            else:
                dx = np.maximum(np.maximum(a - x, x - b), 0.0)
                dy = np.maximum(np.maximum(c - y, y - d), 0.0)
                hit = dx * dx + dy * dy <= m2
            free &= ~hit
        for poly in self.polygons_m:
            blocked = _inside_polygon(x, y, poly)
            if m > 0.0:
                blocked |= _distance_to_polyline(x, y, poly, closed=True) <= m
            free &= ~blocked
        if self._grid_eff is not None:
            free &= ~self._grid_eff.is_occupied_xy(x, y)
        return free

    def _is_free_scalar(self, x: float, y: float) -> bool:
        x0, x1, y0, y1 = self.bounds_m
        if not (x0 <= x <= x1 and y0 <= y <= y1):
            return False
        m = self.inflation_m
        for a, b, c, d in self._rect_list:
            if m == 0.0:
                if a <= x < b and c <= y < d:
                    return False
            else:
                dx = max(a - x, x - b, 0.0)
                dy = max(c - y, y - d, 0.0)
                if dx * dx + dy * dy <= m * m:
                    return False
        if self.polygons_m or self.grid is not None:
            return bool(self.is_free_xy(np.array([x]), np.array([y]))[0])
        return True

    def segment_free(self, a_m: ArrayLike, b_m: ArrayLike) -> BoolArray:
        """``(...)`` bool: the straight segments ``a -> b`` stay in bounds and clear of every obstacle.

        Exact for rectangles and polygons (with inflation: the distance from the segment to the obstacle
        exceeds the margin); occupancy grids are checked at points spaced a quarter cell apart. Obstacles
        count as closed sets here, so a segment that only grazes an edge is blocked (conservative), while
        :meth:`is_free` keeps the thesis' half-open cells for single points.

        Parameters
        ----------
        a_m, b_m : (..., 2) float
            Segment ends.
        """
        a = np.asarray(a_m, dtype=float)
        b = np.asarray(b_m, dtype=float)
        a, b = np.broadcast_arrays(a, b)
        free = self.is_free(a) & self.is_free(b)
        m = self.inflation_m
        if len(self._rect_list):
            for x0, x1, y0, y1 in self._rect_list:
                hit = _segment_hits_box(a, b, x0 - m, x1 + m, y0, y1) | _segment_hits_box(
                    a, b, x0, x1, y0 - m, y1 + m
                )
                if m > 0.0:
                    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
                    for c in corners:
                        hit |= _point_segment_distance(c[0], c[1], a, b) <= m
                free &= ~hit
        for poly in self.polygons_m:
            hit = _inside_polygon(a[..., 0], a[..., 1], poly) | _inside_polygon(b[..., 0], b[..., 1], poly)
            q0 = poly
            q1 = np.roll(poly, -1, axis=0)
            dist = _segment_segment_distance(a[..., None, :], b[..., None, :], q0, q1).min(axis=-1)
            hit |= dist <= m if m > 0.0 else dist <= 0.0
            free &= ~hit
        grid = self._grid_eff
        if grid is not None:
            length = np.linalg.norm(b - a, axis=-1)
            n = max(int(np.ceil(np.max(length, initial=0.0) / (0.25 * grid.cell_m))), 1)
            s = np.linspace(0.0, 1.0, n + 1)
            pts = a[..., None, :] + (b - a)[..., None, :] * s[:, None]
            free &= ~grid.is_occupied_xy(pts[..., 0], pts[..., 1]).any(axis=-1)
        return free

    def rasterize(self, cell_m: float) -> OccupancyGrid:
        """An occupancy grid over the bounds: a cell is occupied when its centre is not free."""
        x0, x1, y0, y1 = self.bounds_m
        nx = max(int(np.ceil((x1 - x0) / cell_m)), 1)
        ny = max(int(np.ceil((y1 - y0) / cell_m)), 1)
        cx = x0 + (np.arange(nx) + 0.5) * cell_m
        cy = y0 + (np.arange(ny) + 0.5) * cell_m
        gx, gy = np.meshgrid(cx, cy)
        occ = ~self.is_free_xy(np.minimum(gx, x1), np.minimum(gy, y1))
        return OccupancyGrid(x0_m=x0, y0_m=y0, cell_m=cell_m, occupied=occ)


def _inside_polygon(x: FloatArray, y: FloatArray, poly: FloatArray) -> BoolArray:
    """Even-odd rule, vectorized over points and edges."""
    x = np.asarray(x, dtype=float)[..., None]
    y = np.asarray(y, dtype=float)[..., None]
    px, py = poly[:, 0], poly[:, 1]
    qx, qy = np.roll(px, -1), np.roll(py, -1)
    crosses = (py > y) != (qy > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = px + (y - py) * (qx - px) / (qy - py)
    return np.sum(crosses & (x < x_at), axis=-1) % 2 == 1


def _point_segment_distance(px: FloatArray, py: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distance from points ``(px, py)`` to segments ``a -> b`` (broadcast)."""
    ab = b - a
    denom = np.sum(ab * ab, axis=-1)
    t = np.where(
        denom > 0,
        ((px - a[..., 0]) * ab[..., 0] + (py - a[..., 1]) * ab[..., 1]) / np.where(denom > 0, denom, 1.0),
        0.0,
    )
    t = np.clip(t, 0.0, 1.0)
    return np.hypot(a[..., 0] + t * ab[..., 0] - px, a[..., 1] + t * ab[..., 1] - py)


def _distance_to_polyline(x: FloatArray, y: FloatArray, poly: FloatArray, *, closed: bool) -> FloatArray:
    q0 = poly if closed else poly[:-1]
    q1 = np.roll(poly, -1, axis=0) if closed else poly[1:]
    d = _point_segment_distance(np.asarray(x)[..., None], np.asarray(y)[..., None], q0, q1)
    return d.min(axis=-1)


def _cross(o: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (
        b[..., 0] - o[..., 0]
    )


def _segment_segment_distance(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> FloatArray:
    """Distance between segments ``a-b`` and ``c-d`` (broadcast over leading axes); 0 when they cross."""
    d1 = _cross(c, d, a)
    d2 = _cross(c, d, b)
    d3 = _cross(a, b, c)
    d4 = _cross(a, b, d)
    proper = (d1 * d2 < 0) & (d3 * d4 < 0)
    dist = np.minimum.reduce(
        [
            _point_segment_distance(a[..., 0], a[..., 1], c, d),
            _point_segment_distance(b[..., 0], b[..., 1], c, d),
            _point_segment_distance(c[..., 0], c[..., 1], a, b),
            _point_segment_distance(d[..., 0], d[..., 1], a, b),
        ]
    )
    return np.where(proper, 0.0, dist)


def _segment_hits_box(a: FloatArray, b: FloatArray, x0: float, x1: float, y0: float, y1: float) -> BoolArray:
    """Liang-Barsky: does segment ``a -> b`` meet the open box ``(x0, x1) x (y0, y1)``?"""
    d = b - a
    t0 = np.zeros(a.shape[:-1])
    t1 = np.ones(a.shape[:-1])
    ok = np.ones(a.shape[:-1], dtype=bool)
    for axis, lo, hi in ((0, x0, x1), (1, y0, y1)):
        p = d[..., axis]
        q_lo = a[..., axis] - lo
        q_hi = hi - a[..., axis]
        parallel = p == 0
        ok &= ~(parallel & ((q_lo <= 0) | (q_hi <= 0)))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            ta = np.where(parallel, -np.inf, (lo - a[..., axis]) / np.where(parallel, 1.0, p))
            tb = np.where(parallel, np.inf, (hi - a[..., axis]) / np.where(parallel, 1.0, p))
        t_enter = np.minimum(ta, tb)
        t_exit = np.maximum(ta, tb)
        t0 = np.maximum(t0, t_enter)
        t1 = np.minimum(t1, t_exit)
    return ok & (t0 < t1)
