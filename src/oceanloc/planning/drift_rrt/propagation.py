"""Drift propagation for planners (OMPL's ``StatePropagator``: ``propagate(state, control, duration)``).

Drifting is the control "do nothing" applied for a duration: the state moves with the current. The
:class:`DriftPropagator` wraps a current field and an integrator (the thesis' Euler step of 60 s by default,
or RK4) and offers

- :meth:`DriftPropagator.step_xy`: one step on floats or arrays (sequential planners use floats);
- :meth:`DriftPropagator.rollout`: many particles at once for many steps, stopping each where it leaves the
  valid space or the field, recording samples every ``stride`` steps and, per particle, the cheapest way to
  finish from its trajectory (drift into the goal disk, or fly from the closest point to the goal).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.models.currents import CurrentField, Scalar
from oceanloc.models.drift import METHODS, Method, step_function
from oceanloc.planning.drift_rrt.space import DriftSpace


@dataclass(frozen=True, slots=True, kw_only=True)
class Rollout:
    """Trajectories of a batch of drifters, sampled every ``stride`` steps.

    Attributes
    ----------
    samples_m : (S, P, 2) float
        Positions at steps ``sample_steps``; ``NaN`` once a particle has stopped.
    sample_steps : (S,) int
        Step index of each sample (``0, stride, 2 stride, ...``).
    goal_distance_m : (P,) float
        Smallest distance to the goal over every step of the trajectory.
    goal_step : (P,) int
        The step where it occurs (the first step inside the goal disk if the drift reaches it).
    reaches_goal : (P,) bool
        Whether the drift enters the goal disk.
    closest_m : (P, 2) float
        Position at ``goal_step``.
    end_step : (P,) int
        Last valid step.
    """

    samples_m: FloatArray
    sample_steps: IntArray
    goal_distance_m: FloatArray
    goal_step: IntArray
    reaches_goal: BoolArray
    closest_m: FloatArray
    end_step: IntArray

    @property
    def finish_cost_m(self) -> FloatArray:
        """``(P,)`` flight distance to finish from the trajectory: 0 if the drift reaches the goal disk."""
        return np.where(self.reaches_goal, 0.0, self.goal_distance_m)


@dataclass(frozen=True, slots=True, kw_only=True)
class DriftPropagator:
    """A current field and an integrator.

    Attributes
    ----------
    field : CurrentField
        The planning current.
    dt_s : float
        Integration step (60 s in the thesis).
    method : {"euler", "rk4"}
        One-step map: Euler reproduces the thesis; RK4 for continuous fields.
    """

    field: CurrentField
    dt_s: float = 60.0
    method: Method = "euler"

    def __post_init__(self) -> None:
        if not self.dt_s > 0:
            raise ConfigError(f"drift step dt_s must be positive, got {self.dt_s}")
        if self.method not in METHODS:
            raise ConfigError(f"drift integrator must be one of {', '.join(METHODS)}; got '{self.method}'")

    def step_xy(self, x_m: Scalar, y_m: Scalar, time_s: Scalar = 0.0) -> tuple[Scalar, Scalar]:
        """One drift step; ``NaN`` where the current is undefined."""
        return step_function(self.method)(self.field, x_m, y_m, time_s, self.dt_s)

    def propagate(
        self, space: DriftSpace, states_m: ArrayLike, n_steps: int, t0_s: float = 0.0
    ) -> tuple[FloatArray, BoolArray]:
        """Drift ``(P, 2)`` states for ``n_steps`` steps; returns the states and whether each stayed valid.

        A state that meets an obstacle, the bounds or an undefined current stops at its last valid
        position and is reported invalid.
        """
        p = np.array(states_m, dtype=float).reshape(-1, 2)
        ok = space.is_valid(p)
        step = step_function(self.method)
        for k in range(n_steps):
            xn, yn = step(self.field, p[:, 0], p[:, 1], t0_s + k * self.dt_s, self.dt_s)
            good = ok & np.isfinite(xn) & np.isfinite(yn)
            good[good] = space.is_valid_xy(xn[good], yn[good])
            p[good, 0] = xn[good]
            p[good, 1] = yn[good]
            ok = good
        return p, ok

    def drift_polyline(
        self, space: DriftSpace, start_m: ArrayLike, n_steps: int, t0_s: float = 0.0
    ) -> FloatArray:
        """``(n + 1, 2)`` every step of one drift, stopping early where it would become invalid."""
        x, y = (float(v) for v in np.asarray(start_m, dtype=float))
        out = [(x, y)]
        step = step_function(self.method)
        field, dt, valid = self.field, self.dt_s, space.is_valid_xy
        for k in range(n_steps):
            xn, yn = step(field, x, y, t0_s + k * dt, dt)
            xn, yn = float(xn), float(yn)
            if not (math.isfinite(xn) and math.isfinite(yn) and valid(xn, yn)):
                break
            x, y = xn, yn
            out.append((x, y))
        return np.asarray(out)

    def rollout(
        self,
        space: DriftSpace,
        starts_m: ArrayLike,
        n_steps: int,
        *,
        goal_m: ArrayLike,
        goal_tolerance_m: float,
        stride: int = 1,
        t0_s: float | FloatArray = 0.0,
    ) -> Rollout:
        """Drift ``(P, 2)`` particles for up to ``n_steps`` steps, all at once.

        Each step advances only the particles still valid (the batch shrinks as particles stop), so the
        cost is proportional to the total number of valid steps. Particles starting invalid stop at once.
        ``t0_s`` is one start time or one per particle ``(P,)`` (each then drifts on its own clock).
        """
        if stride < 1:
            raise ConfigError(f"rollout stride must be at least 1, got {stride}")
        p0 = np.asarray(starts_m, dtype=float).reshape(-1, 2)
        n = p0.shape[0]
        gx, gy = (float(v) for v in np.asarray(goal_m, dtype=float))
        tol = float(goal_tolerance_m)
        n_samples = n_steps // stride + 1
        samples = np.full((n_samples, n, 2), np.nan)
        active = np.flatnonzero(space.is_valid_xy(p0[:, 0], p0[:, 1]))
        samples[0, active] = p0[active]
        best = np.full(n, np.inf)
        best_step = np.zeros(n, dtype=np.int64)
        closest = np.full((n, 2), np.nan)
        end_step = np.zeros(n, dtype=np.int64)
        # State of the active particles, kept aligned with ``active``; a particle inside the goal disk has
        # best distance -inf so that it never "improves" again.
        ax = p0[active, 0].copy()
        ay = p0[active, 1].copy()
        ab = np.hypot(ax - gx, ay - gy)
        closest[active] = p0[active]
        best[active] = ab
        ab = np.where(ab < tol, -np.inf, ab)
        stepper = _CellStepper.build(self, space) or _GenericStepper(self, space)
        state = stepper.start(ax, ay)
        dt = self.dt_s
        clocks = np.ndim(t0_s) > 0
        at = np.broadcast_to(np.asarray(t0_s, dtype=float), (n,))[active] if clocks else t0_s
        for k in range(1, n_steps + 1):
            if active.size == 0:
                break
            xn, yn, ok, state = stepper.step(ax, ay, state, at + (k - 1) * dt)
            if not ok.all():
                dead = ~ok
                end_step[active[dead]] = k - 1
                active = active[ok]
                xn = xn[ok]
                yn = yn[ok]
                ab = ab[ok]
                state = state[ok] if state is not None else None
                if clocks:
                    at = at[ok]
            ax, ay = xn, yn
            ex = ax - gx
            ey = ay - gy
            d = np.sqrt(ex * ex + ey * ey)
            improve = d < ab
            if improve.any():
                idx = active[improve]
                di = d[improve]
                best_step[idx] = k
                closest[idx, 0] = ax[improve]
                closest[idx, 1] = ay[improve]
                best[idx] = di
                ab[improve] = np.where(di < tol, -np.inf, di)
            if k % stride == 0:
                s = k // stride
                samples[s, active, 0] = ax
                samples[s, active, 1] = ay
        end_step[active] = min(n_steps, k) if n_steps else 0
        reached = best < tol
        sample_steps = np.arange(n_samples) * stride
        return Rollout(
            samples_m=samples,
            sample_steps=sample_steps,
            goal_distance_m=best,
            goal_step=best_step,
            reaches_goal=reached,
            closest_m=closest,
            end_step=end_step,
        )


class _GenericStepper:
    """One drift step of the propagator, then the space's validity check (NaN positions are invalid)."""

    def __init__(self, prop: DriftPropagator, space: DriftSpace) -> None:
        self._step = step_function(prop.method)
        self._field = prop.field
        self._dt = prop.dt_s
        self._valid = space.is_valid_xy

    def start(self, x: FloatArray, y: FloatArray) -> None:
        return None

    def step(
        self, x: FloatArray, y: FloatArray, state: None, t: float
    ) -> tuple[FloatArray, FloatArray, BoolArray, None]:
        xn, yn = self._step(self._field, x, y, t, self._dt)
        return xn, yn, self._valid(xn, yn), None


