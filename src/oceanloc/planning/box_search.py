"""Global maximization of smooth objectives over small boxes, batched over many problems.

The planners' decision spaces are tiny (a yaw rate per look-ahead step, or a point in a disk), but the
objectives are multimodal: a single local solve from "straight ahead" (what ``fmincon`` from
``omega = 0`` does) misses the global optimum in a few percent of planning problems. The search here is
global by construction and cheap because every stage evaluates all candidates of all problems in one
vectorized call:

1. **Grid.** Evaluate a regular grid over the box and keep the best ``starts`` grid local maxima
   (points not below any axis neighbour), so distinct basins are refined, not one basin ``starts`` times.
2. **Polish.** From each start, finite-difference Newton steps on a ``3^d`` stencil whose spacing shrinks
   with the step (at most 128-fold per step): central differences, one matrix product, give the
   gradient and Hessian, and the Hessian's eigenvalues are replaced by ``-|lambda|`` (an ascent
   direction even at saddles). The Newton point is not evaluated on its own: it is the centre of the
   next iteration's stencil, so each iteration costs one objective call (single planning problems are
   bound by call overhead, not arithmetic). A candidate that does not improve on the best point seen
   sends the search back there at a finer spacing, so the search is monotone; Newton converges
   quadratically inside a basin. A subproblem stops when the spacing reaches ``step_tol`` or, on a fine
   stencil centred on its best point, when the local model promises less than ``value_tol`` (relative)
   more; its last candidate is then not evaluated (it promises less than that). The cap on the shrink
   matters on bounds: there ``u`` is stationary whatever the objective does, and a zero step on a
   coarse stencil must be confirmed on a fine one, or a bound the objective rises away from within one
   stencil spacing would be returned.

Bounds are removed by the change of variables ``x = c + r sin(u)``, so every point the search visits is
feasible and optima on a bound need no active-set logic (which stalls in the flat valleys these
objectives have near saturated yaw rates).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray
from oceanloc.errors import ConfigError

Objective = Callable[[FloatArray, IntArray], FloatArray]
"""``f(x: (b, C, d), rows: (b,)) -> (b, C)``: values of ``C`` candidates of each problem ``rows[i]``.

