"""The drift planner's value function over (node, time): dynamic programming backwards from the goal.

In a current that changes in time, the cheapest way on from a point depends on *when* the vehicle is
there. The value ``V(p, t)`` (least objective to reach the goal from ``p`` at time ``t``) satisfies

    V(p, t) = min( price * Delta + V(phi(p, t, Delta), t + Delta)                 drift for Delta
                   min over q:  c(p -> q, t) + V(q, t + tau(p -> q, t)) )          a powered leg to q

with ``V = 0`` in the goal disk and, at the end of the planning window (the deadline, or the start plus the
horizon), the cost of going straight to the goal (or ``inf`` with a deadline). :class:`TimeLattice` solves
it on lattice nodes ``h`` apart and time slices ``t_k = t0 + k Delta``, backwards from the last slice
(a semi-Lagrangian scheme, the standard discretization of this Hamilton-Jacobi-Bellman equation):

1. every free node is drifted from every slice time for one slice with the problem's integrator, all at
   once (``K x N`` particles, each with its own clock); where the drift enters the goal disk, or leaves the
   valid space, is recorded;
2. for ``k = K - 1 ... 0``: the drift term interpolates ``V(., t_(k+1))`` bilinearly at the drifted
   positions; the powered term is, in the air, an exact minimum over every pair of nodes (straight flights,
   the landing value taken at the slice nearest to the landing time, chains of flights relaxed within the
   slice when legs are limited or obstacles are no-fly zones), and in the water a minimum over a stencil of
   straight moves whose time comes from the current at the move's middle (``V`` at the landing time
   interpolated linearly between slices).

Values are in metres of powered travel at the vehicle's speed (the flight distance in the air): a flight
costs its length, a second of the plan ``time_rate / unit_cost`` metres. :meth:`TimeLattice.value_at` reads
``V`` at any point and time (bilinear in space, linear in time). The plan is read out and refined by
:mod:`oceanloc.planning.drift_rrt.time_plan`. Private to the drift planners.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError
from oceanloc.models.drift import step_function
from oceanloc.models.powered import water_ground_speed
from oceanloc.planning.drift_rrt.problem import DriftProblem

GIB = 2.0**30
VALLEY_WEIGHT = 0.5


@dataclass(frozen=True, slots=True, kw_only=True)
class TimeLatticeOptions:
    """Resolution and effort of the planner in time.

    Attributes
    ----------
    spacing_m : float
        Lattice spacing ``h`` (enlarged until the lattice has at most ``max_nodes`` nodes).
    slice_s : float
        Time between value slices ``Delta`` (shortened so that a whole number of slices spans the window).
    substep_s : float or None
        Integration step of the guide's drifts with Runge-Kutta, and spacing of their take-off candidates
        (rounded so that a whole number fits a slice); ``None`` or an Euler problem: the problem's step.
    window_slices : int
        Slices every node is drifted exactly from every slice time: drifts into the goal and take-offs
        within the window are exact; beyond it the value is interpolated.
    stencil_radius : int
        Water moves ``(a, b)`` with ``a^2 + b^2 <= r^2`` and ``gcd(a, b) = 1``.
    max_nodes : int
        Largest lattice.
    stride : int
        Drift steps between take-off candidates when the plan is read out.
    refine_rounds : int
        Rounds of local refinement of the landing points (each a quarter of the previous extent).
    cloud_half_width : int
        A refinement cloud has ``(2 w + 1)^2`` candidates.
    random_offset : bool
        Shift the lattice by a random fraction of ``h`` drawn from the planner's generator.
    max_flights : int
        Safety cap on the legs of a plan.
    max_relax : int
        Relaxations of chained flights within a slice (limited legs, no-fly obstacles).
    max_memory_gib : float
        Largest estimated working memory (GiB); a larger problem is a ConfigError saying what to change.
    """

    spacing_m: float = 500.0
    slice_s: float = 1800.0
    substep_s: float | None = 900.0
    window_slices: int = 8
    stencil_radius: int = 4
    max_nodes: int = 2500
    stride: int = 2
    refine_rounds: int = 4
    cloud_half_width: int = 4
    random_offset: bool = False
    max_flights: int = 64
    max_relax: int = 4
    max_memory_gib: float = 4.0

    def __post_init__(self) -> None:
        if not (self.spacing_m > 0 and self.slice_s > 0):
            raise ConfigError(f"spacing_m and slice_s must be positive, got {self.spacing_m}, {self.slice_s}")
        if self.substep_s is not None and not self.substep_s > 0:
            raise ConfigError(f"substep_s must be positive or None, got {self.substep_s}")
        if min(self.stencil_radius, self.stride, self.cloud_half_width, self.max_flights, self.max_relax) < 1:
            raise ConfigError(
                "stencil_radius, stride, cloud_half_width, max_flights and max_relax must be >= 1"
            )
        if self.max_nodes < 4 or self.refine_rounds < 0 or not self.max_memory_gib > 0:
            raise ConfigError("max_nodes >= 4, refine_rounds >= 0 and max_memory_gib > 0 are required")


@dataclass(frozen=True, slots=True)
class WindowDrift:
    """Drifts of every free node from every slice time over a window of slices, sampled every substep."""

    points_m: FloatArray  # (K, Nf, M + 1, 2) positions at every substep; NaN once stopped
    goal_s: FloatArray  # (K, Nf) seconds after the slice time when the drift entered the goal disk, else inf
    near_m: FloatArray  # (K, Nf) closest approach to the goal within the window
    near_s: FloatArray  # (K, Nf) seconds after the slice time of the closest approach
    substep_s: float


def unit_cost(problem: DriftProblem) -> float:
    """Objective per metre of powered travel at the vehicle's speed (the value lattice's unit)."""
    rate = problem.powered_rate + problem.time_rate
    if not rate > 0:
        raise ConfigError("the objective must put a price on powered travel or on time")
    return rate / problem.energy.flight_speed_mps


def price_m_per_s(problem: DriftProblem) -> float:
    """The price of a second of the plan in the lattice's unit (metres of powered travel)."""
    return problem.time_rate / unit_cost(problem)


