"""Where to measure next: D-optimal measurement-site planners and random baselines.

All planners share one shape (OMPL's lesson: a problem, a planner, ``plan(...) -> SitePlanResult``) and
are batched: ``B`` independent planning problems (Monte Carlo runs) are solved in one call.

* :class:`LookaheadPlanner` - multi-step look-ahead over yaw rates (Garcia et al. 2019, eqs. 28-40):
  choose ``omega_1..omega_k`` in ``[-w_max, w_max]^k`` to maximize the information gain of the ``k`` sites
  they lead to through the unicycle model (eq. 1), linearized about the current estimates, summed over all
  transponders; receding horizon: only ``omega_1`` is applied.
* :class:`GreedyPlanner` - single step within a reach (PLANS 2018 eqs. 18-29, thesis Section 5.2):
  maximize ``sum_m log(1 + alpha_m(x))`` over surface points ``x`` within ``d_max`` of the vehicle.
* :class:`RandomYawPlanner` - a yaw rate uniform in ``[-w_max, w_max]`` (the journal's "k = 0").
* :class:`RandomDiskPlanner` - a point uniform in the disk of radius ``d_max`` (the thesis' baseline).

The optimizing planners find the global optimum of their planning problem (see
:mod:`oceanloc.planning.box_search`); the objective reported is the gain in nats,
``sum_m log det Y_{N+k}^m - log det Y_N^m``.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from oceanloc import _validate
from oceanloc._random import BatchRng, uniform
from oceanloc._typing import FloatArray, IntArray
from oceanloc.errors import ArgumentError, ConfigError
from oceanloc.models.vehicles import unicycle_rollout
from oceanloc.planning.box_search import BoxSearchOptions, maximize_in_box
from oceanloc.planning.information import information_gain, log_det_identity_plus_gram, scaled_cholesky
from oceanloc.planning.status import PlanStatus


@dataclass(frozen=True, slots=True, kw_only=True)
class PlanningState:
    """What a measurement-site planner knows at epoch ``N``, for ``B`` problems.

    Attributes
    ----------
    pos_enu_m : (B, 3) float
        Vehicle positions, metres.
    yaw_rad : (B,) float
        Vehicle headings, radians counter-clockwise from east.
    estimates_m : (B, M, 3) float
        Current transponder estimates, metres.
    covariances_m2 : (B, M, 3, 3) float
        Their covariances (inverse information ``Y_N^m``, prior included), square metres.
    """

    pos_enu_m: FloatArray
    yaw_rad: FloatArray
    estimates_m: FloatArray
    covariances_m2: FloatArray

    def __post_init__(self) -> None:
        big = _validate.MAX_LENGTH_M
        pos = _validate.float_array("pos_enu_m", self.pos_enu_m, shape=(None, 3), max_abs=big, unit="m")
        b = pos.shape[0]
        _validate.float_array("yaw_rad", self.yaw_rad, shape=(b,), max_abs=1e6, unit="rad")
        est = _validate.float_array(
            "estimates_m", self.estimates_m, shape=(b, None, 3), max_abs=big, unit="m"
        )
        cov = _validate.float_array("covariances_m2", self.covariances_m2, shape=(b, est.shape[1], 3, 3))
        if np.any(np.abs(cov) > _validate.MAX_VARIANCE):
            raise ArgumentError(
                f"covariances_m2: beyond the allowed magnitude {_validate.MAX_VARIANCE:g} m^2"
            )

    @property
    def batch(self) -> int:
        return int(self.pos_enu_m.shape[0])


@dataclass(frozen=True, slots=True, kw_only=True)
class SitePlanResult:
    """A batch of plans.

    Attributes
    ----------
    next_pos_enu_m : (B, 3) float
        Where the vehicle measures next (epoch ``N + 1``), metres.
    next_yaw_rad : (B,) float
        Heading on arrival, radians.
    waypoints_enu_m : (B, k, 3) float
        All planned sites ``N+1 .. N+k`` (``k = 1`` for single-step planners), metres.
    yaw_rates_rad_s : (B, k) float or None
        Planned yaw-rate sequence (yaw-rate planners); only the first is applied (receding horizon).
    objective : (B,) float
        Information gain of the planned sites, ``sum_m log det Y_{N+k}^m - log det Y_N^m``, nats.
    solve_time_s : float
        Wall time of the whole batched call, seconds.
    status : PlanStatus
    """

    next_pos_enu_m: FloatArray
    next_yaw_rad: FloatArray
    waypoints_enu_m: FloatArray
    yaw_rates_rad_s: FloatArray | None
    objective: FloatArray
    solve_time_s: float
    status: PlanStatus = PlanStatus.EXACT


class MeasurementSitePlanner(Protocol):
    """Anything with ``plan(state, rng) -> SitePlanResult``."""

    def plan(self, state: PlanningState, rng: BatchRng | None = None) -> SitePlanResult: ...


@dataclass(frozen=True, slots=True, kw_only=True)
class LookaheadPlanner:
    """Multi-step look-ahead D-optimal planner over yaw-rate sequences (journal eqs. 28-40).

    Attributes
    ----------
    horizon : int
        Look-ahead steps ``k``.
    max_yaw_rate_rad_s : float
        ``w_max``; each yaw rate lies in ``[-w_max, w_max]``.
    speed_mps : float
        Forward speed (body velocity ``[speed, 0, 0]``).
    period_s : float
        Sampling period ``T``.
    sigma_range_m : float
        Range noise standard deviation.
    search : BoxSearchOptions
        Global search settings; the defaults reach the exhaustive-search optimum on the papers' problems.
    """

    horizon: int
    max_yaw_rate_rad_s: float
    speed_mps: float
    period_s: float
    sigma_range_m: float
    search: BoxSearchOptions = field(default_factory=BoxSearchOptions)

    def __post_init__(self) -> None:
        if self.horizon < 1:
            raise ConfigError(f"horizon must be at least 1, got {self.horizon}")
        for name in ("max_yaw_rate_rad_s", "speed_mps", "period_s", "sigma_range_m"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"{name} must be positive, got {getattr(self, name)}")

    def bounds(self) -> tuple[FloatArray, FloatArray]:
        """Bounds of the decision box, as ``(lower (k,), upper (k,))``."""
        bound = np.full(self.horizon, self.max_yaw_rate_rad_s)
        return -bound, bound

    @property
    def wraps(self) -> bool:
        """Whether one step can turn through a whole circle (``w_max T >= pi``)."""
        return self.max_yaw_rate_rad_s * self.period_s >= np.pi

    def search_box(self) -> tuple[FloatArray, FloatArray, bool]:
        """The box the search runs over, ``(lower (k,), upper (k,), periodic)``.

        The objective depends on the yaw rates only through the headings ``psi_j = psi_0 + T sum omega_i``
        (eq. 1), so it is ``2 pi / T`` periodic in every ``omega_i``. Where ``w_max T >= pi`` the decision
        box holds at least one whole period and the search runs over ``[-pi/T, pi/T)`` as a periodic box:
        every optimum has an equivalent there, and every point of it is feasible.
        """
        if not self.wraps:
            lower, upper = self.bounds()
            return lower, upper, False
        bound = np.full(self.horizon, np.pi / self.period_s)
        return -bound, bound, True

    def search_options(self) -> BoxSearchOptions:
        """``search`` with the grid grown to the decision range (:func:`lookahead_grid_points`)."""
        points = lookahead_grid_points(self.max_yaw_rate_rad_s * self.period_s, self.search.grid_points)
        if points == self.search.grid_points:
            return self.search
        return dataclasses.replace(self.search, grid_points=points)

    def gain(self, state: PlanningState, yaw_rates_rad_s: FloatArray) -> FloatArray:
        """Information gain of yaw-rate sequences ``(B, C, k)`` -> ``(B, C)``."""
        return _YawRateObjective(state, self)(yaw_rates_rad_s, np.arange(state.batch))

    def plan(self, state: PlanningState, rng: BatchRng | None = None) -> SitePlanResult:
        """The D-optimal yaw-rate sequence for each problem (``rng`` is not used)."""
        start = time.perf_counter()
        lower, upper, periodic = self.search_box()
        best = maximize_in_box(
            _YawRateObjective(state, self),
            lower,
            upper,
            state.batch,
            periodic=np.full(self.horizon, periodic),
            options=self.search_options(),
        )
        poses = unicycle_rollout(state.pos_enu_m, state.yaw_rad, best.x, self.speed_mps, self.period_s)
        return SitePlanResult(
            next_pos_enu_m=poses.pos_enu_m[:, 0],
            next_yaw_rad=poses.yaw_rad[:, 0],
            waypoints_enu_m=poses.pos_enu_m,
            yaw_rates_rad_s=best.x,
            objective=best.value,
            solve_time_s=time.perf_counter() - start,
        )


MAX_GRID_HEADING_SPACING_RAD = 12.0 * np.pi / 180.0
"""Widest heading-change spacing of the look-ahead grid, radians (:func:`lookahead_grid_points`)."""


def lookahead_grid_points(max_heading_change_rad: float, minimum: int) -> int:
    """Grid points per yaw-rate axis of the look-ahead's grid stage, for a decision range of heading
    changes ``[-w_max T, w_max T]`` (``max_heading_change_rad = w_max T``).

    The rule: neighbouring grid points differ by at most ``MAX_GRID_HEADING_SPACING_RAD`` (12 degrees)
    of heading change, whatever the width of the range. Why a bound on the spacing and not a count: the
    objective's basins have a width in heading change set by the geometry (sites on circles of radius
    ``v T`` about the previous site, lines of sight to the transponders), not by ``w_max``, so a grid
    that resolves them on one range resolves them on any range only if its spacing is the same. The
    bound is the spacing at which the search was validated against exhaustive search (``w_max T`` =
    30 degrees, 9 points: 11.7 degrees at the centre of the sine grid, 1e-6 relative on every benchmark
    problem); the fixed 9 points spaced 70 degrees at ``w_max T`` = 180 degrees, and missed.

    * ``w_max T < pi``: the grid is uniform in ``u`` with ``x = w_max T sin(u)``; its widest spacing,
      at the centre, is ``w_max T pi / (n - 1)`` at most, so ``n = ceil(pi w_max T / spacing) + 1``.
    * ``w_max T >= pi``: the search is over one period (:meth:`LookaheadPlanner.search_box`), a
      uniform periodic grid of ``n = ceil(2 pi / spacing)`` points (30), whatever ``w_max T``.

    Never fewer than ``minimum`` (the options' ``grid_points``), so the default scenario's grid (9
    points at 30 degrees) and its latency are unchanged.
    """
    if max_heading_change_rad >= np.pi:
        points = int(np.ceil(2.0 * np.pi / MAX_GRID_HEADING_SPACING_RAD - 1e-9))
    else:
        points = int(np.ceil(np.pi * max_heading_change_rad / MAX_GRID_HEADING_SPACING_RAD - 1e-9)) + 1
    return max(points, minimum)


class _YawRateObjective:
    """The look-ahead objective with each problem's constants unpacked once (the planner's hot path).

    ``objective(rates (b, C, k), rows (b,)) -> (b, C)``: the unicycle rollout (eq. 1) in closed form and the
    gain ``log det(I_k + U U^T)`` of :mod:`oceanloc.planning.information`, component by component. The
    arrays are laid out ``(step, problem, transponder, candidate)`` so that every operand is contiguous
    (the sizes are small: the cost is per array operation, and strided views double it), and the parts
    of the whitened line of sight ``L^T (p_hat - site) / r`` that do not depend on the site (``dz`` times
    the Cholesky factor's last row) are computed once here.
    """

    def __init__(self, state: PlanningState, planner: LookaheadPlanner) -> None:
        pos, est = state.pos_enu_m, state.estimates_m
        chol = scaled_cholesky(state.covariances_m2, planner.sigma_range_m)
        dz = est[..., 2] - pos[:, 2:3]
        # (10, B, M, 1): one gather per call; the trailing axis broadcasts over candidates. Rows: start
        # yaw; transponder east and north of the vehicle; L00, L10, L11; dz L20, dz L21, dz L22; dz^2.
        self.table = np.stack(
            [
                np.broadcast_to(state.yaw_rad[:, None], dz.shape),
                est[..., 0] - pos[:, 0:1],
                est[..., 1] - pos[:, 1:2],
                chol[..., 0, 0],
                chol[..., 1, 0],
                chol[..., 1, 1],
                dz * chol[..., 2, 0],
                dz * chol[..., 2, 1],
                dz * chol[..., 2, 2],
                dz * dz,
            ]
        )[..., None]
        self.step_m = planner.speed_mps * planner.period_s
        self.period_s = planner.period_s
        self.batch = pos.shape[0]

    def _constants(self, rows: IntArray) -> FloatArray:
        return self.table if rows.size == self.batch == 1 else self.table[:, rows]

    def _whitened_rows(
        self, dx: FloatArray, dy: FloatArray, t: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``L^T (p_hat - site) / r`` from the horizontal components ``dx, dy`` (broadcast against the
        constants ``t``): :func:`~oceanloc.planning.information.whitened_line_of_sight` with the
        site-independent products precomputed."""
        inv_r = 1.0 / np.sqrt(dx * dx + dy * dy + t[9])
        return (dx * t[3] + dy * t[4] + t[6]) * inv_r, (dy * t[5] + t[7]) * inv_r, t[8] * inv_r

    def __call__(self, rates: FloatArray, rows: IntArray) -> FloatArray:
        t = self._constants(rows)
        k = rates.shape[-1]
        steps = rates.transpose(2, 0, 1)  # (k, b, C)
        yaw = t[0, :, 0] + np.cumsum(steps, axis=0) * self.period_s
        px = (np.cumsum(np.cos(yaw), axis=0) * self.step_m)[:, :, None, :]  # (k, b, 1, C), from the start
        py = (np.cumsum(np.sin(yaw), axis=0) * self.step_m)[:, :, None, :]
        u0, u1, u2 = self._whitened_rows(t[1] - px, t[2] - py, t)  # (k, b, M, C)
        if k > 3:
            U = np.stack(np.broadcast_arrays(u0, u1, u2), axis=-1)  # (k, b, M, C, 3)
            U = np.moveaxis(U, 0, -2)  # (b, M, C, k, 3)
            gain = np.linalg.slogdet(np.eye(k) + U @ np.swapaxes(U, -1, -2))[1]
        else:
            gain = log_det_identity_plus_gram([(u0[i], u1[i], u2[i]) for i in range(k)])
        return gain.sum(axis=1)

    def tensor_grid(self, axes: list[FloatArray], rows: IntArray) -> FloatArray | None:
        """The objective on the tensor grid ``axes[0] x ... x axes[k-1]`` of yaw rates, ``(b, prod n_j)``
        in C order, or None for ``k > 3``.

        Step ``j`` of the rollout depends only on the first ``j + 1`` yaw rates, so its sites and
        line-of-sight vectors are computed on ``n_0 ... n_j`` grid points, not on the whole grid: the
        grid stage of the search costs about half the direct evaluation.
        """
        k = len(axes)
        if k > 3:
            return None
        c = self._constants(rows)
        t = c.reshape(*c.shape[:3], *([1] * k))  # (10, b, M, 1, ..., 1)
        yaw = t[0, :, :1]
        px = py = 0.0
        rows_u = []
        for j, ax in enumerate(axes):
            shape = [1] * (k + 2)
            shape[j + 2] = ax.size
            yaw = yaw + ax.reshape(shape) * self.period_s
            px = px + np.cos(yaw) * self.step_m
            py = py + np.sin(yaw) * self.step_m
            rows_u.append(self._whitened_rows(t[1] - px, t[2] - py, t))
        gain = log_det_identity_plus_gram(rows_u)  # (b, M, n_0, ..., n_{k-1})
        return gain.sum(axis=1).reshape(gain.shape[0], -1)


@dataclass(frozen=True, slots=True, kw_only=True)
class GreedyPlanner:
    """Greedy D-optimal point within a reach (PLANS 2018 eqs. 18-29; thesis Section 5.2).

    The decision is a surface point ``x = p + rho [cos theta, sin theta, 0]`` with ``0 <= rho <= d_max``;
    the box search works in these polar coordinates (``theta`` periodic), so the reach constraint is a
    bound and boundary optima (the usual case) are found exactly.

    Attributes
    ----------
    max_distance_m : float
        Reach ``d_max`` between epochs.
    sigma_range_m : float
        Range noise standard deviation.
    search : BoxSearchOptions
    """

    max_distance_m: float
    sigma_range_m: float
    search: BoxSearchOptions = field(default_factory=lambda: BoxSearchOptions(grid_points=24, starts=4))

    def __post_init__(self) -> None:
        if not (self.max_distance_m > 0 and self.sigma_range_m > 0):
            raise ConfigError("max_distance_m and sigma_range_m must be positive")

    def sites(self, state: PlanningState, polar: FloatArray, rows: IntArray | None = None) -> FloatArray:
        """Surface points ``(b, C, 1, 3)`` for polar decisions ``(b, C, 2)`` = ``(rho, theta)``."""
        rho, theta = polar[..., 0], polar[..., 1]
        base = state.pos_enu_m[:, None, :] if rows is None else state.pos_enu_m[rows, None, :]
        pts = np.stack(
            [
                base[..., 0] + rho * np.cos(theta),
                base[..., 1] + rho * np.sin(theta),
                base[..., 2] + 0.0 * rho,
            ],
            -1,
        )
        return pts[..., None, :]

    def gain(self, state: PlanningState, points_enu_m: FloatArray) -> FloatArray:
        """Information gain of measuring at surface points ``(B, C, 3)`` -> ``(B, C)``."""
        chol = scaled_cholesky(state.covariances_m2, self.sigma_range_m)[:, None]
        return information_gain(points_enu_m[..., None, :], state.estimates_m[:, None], chol)

    def plan(self, state: PlanningState, rng: BatchRng | None = None) -> SitePlanResult:
        """The D-optimal point within reach for each problem (``rng`` is not used)."""
        start = time.perf_counter()
        chol = scaled_cholesky(state.covariances_m2, self.sigma_range_m)[:, None]
        est = state.estimates_m[:, None]
        best = maximize_in_box(
            lambda x, rows: information_gain(self.sites(state, x, rows), est[rows], chol[rows]),
            [0.0, -np.pi],
            [self.max_distance_m, np.pi],
            state.batch,
            periodic=[False, True],
            options=self.search,
        )
        site = self.sites(state, best.x[:, None, :])[:, 0, 0]
        return SitePlanResult(
            next_pos_enu_m=site,
            next_yaw_rad=_heading_to(state, site),
            waypoints_enu_m=site[:, None, :],
            yaw_rates_rad_s=None,
            objective=best.value,
            solve_time_s=time.perf_counter() - start,
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class RandomYawPlanner:
    """Random baseline of the journal (k = 0): a yaw rate uniform in ``[-w_max, w_max]``."""

    max_yaw_rate_rad_s: float
    speed_mps: float
    period_s: float
    sigma_range_m: float

    def __post_init__(self) -> None:
        _validate.number("max_yaw_rate_rad_s", self.max_yaw_rate_rad_s, lo=0.0, hi=10.0, lo_open=True)
        _validate.number("speed_mps", self.speed_mps, lo=0.0, hi=100.0, lo_open=True)
        _validate.number("period_s", self.period_s, lo=0.0, hi=86_400.0, lo_open=True)
        _validate.sigmas("sigma_range_m", self.sigma_range_m)

    def plan(self, state: PlanningState, rng: BatchRng | None = None) -> SitePlanResult:
        """Draw one yaw rate per problem from ``rng`` (one generator, or one per problem)."""
        if rng is None:
            raise ConfigError("the random planner needs a random generator")
        start = time.perf_counter()
        rates = (2.0 * uniform(rng, state.batch, (1,)) - 1.0) * self.max_yaw_rate_rad_s
        poses = unicycle_rollout(state.pos_enu_m, state.yaw_rad, rates, self.speed_mps, self.period_s)
        chol = scaled_cholesky(state.covariances_m2, self.sigma_range_m)
        gain = information_gain(poses.pos_enu_m, state.estimates_m, chol)
        return SitePlanResult(
            next_pos_enu_m=poses.pos_enu_m[:, 0],
            next_yaw_rad=poses.yaw_rad[:, 0],
            waypoints_enu_m=poses.pos_enu_m,
            yaw_rates_rad_s=rates,
            objective=gain,
            solve_time_s=time.perf_counter() - start,
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class RandomDiskPlanner:
    """Random baseline of the thesis: a point uniform in the disk of radius ``d_max`` around the vehicle."""

    max_distance_m: float
    sigma_range_m: float

    def __post_init__(self) -> None:
        _validate.number(
            "max_distance_m", self.max_distance_m, lo=0.0, hi=_validate.MAX_LENGTH_M, lo_open=True
        )
        _validate.sigmas("sigma_range_m", self.sigma_range_m)

    def plan(self, state: PlanningState, rng: BatchRng | None = None) -> SitePlanResult:
        """Draw one point per problem from ``rng`` (one generator, or one per problem)."""
        if rng is None:
            raise ConfigError("the random planner needs a random generator")
        start = time.perf_counter()
        u = uniform(rng, state.batch, (2,))
        rho = self.max_distance_m * np.sqrt(u[:, 0])
        theta = 2.0 * np.pi * u[:, 1]
        site = state.pos_enu_m + np.stack([rho * np.cos(theta), rho * np.sin(theta), 0.0 * rho], -1)
        chol = scaled_cholesky(state.covariances_m2, self.sigma_range_m)
        gain = information_gain(site[:, None, :], state.estimates_m, chol)
        return SitePlanResult(
            next_pos_enu_m=site,
            next_yaw_rad=_heading_to(state, site),
            waypoints_enu_m=site[:, None, :],
            yaw_rates_rad_s=None,
            objective=gain,
            solve_time_s=time.perf_counter() - start,
        )


def _heading_to(state: PlanningState, site: FloatArray) -> FloatArray:
    """Heading of the move to ``site``; the current heading where the vehicle stays put."""
    step = site - state.pos_enu_m
    moved = np.hypot(step[:, 0], step[:, 1]) > 1e-12
    return np.where(moved, np.arctan2(step[:, 1], step[:, 0]), state.yaw_rad)