An objective may also offer ``tensor_grid(axes: list of (n_j,), rows) -> (b, prod n_j)`` (C order; or
None), a faster evaluation of a whole tensor grid (in ``x``); the grid stage uses it where offered.
"""


@dataclass(frozen=True, slots=True, kw_only=True)
class BoxSearchOptions:
    """Settings of :func:`maximize_in_box`.

    Attributes
    ----------
    grid_points : int
        Grid points per dimension in the global stage.
    starts : int
        Grid local maxima refined per problem.
    max_iterations : int
        Newton iterations of the polish stage.
    step_tol : float
        Stop when the stencil spacing falls below this fraction of the box width.
    value_tol : float
        Or when the local Newton model, at a maximum, promises less than this fraction of the value more
        (the planners need the optimum to 1e-6 relative; this is ten thousand times finer).
    """

    grid_points: int = 9
    starts: int = 3
    max_iterations: int = 40
    step_tol: float = 1e-7
    value_tol: float = 1e-10

    def __post_init__(self) -> None:
        if (
            self.grid_points < 2
            or self.starts < 1
            or self.max_iterations < 0
            or not self.step_tol > 0
            or not self.value_tol >= 0
        ):
            raise ConfigError(f"invalid box search options: {self}")


@dataclass(frozen=True, slots=True, kw_only=True)
class BoxMaximum:
    """Result of :func:`maximize_in_box`.

    Attributes
    ----------
    x : (B, d) float
        Maximizers.
    value : (B,) float
        Objective at ``x``.
    evaluations : int
        Objective evaluations per problem.
    """

    x: FloatArray
    value: FloatArray
    evaluations: int


def grid_axes(lower: FloatArray, upper: FloatArray, points: int, periodic: BoolArray) -> list[FloatArray]:
    """Grid coordinates per dimension; periodic dimensions exclude the upper end (it equals the lower)."""
    return [
        np.linspace(lo, hi, points, endpoint=not per)
        for lo, hi, per in zip(lower, upper, periodic, strict=True)
    ]


def grid_maximum(
    fn: Objective,
    lower: ArrayLike,
    upper: ArrayLike,
    batch: int,
    points: int,
    *,
    periodic: ArrayLike | None = None,
    max_candidates: int = 1 << 20,
) -> BoxMaximum:
    """Exhaustive search over a regular grid (the reference the planners are tested against).

    Evaluates ``points ** d`` grid points per problem, at most ``max_candidates`` (over all problems) per
    call of ``fn`` to bound memory.
    """
    lo, hi, per = _box(lower, upper, periodic)
    mesh = np.stack(np.meshgrid(*grid_axes(lo, hi, points, per), indexing="ij"), axis=-1).reshape(-1, lo.size)
    best_val = np.full(batch, -np.inf)
    best_x = np.zeros((batch, lo.size))
    block = max(1, max_candidates // batch)
    for start in range(0, mesh.shape[0], block):
        cand = mesh[start : start + block]
        vals = fn(np.broadcast_to(cand, (batch, *cand.shape)), np.arange(batch))
        j = np.argmax(vals, axis=1)
        v = vals[np.arange(batch), j]
        better = v > best_val
        best_val = np.where(better, v, best_val)
        best_x = np.where(better[:, None], cand[j], best_x)
    return BoxMaximum(x=best_x, value=best_val, evaluations=mesh.shape[0])


def maximize_in_box(
    fn: Objective,
    lower: ArrayLike,
    upper: ArrayLike,
    batch: int,
    *,
    periodic: ArrayLike | None = None,
    options: BoxSearchOptions | None = None,
) -> BoxMaximum:
    """Global maximum of ``fn`` over ``[lower, upper]`` for ``batch`` problems at once.

    Bounded coordinates are searched through ``x = c + r sin(u)`` (``c``, ``r`` the box centre and half
    width): every ``u`` is feasible, an optimum on a bound is an interior stationary point in ``u``, and the
    polish is unconstrained Newton. The grid is uniform in ``u``, denser near the bounds, where optima
    of saturated controls lie.

    Parameters
    ----------
    fn : callable
        ``fn(x: (b, C, d), rows: (b,)) -> (b, C)``: candidates ``x[i]`` of problem ``rows[i]``.
    lower, upper : (d,) float
        Box bounds.
    batch : int
        Number of problems ``B``.
    periodic : (d,) bool, optional
        Dimensions that wrap around (an angle over ``[lower, upper)``).
    options : BoxSearchOptions, optional
    """
    opts = options or BoxSearchOptions()
    space = _SearchSpace.of(*_box(lower, upper, periodic))
    fn_u = functools.partial(_objective_in_u, fn, space, batch)
    starts = _grid_starts(fn, fn_u, space, batch, opts)
    polished = _polish(fn_u, starts, batch, opts)
    f = polished.f.reshape(batch, starts.count)
    best = np.argmax(f, axis=1)
    all_rows = np.arange(batch)
    u_best = polished.u.reshape(batch, starts.count, space.dims)[all_rows, best]
    return BoxMaximum(x=space.to_x(u_best), value=f[all_rows, best], evaluations=round(polished.evaluations))


@dataclass(frozen=True, slots=True, kw_only=True)
class _SearchSpace:
    """The box in the search variable ``u``: ``x = mid + half sin(u)`` on bounded axes, ``u`` itself
    (wrapped) on periodic ones."""

    lo: FloatArray
    hi: FloatArray
    periodic: BoolArray
    mid: FloatArray
    half: FloatArray
    u_lo: FloatArray
    u_hi: FloatArray
    any_periodic: bool

    @classmethod
    def of(cls, lo: FloatArray, hi: FloatArray, per: BoolArray) -> _SearchSpace:
        return cls(
            lo=lo,
            hi=hi,
            periodic=per,
            mid=0.5 * (lo + hi),
            half=0.5 * (hi - lo),
            u_lo=np.where(per, lo, -0.5 * np.pi),
            u_hi=np.where(per, hi, 0.5 * np.pi),
            any_periodic=bool(np.any(per)),
        )

    @property
    def dims(self) -> int:
        return int(self.lo.size)

    def to_x(self, u: FloatArray) -> FloatArray:
        if not self.any_periodic:
            return self.mid + self.half * np.sin(u)
        return np.where(
            self.periodic, self.lo + np.mod(u - self.lo, self.hi - self.lo), self.mid + self.half * np.sin(u)
        )


def _objective_in_u(
    fn: Objective, space: _SearchSpace, batch: int, u: FloatArray, rows: IntArray
) -> FloatArray:
    """``fn`` of the search variable; a single problem's subproblems are one candidate set of it."""
    if batch == 1 and u.shape[0] > 1:
        return fn(space.to_x(u.reshape(1, -1, space.dims)), rows[:1]).reshape(u.shape[:2])
    return fn(space.to_x(u), rows)