class _CellStepper:
    """Fast path for the thesis' dynamics: Euler steps on a steady piecewise-constant grid.

    Each particle carries the index of its cell (the grid padded by one cell on every side). A step is
    ``p + dt v(cell)``, with ``dt v`` tabulated per cell, and validity is read from a table classifying
    every cell as free, blocked or mixed; only points in mixed cells (edges of the map, obstacles not
    aligned with the cells) go through the space's exact check. Positions and validity are exactly those
    of the generic path (same arithmetic), at about half the cost per step.
    """

    def __init__(
        self, dx_tab: FloatArray, dy_tab: FloatArray, status: np.ndarray, grid: tuple, space: DriftSpace
    ) -> None:
        self._dx = dx_tab
        self._dy = dy_tab
        self._status = status
        self._x0, self._y0, self._hx, self._hy, self._nx, self._ny = grid
        self._valid = space.is_valid_xy

    @classmethod
    def build(cls, prop: DriftPropagator, space: DriftSpace) -> _CellStepper | None:
        from oceanloc.models.currents import GridCurrent

        f = prop.field
        obs = space.obstacles
        if not (isinstance(f, GridCurrent) and f.interpolation == "cell" and f.u_mps.shape[0] == 1):
            return None
        if prop.method != "euler" or obs.polygons_m or obs.grid is not None or obs.inflation_m != 0.0:
            return None
        gx0, gx1, gy0, gy1 = f.bounds_m
        bx0, bx1, by0, by1 = obs.bounds_m
        if not (gx0 <= bx0 and bx1 <= gx1 and gy0 <= by0 and by1 <= gy1):
            return None
        hx, hy = f.spacing_m
        nx, ny = f.x_m.size, f.y_m.size
        dx_tab = np.full((ny + 2, nx + 2), np.nan)
        dy_tab = np.full((ny + 2, nx + 2), np.nan)
        dx_tab[1:-1, 1:-1] = prop.dt_s * f.u_mps[0]
        dy_tab[1:-1, 1:-1] = prop.dt_s * f.v_mps[0]
        # Cell e (padded) covers [x0 + (e - 1) h, x0 + e h); e = 0 and e = n + 1 lie off the grid.
        ex = gx0 + (np.arange(nx + 2) - 1.0) * hx
        ey = gy0 + (np.arange(ny + 2) - 1.0) * hy
        cx0, cx1 = ex[None, :], ex[None, :] + hx
        cy0, cy1 = ey[:, None], ey[:, None] + hy
        inside = (cx0 >= bx0) & (cx1 <= bx1) & (cy0 >= by0) & (cy1 <= by1)
        outside = (cx1 <= bx0) | (cx0 > bx1) | (cy1 <= by0) | (cy0 > by1)
        status = np.where(inside, 1, np.where(outside, 0, 2)).astype(np.int8)
        for a, b, c, d in obs.rectangles_m:
            covered = (cx0 >= a) & (cx1 <= b) & (cy0 >= c) & (cy1 <= d)
            touches = (cx1 > a) & (cx0 < b) & (cy1 > c) & (cy0 < d)
            status = np.where(covered & (status == 1), 0, status)
            status = np.where(touches & ~covered & (status == 1), 2, status).astype(np.int8)
        return cls(dx_tab.ravel(), dy_tab.ravel(), status.ravel(), (gx0, gy0, hx, hy, nx, ny), space)

    def _cells(self, x: FloatArray, y: FloatArray) -> np.ndarray:
        fx = np.floor((x - self._x0) / self._hx) + 1.0
        fy = np.floor((y - self._y0) / self._hy) + 1.0
        ix = np.minimum(np.maximum(fx, 0.0), self._nx + 1).astype(np.intp)
        iy = np.minimum(np.maximum(fy, 0.0), self._ny + 1).astype(np.intp)
        return iy * (self._nx + 2) + ix

    def start(self, x: FloatArray, y: FloatArray) -> np.ndarray:
        return self._cells(x, y)

    def step(
        self, x: FloatArray, y: FloatArray, cells: np.ndarray, t: float
    ) -> tuple[FloatArray, FloatArray, BoolArray, np.ndarray]:
        xn = x + self._dx[cells]
        yn = y + self._dy[cells]
        new = self._cells(xn, yn)
        st = self._status[new]
        ok = st == 1
        mixed = st == 2
        if mixed.any():
            ok[mixed] = self._valid(xn[mixed], yn[mixed])
        return xn, yn, ok, new