def lattice_spacing(problem: DriftProblem, opts: TimeLatticeOptions) -> float:
    """``opts.spacing_m``, enlarged until the lattice over the map has at most ``opts.max_nodes`` nodes."""
    x0, x1, y0, y1 = problem.space.bounds_m
    h = opts.spacing_m
    for _ in range(64):
        if (math.floor((x1 - x0) / h) + 1) * (math.floor((y1 - y0) / h) + 1) <= opts.max_nodes:
            return h
        h *= 1.1
    return h


def water_moves(radius: int) -> list[tuple[int, int]]:
    """Stencil moves ``(a, b)``, ``0 < a^2 + b^2 <= r^2``, ``gcd(|a|, |b|) = 1``."""
    return [
        (a, b)
        for a in range(-radius, radius + 1)
        for b in range(-radius, radius + 1)
        if (a, b) != (0, 0) and math.gcd(abs(a), abs(b)) == 1 and a * a + b * b <= radius * radius
    ]


class TimeLattice:
    """Lattice nodes, time slices and the value ``V[k, node]`` (see the module docstring)."""

    def __init__(self, problem: DriftProblem, opts: TimeLatticeOptions, offset: FloatArray) -> None:
        """``offset``: shift of the lattice as a fraction of its spacing, ``(2,)`` in ``[0, 1)``."""
        self.problem = problem
        self.opts = opts
        x0, x1, y0, y1 = problem.space.bounds_m
        h = lattice_spacing(problem, opts)
        self.h = h
        self.xs = np.arange(x0 + offset[0] * h, x1 + 1e-9, h)
        self.ys = np.arange(y0 + offset[1] * h, y1 + 1e-9, h)
        gx, gy = np.meshgrid(self.xs, self.ys)
        self.nodes = np.column_stack([gx.ravel(), gy.ravel()])
        self.n_nodes = self.nodes.shape[0]
        self.free = problem.space.is_valid(self.nodes)
        self.free_idx = np.flatnonzero(self.free)
        self.goal = problem.goal_m
        self.tol = problem.goal_tolerance_m
        self.leg = math.inf if problem.max_leg_m is None else float(problem.max_leg_m)
        self.speed = problem.energy.flight_speed_mps
        self.unit = unit_cost(problem)
        self.price = price_m_per_s(problem)
        self.t0 = problem.t0_s
        self.t_end = problem.end_s
        span = self.t_end - self.t0
        self.n_slices = max(1, math.ceil(span / opts.slice_s - 1e-9))
        self.delta = span / self.n_slices
        self.times = self.t0 + self.delta * np.arange(self.n_slices + 1)
        self.deadline = problem.deadline_s
        self.values = np.empty((0, self.n_nodes))
        self.goal_dist = np.hypot(self.nodes[:, 0] - self.goal[0], self.nodes[:, 1] - self.goal[1])

    # -- memory ----------------------------------------------------------------------------------------
    def memory_bytes(self) -> float:
        """Estimated working memory: the value stack, the slice drifts, and the flight matrices (air)."""
        n, nf, k = float(self.n_nodes), float(self.free_idx.size), float(self.n_slices)
        per = max(1.0, math.ceil(self.delta / self.guide_step_s() - 1e-9))
        total = 16.0 * (k + 1) * n + (48.0 + 16.0 * per * self.opts.window_slices) * k * nf
        if self.problem.propulsion == "air":
            total += 12.0 * n * (nf + 1)
        else:
            total += 24.0 * len(water_moves(self.opts.stencil_radius)) * n
        return total

    def check_memory(self) -> None:
        total = self.memory_bytes()
        if total > self.opts.max_memory_gib * GIB:
            raise ConfigError(
                f"the planner in time would need about {total / GIB:.3g} GiB (at most "
                f"{self.opts.max_memory_gib:g}): {self.n_nodes} lattice nodes {self.h:.0f} m apart and "
                f"{self.n_slices} time slices; shrink [map] bounds_m or shorten [drift] horizon_h"
            )

    # -- drift -----------------------------------------------------------------------------------------
    def guide_step_s(self) -> float:
        """Integration step of the guide's drifts: ``opts.substep_s`` with Runge-Kutta (never below the
        problem's step), the problem's own step with Euler (a piecewise-constant field needs it)."""
        prop = self.problem.propagator
        if self.opts.substep_s is None or prop.method == "euler":
            return prop.dt_s
        return max(self.opts.substep_s, prop.dt_s)

    def window_drift(self) -> WindowDrift:
        """Drift every free node from every slice time over the window (step 1 of the module docstring).

        Particles are integrated all at once, each on its own clock, with the problem's integrator; a
        particle stops where its drift leaves the valid space (or the window passes the last slice). The
        goal disk counts as entered where a step's segment first comes within the tolerance, so a long
        substep does not jump over it.
        """
        prop, space = self.problem.propagator, self.problem.space
        per = max(1, math.ceil(self.delta / self.guide_step_s() - 1e-9))
        h = self.delta / per
        w = self.opts.window_slices
        k_n, nf = self.n_slices, self.free_idx.size
        m_n = per * w
        start = self.nodes[self.free_idx]
        x = np.tile(start[:, 0], k_n)
        y = np.tile(start[:, 1], k_n)
        k_of = np.repeat(np.arange(k_n), nf)
        t = self.times[k_of].copy()
        limit = np.minimum(w, k_n - k_of) * per  # substeps until the window (or the plan's window) ends
        pts = np.full((x.size, m_n + 1, 2), np.nan)
        pts[:, 0, 0], pts[:, 0, 1] = x, y
        gx, gy, tol = float(self.goal[0]), float(self.goal[1]), self.tol
        near = np.hypot(x - gx, y - gy)
        near_s = np.zeros(x.size)
        goal_s = np.where(near < tol, 0.0, np.inf)
        active = np.flatnonzero(near >= tol)
        step = step_function(prop.method)
        field = prop.field
        for i in range(m_n):
            active = active[limit[active] > i]
            if active.size == 0:
                break
            xa, ya = x[active], y[active]
            xn, yn = step(field, xa, ya, t[active] + i * h, h)
            ok = np.isfinite(xn) & np.isfinite(yn)
            ok[ok] = space.is_valid_xy(xn[ok], yn[ok])
            active, xa, ya, xn, yn = active[ok], xa[ok], ya[ok], xn[ok], yn[ok]
            x[active], y[active] = xn, yn
            pts[active, i + 1, 0], pts[active, i + 1, 1] = xn, yn
            ex, ey = xn - xa, yn - ya
            seg2 = ex * ex + ey * ey
            with np.errstate(invalid="ignore", divide="ignore"):
                u = np.clip(((gx - xa) * ex + (gy - ya) * ey) / seg2, 0.0, 1.0)
            u = np.where(seg2 > 0.0, u, 1.0)
            cx, cy = xa + u * ex - gx, ya + u * ey - gy
            c2 = cx * cx + cy * cy
            closer = c2 < near[active] ** 2
            if closer.any():
                near[active[closer]] = np.sqrt(c2[closer])
                near_s[active[closer]] = (i + u[closer]) * h
            hit = c2 < tol * tol
            if hit.any():
                goal_s[active[hit]] = (i + u[hit]) * h
                active = active[~hit]
        return WindowDrift(
            points_m=pts.reshape(k_n, nf, m_n + 1, 2),
            goal_s=goal_s.reshape(k_n, nf),
            near_m=near.reshape(k_n, nf),
            near_s=near_s.reshape(k_n, nf),
            substep_s=h,
        )

    # -- interpolation ---------------------------------------------------------------------------------
    def interpolate(self, values: FloatArray, z: FloatArray, rows: IntArray | None = None) -> FloatArray:
        """Bilinear interpolation of node ``values (N,)`` at ``z (..., 2)`` (or of ``values (R, N)`` with each
        point read in its row ``rows (...)``); where a corner is ``inf``, the cheapest corner plus the
        distance to it (going there under power)."""
        h = self.h
        fx = np.clip((z[..., 0] - self.xs[0]) / h, 0.0, self.xs.size - 1.0)
        fy = np.clip((z[..., 1] - self.ys[0]) / h, 0.0, self.ys.size - 1.0)
        fx = np.where(np.isfinite(fx), fx, 0.0)
        fy = np.where(np.isfinite(fy), fy, 0.0)
        ix = np.minimum(fx.astype(np.intp), self.xs.size - 2)
        iy = np.minimum(fy.astype(np.intp), self.ys.size - 2)
        tx = fx - ix
        ty = fy - iy
        nx = self.xs.size
        k = iy * nx + ix
        if rows is not None:
            k = k + rows * self.n_nodes
            values = values.ravel()
        a, b, c, d = values[k], values[k + 1], values[k + nx], values[k + nx + 1]
        with np.errstate(invalid="ignore"):
            low = a + (b - a) * tx
            out = low + (c + (d - c) * tx - low) * ty
            lam = VALLEY_WEIGHT
            if lam > 0.0:
                txh, tyh = tx * h, ty * h
                lipschitz = np.maximum(
                    np.maximum(a - np.hypot(txh, tyh), b - np.hypot(h - txh, tyh)),
                    np.maximum(c - np.hypot(txh, h - tyh), d - np.hypot(h - txh, h - tyh)),
                )
                out = out - lam * np.maximum(out - lipschitz, 0.0)
        bad = ~np.isfinite(out)
        if bad.any():
            txb, tyb = tx[bad] * h, ty[bad] * h
            cone = np.minimum(
                np.minimum(a[bad] + np.hypot(txb, tyb), b[bad] + np.hypot(h - txb, tyb)),
                np.minimum(c[bad] + np.hypot(txb, h - tyb), d[bad] + np.hypot(h - txb, h - tyb)),
            )
            out[bad] = cone
        return out

    def slice_weights(self, t_s: FloatArray) -> tuple[IntArray, FloatArray, BoolArray]:
        """Slice index ``k`` and weight ``w`` of ``t`` between slices ``k`` and ``k + 1``, and whether ``t``
        is inside the planning window (times after it are ``inf`` with a deadline, the last slice else)."""
        f = (np.asarray(t_s, dtype=float) - self.t0) / self.delta
        inside = f <= self.n_slices + 1e-9
        f = np.clip(np.where(np.isfinite(f), f, self.n_slices), 0.0, float(self.n_slices))
        k = np.minimum(f.astype(np.intp), self.n_slices - 1)
        return k, f - k, inside

    def node_value(self, node: IntArray, t_s: FloatArray) -> FloatArray:
        """``V`` of lattice nodes at times ``t_s`` (linear between slices), broadcast."""
        k, w, inside = self.slice_weights(t_s)
        v0 = self.values[k, node]
        v1 = self.values[k + 1, node]
        with np.errstate(invalid="ignore"):
            out = np.where(w > 0.0, v0 + (v1 - v0) * w, v0)
        out = np.where(np.isnan(out), np.inf, out)
        if self.deadline is not None:
            out = np.where(inside, out, np.inf)
        return out

    def value_at(self, z: FloatArray, t_s: float) -> FloatArray:
        """``V`` at points ``z (..., 2)`` and one time ``t_s`` (bilinear in space, linear in time)."""
        k, w, inside = self.slice_weights(np.asarray(t_s))
        k, w = int(k), float(w)
        if self.deadline is not None and not bool(inside):
            return np.full(z.shape[:-1], np.inf)
        v0 = self.interpolate(self.values[k], z)
        if w == 0.0:
            return v0
        v1 = self.interpolate(self.values[k + 1], z)
        with np.errstate(invalid="ignore"):
            out = v0 + (v1 - v0) * w
        return np.where(np.isnan(out), np.inf, out)

    # -- the dynamic programme -------------------------------------------------------------------------
    def terminal(self) -> FloatArray:
        """``V`` at the end of the window: 0 in the goal disk; else straight to the goal (no deadline)."""
        out = np.where(self.goal_dist < self.tol, 0.0, np.inf)
        if self.deadline is not None:
            return out
        direct = self.goal_flights(self.t_end)
        return np.minimum(out, direct)

    def goal_flights(self, t_s: float) -> FloatArray:
        """Cost of a powered leg from every node straight to the goal begun at ``t_s`` (``inf`` if
        infeasible or, with a deadline, late)."""
        p = self.problem
        if p.propulsion == "air":
            d = self.goal_dist.copy()
            d[~self._goal_ok] = np.inf
            arrive = t_s + d / self.speed
        else:
            tau, ok = p.leg_times_s(self.nodes, self.goal, t_s)
            d = np.where(ok & self._goal_ok, tau * self.speed, np.inf)
            arrive = t_s + tau
        if self.deadline is not None:
            d = np.where(arrive <= self.deadline + 1e-9, d, np.inf)
        return d

    def solve(self) -> None:
        """Fill ``values[k, node]`` backwards from the last slice."""
        self.check_memory()
        self._prepare_powered()
        drift = self.window_drift()
        k_last = self.n_slices
        values = np.full((k_last + 1, self.n_nodes), np.inf)
        values[k_last] = self.terminal()
        powered = values.copy()
        self.values = values
        self.powered_values = powered
        free = self.free_idx
        h = drift.substep_s
        per = max(1, round(self.delta / h))
        m_n = drift.points_m.shape[2] - 1
        for k in range(k_last - 1, -1, -1):
            pts = drift.points_m[k]  # (Nf, M + 1, 2)
            dk = np.full(free.size, np.inf)
            # Take off at a substep of the drift (the powered value of the slice at or after it).
            m_top = min(m_n, (k_last - k) * per)
            z = pts[:, 1 : m_top + 1]  # (Nf, m, 2)
            ok = np.isfinite(z[..., 0])
            if ok.any():
                steps = np.broadcast_to(np.arange(1, m_top + 1), ok.shape)[ok]
                rows = k + (steps + per - 1) // per
                cand = np.full(ok.shape, np.inf)
                cand[ok] = self.price * steps * h + self.interpolate(powered, z[ok], rows)
                dk = cand.min(axis=1)
            # Drift on past the window: the value where the window ends.
            kw = k + min(self.opts.window_slices, k_last - k)
            z = pts[:, (kw - k) * per]
            ok = np.isfinite(z[:, 0])
            if ok.any():
                dk[ok] = np.minimum(
                    dk[ok], self.price * (kw - k) * self.delta + self.interpolate(values[kw], z[ok])
                )
            # Take off where the drift passes closest to the goal, or drift into the disk.
            dk = np.minimum(dk, self.price * drift.near_s[k] + self._near_cost(drift.near_m[k]))
            reached = np.isfinite(drift.goal_s[k])
            dk[reached] = self.price * drift.goal_s[k][reached]
            d = np.full(self.n_nodes, np.inf)
            d[free] = dk
            values[k], powered[k] = self._powered(k, d)

    def _near_cost(self, dist_m: FloatArray) -> FloatArray:
        """Cost of going straight to the goal from a point ``dist_m`` away (the air's flight; in the water,
        the same distance at the vehicle's speed, the current aside): an estimate for the guide only."""
        if self.deadline is not None:
            return np.full(dist_m.shape, np.inf)
        return dist_m

    # -- powered legs ----------------------------------------------------------------------------------
    def _prepare_powered(self) -> None:
        no_fly = self._prepare_goal()
        if self.problem.propulsion == "air":
            self._prepare_flights(no_fly)
        else:
            self._prepare_moves()

    def _prepare_goal(self) -> bool:
        """Which nodes may go straight to the goal; returns whether obstacles block powered legs."""
        p = self.problem
        space = p.space
        no_fly = space.flights_avoid_obstacles or p.propulsion == "water"
        if no_fly:
            self._goal_ok = space.obstacles.segment_free(
                self.nodes, np.broadcast_to(self.goal, self.nodes.shape)
            )
        else:
            self._goal_ok = np.ones(self.n_nodes, dtype=bool)
        if math.isfinite(self.leg) and p.propulsion == "air":
            self._goal_ok &= self._split_ok(self.nodes, np.broadcast_to(self.goal, self.nodes.shape))
        self._chain = no_fly or math.isfinite(self.leg)
        return no_fly

    def _split_ok(self, a: FloatArray, b: FloatArray) -> BoolArray:
        """Flights longer than a leg are equal legs whose landing points must be free."""
        d = np.hypot(b[..., 0] - a[..., 0], b[..., 1] - a[..., 1])
        n = np.ceil(d / self.leg - 1e-12).astype(np.int64)
        ok = np.ones(d.shape, dtype=bool)
        for i in range(1, int(n.max(initial=1))):
            frac = np.where(n > i, i / np.maximum(n, 1), 0.0)[..., None]
            pts = a + frac * (b - a)
            ok &= (n <= i) | self.problem.space.is_valid(pts)
        return ok

    def _prepare_flights(self, no_fly: bool) -> None:
        nodes = self.nodes.astype(np.float32)
        lands = nodes[self.free_idx]
        ex = nodes[:, None, 0] - lands[None, :, 0]
        ey = nodes[:, None, 1] - lands[None, :, 1]
        dist = np.sqrt(ex * ex + ey * ey)
        if no_fly:
            shape = (self.n_nodes, self.free_idx.size, 2)
            ok = self.problem.space.flight_valid(
                np.broadcast_to(self.nodes[:, None, :], shape),
                np.broadcast_to(self.nodes[self.free_idx][None], shape),
            )
            dist = np.where(ok, dist, np.float32(np.inf))
        if math.isfinite(self.leg):
            # Within one leg, any free landing; beyond, chains through landing nodes (relaxed per slice).
            dist[dist > self.leg] = np.inf
        dist[self.free_idx, np.arange(self.free_idx.size)] = np.inf  # staying is drifting
        # Flights land at the slice nearest to their landing time.
        groups = np.rint(dist * np.float32(1.0 / (self.speed * self.delta)))
        finite = np.isfinite(dist)
        self._flight_groups: list[tuple[int, np.ndarray]] = []
        top = int(np.max(np.where(finite, groups, 0.0), initial=0.0))
        if top == 0:
            self._flight_groups.append((0, dist))
            return
        for j in range(top + 1):
            mask = groups == j
            if mask.any():
                self._flight_groups.append((j, np.where(mask, dist, np.float32(np.inf))))

    def _prepare_moves(self) -> None:
        """Water: stencil moves between lattice nodes that stay in the water."""
        r = self.opts.stencil_radius
        nx, ny = self.xs.size, self.ys.size
        moves = []
        jj, ii = np.divmod(np.arange(self.n_nodes), nx)
        for a, b in water_moves(r):
            ti, tj = ii + a, jj + b
            inside = (ti >= 0) & (ti < nx) & (tj >= 0) & (tj < ny)
            src = np.flatnonzero(inside & self.free)
            dst = tj[src] * nx + ti[src]
            keep = self.free[dst]
            src, dst = src[keep], dst[keep]
            ok = self.problem.space.obstacles.segment_free(self.nodes[src], self.nodes[dst])
            src, dst = src[ok], dst[ok]
            length = self.h * math.hypot(a, b)
            moves.append((src, dst, a * self.h / length, b * self.h / length, length))
        self._moves = moves

    def _powered(self, k: int, drift_values: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``V`` at slice ``k`` from the drift values, and its powered part (the best powered leg now)."""
        if self.problem.propulsion == "air":
            return self._flights(k, drift_values)
        return self._water(k, drift_values)

    def _flights(self, k: int, drift_values: FloatArray) -> tuple[FloatArray, FloatArray]:
        t_k = float(self.times[k])
        env = self.goal_flights(t_k)
        free = self.free_idx
        same = None
        for j, mat in self._flight_groups:
            if j == 0:
                same = mat
                continue
            kk = k + j
            if kk > self.n_slices:
                if self.deadline is not None:
                    continue
                kk = self.n_slices
            land = self.values[kk, free].astype(np.float32)
            env = np.minimum(env, np.min(mat + land[None, :], axis=1).astype(float))
        best = np.minimum(drift_values, env)
        if same is not None:
            for _ in range(self.opts.max_relax if self._chain else 1):
                land = best[free].astype(np.float32)
                new = np.minimum(env, np.min(same + land[None, :], axis=1).astype(float))
                if np.all(new >= env - 1e-9):
                    break
                env = new
                best = np.minimum(drift_values, env)
        return best, env

    def _water(self, k: int, w: FloatArray) -> tuple[FloatArray, FloatArray]:
        t_k = float(self.times[k])
        env = self.goal_flights(t_k)
        best = np.minimum(w, env)
        field = self.problem.propagator.field
        legs = []
        for src, dst, ex, ey, length in self._moves:
            mid = 0.5 * (self.nodes[src] + self.nodes[dst])
            u, v = field.velocity_xy(mid[:, 0], mid[:, 1], t_k + 0.5 * length / self.speed)
            g = water_ground_speed(np.asarray(u), np.asarray(v), ex, ey, self.speed)
            tau = length / g
            ok = np.isfinite(tau)
            src, dst, tau = src[ok], dst[ok], tau[ok]
            kk, frac, inside = self.slice_weights(t_k + tau)
            if self.deadline is not None:
                src, dst, tau, kk, frac = src[inside], dst[inside], tau[inside], kk[inside], frac[inside]
            legs.append((src, dst, tau * self.speed, kk, frac))
        for _ in range(max(self.opts.max_relax, 2 * self.opts.stencil_radius)):
            before = best.copy()
            for src, dst, cost, kk, frac in legs:
                lo = np.where(kk == k, best[dst], self.values[kk, dst])
                hi = np.where(kk + 1 == k, best[dst], self.values[np.minimum(kk + 1, self.n_slices), dst])
                land = np.where(frac > 0.0, lo + (hi - lo) * frac, lo)
                land = np.where(np.isnan(land), np.inf, land)
                # A move costs its time at the vehicle's speed (the unit already prices the time).
                env[src] = np.minimum(env[src], cost + land)
                best[src] = np.minimum(best[src], env[src])
            if np.all(best >= before - 1e-9):
                break
        return best, env