@dataclass(frozen=True, slots=True, kw_only=True)
class _GridStarts:
    """The grid stage's result: one polish subproblem per (problem, start).

    ``u (S, d)`` and ``f (S,)`` are the starts and their values (``S = B * count``, problem-major),
    ``rows (S,)`` their problems, ``base (d,)`` the first stencil spacing in ``u``; ``evaluations`` counts
    the grid's objective evaluations per problem.
    """

    u: FloatArray
    f: FloatArray
    rows: IntArray
    count: int
    base: FloatArray
    evaluations: int


def _grid_starts(
    fn: Objective, fn_u: Objective, space: _SearchSpace, batch: int, opts: BoxSearchOptions
) -> _GridStarts:
    """Stage 1: the objective on the ``u`` grid (a tensor-grid evaluation where ``fn`` offers one) and the
    best ``opts.starts`` grid local maxima of every problem."""
    n, d, per = opts.grid_points, space.dims, space.periodic
    axes, mesh, base = _u_grid(n, tuple(space.u_lo.tolist()), tuple(space.u_hi.tolist()), tuple(per.tolist()))
    all_rows = np.arange(batch)
    tensor_grid = getattr(fn, "tensor_grid", None)
    # on the grid a periodic axis is x itself (its nodes lie in [lo, hi)), a bounded one mid + half sin(u)
    x_axes = [ax if per[j] else space.mid[j] + space.half[j] * np.sin(ax) for j, ax in enumerate(axes)]
    # problems in blocks of at most _GRID_CANDIDATES grid points in all, to bound memory on fine grids
    block = max(1, _GRID_CANDIDATES // mesh.shape[0])
    parts = []
    for first in range(0, batch, block):
        rows = all_rows[first : first + block]
        part = tensor_grid(x_axes, rows) if tensor_grid is not None else None
        if part is None:
            part = fn_u(np.broadcast_to(mesh, (rows.size, *mesh.shape)), rows)
        parts.append(part)
    values = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=0)
    starts = _grid_local_maxima(values.reshape(batch, *([n] * d)), per, opts.starts)
    return _GridStarts(
        u=mesh[starts.reshape(-1)],
        f=np.take_along_axis(values, starts, axis=1).reshape(-1),
        rows=np.repeat(all_rows, starts.shape[1]),
        count=int(starts.shape[1]),
        base=base,
        evaluations=mesh.shape[0],
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class _StencilModel:
    """The local quadratic model one ``3^d`` stencil gives, for ``n`` live subproblems (stencil units).

    Attributes
    ----------
    best_index : (n,) int
        Stencil point with the largest value; ``best_value`` its value, ``centre_value`` the centre's.
    step : (n, d) float
        Newton step on the ``-|lambda|`` Hessian, before the trust region (four spacings per axis).
    step_size : (n,) float
        Its largest component; ``inv_clip`` the trust-region factor ``1 / max(step_size / 4, 1)``.
    predicted_gain : (n,) float
        The model's gain at the unclipped step; ``model_value`` the model's value at the clipped one.
    at_max : (n,) bool
        The Hessian is negative definite (a maximum of the model, not a saddle).
    """

    best_index: IntArray
    best_value: FloatArray
    centre_value: FloatArray
    step: FloatArray
    step_size: FloatArray
    inv_clip: FloatArray
    predicted_gain: FloatArray
    model_value: FloatArray
    at_max: BoolArray


def _stencil_model(fs: FloatArray, weights: FloatArray, center: int, d: int, ar_n: IntArray) -> _StencilModel:
    """Gradient and Hessian from one matrix product of the stencil values, then the ascent step."""
    n = fs.shape[0]
    gh = fs @ weights
    lam, vec = np.linalg.eigh(gh[:, d:].reshape(n, d, d))
    a_lam = np.abs(lam)
    # eigenvalues come sorted: the largest magnitude is at one end
    floor = 1e-9 * np.maximum(a_lam[:, :1], a_lam[:, -1:]) + 1e-300
    curvature = np.maximum(a_lam, floor)
    g_eig = (gh[:, None, :d] @ vec)[:, 0]  # V^T g
    s_eig = g_eig / curvature  # V^T step, before the trust region
    predicted_gain = 0.5 * np.add.reduce(g_eig * s_eig, axis=1)
    step = (vec @ s_eig[:, :, None])[:, :, 0]
    a_step = np.maximum.reduce(np.abs(step), axis=1)
    clip = np.maximum(0.25 * a_step, 1.0)
    inv_clip = 1.0 / clip
    # the model's value at the clipped step: f0 + (2/c - 1/c^2) predicted_gain
    j_best = fs.argmax(axis=1)
    f0 = fs[:, center]
    return _StencilModel(
        best_index=j_best,
        best_value=fs[ar_n, j_best],
        centre_value=f0,
        step=step,
        step_size=a_step,
        inv_clip=inv_clip,
        predicted_gain=predicted_gain,
        model_value=f0 + predicted_gain * inv_clip * (2.0 - inv_clip),
        at_max=lam[:, -1] < 0.0,
    )


@dataclass(frozen=True, slots=True, kw_only=True)
class _Polished:
    """The polish stage's result: the best point ``u (S, d)`` and value ``f (S,)`` of every subproblem,
    and the evaluations per problem so far (grid included)."""

    u: FloatArray
    f: FloatArray
    evaluations: float


@dataclass(frozen=True, slots=True, kw_only=True)
class _Live:
    """The live subproblems of the polish, compacted: ``index`` their position in the stage's arrays,
    ``u`` and ``f`` their best point and value, ``candidate`` the next stencil centre, ``spacing`` the
    stencil spacing in units of ``base``, ``rows`` their problems."""

    index: IntArray
    u: FloatArray
    f: FloatArray
    candidate: FloatArray
    spacing: FloatArray
    rows: IntArray

    def take(self, keep: BoolArray) -> _Live:
        return _Live(
            index=self.index[keep],
            u=self.u[keep],
            f=self.f[keep],
            candidate=self.candidate[keep],
            spacing=self.spacing[keep],
            rows=self.rows[keep],
        )


def _advance(
    live: _Live,
    model: _StencilModel,
    pts: FloatArray,
    hl: FloatArray,
    ar_n: IntArray,
    center: int,
    value_tol: float,
) -> tuple[_Live, BoolArray]:
    """One polish step from the stencil's model: the new best points, the next stencil centres and
    spacings, and which subproblems converged in value."""
    lu, lf, lc, ls = live.u, live.f, live.candidate, live.spacing
    improved = model.best_value > lf
    # Centred on the best point so far, or a better stencil point that the model's Newton point
    # promises to beat: go to the Newton point, spacing from the step. Otherwise a better stencil
    # point: move there at the same spacing. Neither: back to the best point, four times finer.
    centre_best = (model.best_index == center) & (model.centre_value >= lf)
    newton = centre_best | (improved & (model.model_value > model.best_value))
    lu = np.where(improved[:, None], pts[ar_n, model.best_index], lu)
    lf = np.where(improved, model.best_value, lf)
    s_now = ls
    # The next spacing follows the step, but shrinks at most 128-fold: a vanishing step on a coarse
    # stencil (on a bound x = c + r sin(u) is stationary in u whatever the objective does nearby)
    # is checked on a stencil fine enough to stop on (below 1e-2), which sees the way up to any
    # maximum lying farther inside than its spacing.
    step_scale = np.minimum(np.maximum(2.0 * model.step_size * model.inv_clip, _MAX_SHRINK), 1.0) * s_now
    lc = np.where(newton[:, None], lc + model.step * (model.inv_clip[:, None] * hl), lu)
    ls = np.where(newton, step_scale, np.where(improved, s_now, 0.25 * s_now))
    # Converged in value: centred on the best point, on a fine stencil (where the quadratic model is
    # accurate), at a maximum of the model that promises less than value_tol (relative) more, even if
    # a flat direction would let the point itself keep moving.
    flat = (
        centre_best
        & model.at_max
        & (s_now < 1e-2)
        & (model.predicted_gain <= value_tol * np.maximum(1.0, np.abs(lf)))
    )
    return _Live(index=live.index, u=lu, f=lf, candidate=lc, spacing=ls, rows=live.rows), flat


def _polish(fn_u: Objective, starts: _GridStarts, batch: int, opts: BoxSearchOptions) -> _Polished:
    """Stage 2: finite-difference Newton from every start (see the module docstring), then the last
    candidate of every subproblem still live after ``opts.max_iterations``."""
    u, f, base = starts.u.copy(), starts.f.copy(), starts.base
    d = base.size
    scale_min = opts.step_tol * 2.0 * np.pi / float(base.max())
    evaluations: float = starts.evaluations
    stencil, center, weights = _stencil(d)
    # The stencil of each iteration is centred on a candidate: the Newton point of the previous model,
    # evaluated lazily as the centre of the next stencil (one objective call per iteration), or the best
    # point so far after a failed candidate. ``u`` and ``f`` hold the best point seen, so the search is
    # monotone whatever the candidate does. The local model is built in stencil units
    # ``z = (u - centre) / (s base)``: one matrix product gives its gradient and Hessian, and the trust
    # region is four spacings per axis. Retiring subproblems are written back to ``u`` and ``f``.
    live = _Live(
        index=np.arange(u.shape[0]),
        u=u.copy(),
        f=f.copy(),
        candidate=u.copy(),
        spacing=np.ones(u.shape[0]),
        rows=starts.rows.copy(),
    )
    ar = np.arange(u.shape[0])
    for _ in range(opts.max_iterations):
        n = live.index.size
        if n == 0:
            break
        hl = live.spacing[:, None] * base
        pts = live.candidate[:, None, :] + stencil * hl[:, None, :]
        fs = fn_u(pts, live.rows)
        evaluations += len(stencil) * n / batch
        ar_n = ar[:n]
        live, flat = _advance(
            live, _stencil_model(fs, weights, center, d, ar_n), pts, hl, ar_n, center, opts.value_tol
        )
        keep = (live.spacing > scale_min) & ~flat
        if not keep.all():
            done = ~keep
            u[live.index[done]], f[live.index[done]] = live.u[done], live.f[done]
            live = live.take(keep)
    u[live.index], f[live.index] = live.u, live.f
    return _last_candidates(fn_u, _Polished(u=u, f=f, evaluations=evaluations), live, starts.rows, batch)


def _last_candidates(
    fn_u: Objective, polished: _Polished, live: _Live, rows: IntArray, batch: int
) -> _Polished:
    """Subproblems that retired converged (in value, or in spacing) have a last Newton candidate that
    promises nothing worth a call; those still live after ``max_iterations`` get theirs evaluated."""
    u, f, evaluations = polished.u, polished.f, polished.evaluations
    moved = np.any(live.candidate != live.u, axis=-1)
    if moved.any():
        pending, lc = live.index[moved], live.candidate[moved]
        f_cand = fn_u(lc[:, None, :], rows[pending])[:, 0]
        evaluations += pending.size / batch
        better = f_cand > f[pending]
        u[pending[better]] = lc[better]
        f[pending[better]] = f_cand[better]
    return _Polished(u=u, f=f, evaluations=evaluations)


_GRID_CANDIDATES = 1 << 17
"""Most grid points (over all problems of a block) the grid stage evaluates in one objective call."""

_MAX_SHRINK = 1.0 / 128.0
"""Smallest ratio of one stencil spacing to the previous one after a Newton step."""


@functools.lru_cache(maxsize=32)
def _u_grid(
    points: int, u_lo: tuple[float, ...], u_hi: tuple[float, ...], periodic: tuple[bool, ...]
) -> tuple[list[FloatArray], FloatArray, FloatArray]:
    """The grid stage's axes, its ``(points^d, d)`` mesh and the first stencil spacing ``base (d,)`` (half
    the grid step), in the search variable ``u`` (cached: every planning call of a planner uses the same)."""
    axes = grid_axes(np.array(u_lo), np.array(u_hi), points, np.array(periodic))
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(axes))
    base = np.array([ax[1] - ax[0] for ax in axes]) / 2.0
    for arr in (*axes, mesh, base):
        arr.flags.writeable = False
    return axes, mesh, base


def _box(
    lower: ArrayLike, upper: ArrayLike, periodic: ArrayLike | None
) -> tuple[FloatArray, FloatArray, BoolArray]:
    lo = np.atleast_1d(np.asarray(lower, dtype=float))
    hi = np.atleast_1d(np.asarray(upper, dtype=float))
    per = np.zeros(lo.size, bool) if periodic is None else np.atleast_1d(np.asarray(periodic, bool))
    if lo.shape != hi.shape or per.shape != lo.shape or not np.all(hi > lo):
        raise ConfigError(f"invalid box: lower {lo}, upper {hi}, periodic {per}")
    return lo, hi, per


@functools.lru_cache(maxsize=8)
def _stencil(d: int) -> tuple[FloatArray, int, FloatArray]:
    """The ``3^d`` stencil, the index of its centre, and the central-difference weights ``(3^d, d + d^2)``
    that turn the stencil's values into the gradient and the (row-major) Hessian in stencil units
    (cached: the same few dimensions recur on every planning call)."""
    stencil = np.array(list(itertools.product((-1.0, 0.0, 1.0), repeat=d)))
    center = (len(stencil) - 1) // 2
    weights = np.zeros((len(stencil), d + d * d))
    for i in range(d):
        plus, minus = _stencil_index(stencil, {i: 1}), _stencil_index(stencil, {i: -1})
        weights[plus, i], weights[minus, i] = 0.5, -0.5
        hii = d + i * d + i
        weights[plus, hii], weights[minus, hii], weights[center, hii] = 1.0, 1.0, -2.0
        for j in range(i + 1, d):
            for a, b, w in ((1, 1, 0.25), (1, -1, -0.25), (-1, 1, -0.25), (-1, -1, 0.25)):
                idx = _stencil_index(stencil, {i: a, j: b})
                weights[idx, d + i * d + j] = weights[idx, d + j * d + i] = w
    for arr in (stencil, weights):
        arr.flags.writeable = False
    return stencil, center, weights


def _stencil_index(stencil: FloatArray, offsets: dict[int, int]) -> int:
    target = np.zeros(stencil.shape[1])
    for i, o in offsets.items():
        target[i] = o
    return int(np.flatnonzero(np.all(stencil == target, axis=1))[0])


def _grid_local_maxima(values: FloatArray, periodic: BoolArray, count: int) -> FloatArray:
    """Flat indices ``(B, count)`` of the best grid local maxima (best point repeated if fewer)."""
    batch = values.shape[0]
    d = values.ndim - 1
    # pad every non-periodic axis with -inf (wrap the periodic ones), then compare with both neighbours
    padded = values
    for axis in range(1, d + 1):
        if periodic[axis - 1]:
            padded = np.concatenate([padded.take([-1], axis), padded, padded.take([0], axis)], axis=axis)
        else:
            shape = list(padded.shape)
            shape[axis] = 1
            edge = np.full(shape, -np.inf)
            padded = np.concatenate([edge, padded, edge], axis=axis)
    inner = tuple([slice(None)] + [slice(1, -1)] * d)
    is_max = np.ones(values.shape, dtype=bool)
    for axis in range(1, d + 1):
        for lo, hi in ((0, -2), (2, None)):
            nb = list(inner)
            nb[axis] = slice(lo, hi)
            is_max &= values >= padded[tuple(nb)]
    flat = values.reshape(batch, -1)
    score = np.where(is_max.reshape(batch, -1), flat, -np.inf)
    order = np.argsort(-score, axis=1, kind="stable")[:, :count]
    ranked = np.take_along_axis(score, order, axis=1)
    return np.where(np.isfinite(ranked), order, order[:, :1])
