"""Beacon localization from aligned GPS + USBL range logs: robust MAP per beacon (eqs. 10-22).

Each beacon is one MAP problem. The range noise is the journal's total ``sigma_eps`` (USBL noise and
GPS error projected on the line of sight, Section VI-B, eqs. 46-52). Multipath returns arrive late
(ranges too long by metres); the authors' rule removes the largest normalized residual above
``outlier_threshold`` one at a time, re-solving after each removal, and every exclusion is listed.

The journal treats the GPS part ``q(n) = h(n) dp_V(n)`` as white. A differential GPS error is not: it
wanders over tens of seconds to minutes, so ranges a few seconds apart share it, and the white model's
covariance is several times too small (NEES in the tens to hundreds on the simulated pier logs, whose
DGPS error is Gauss-Markov with a 60 s time constant). With ``gps_correlation_s`` the GPS error is a
Gauss-Markov process, ``Cov(q_i, q_j) = h_i D h_j^T exp(-|t_i - t_j| / tau)``, and the final estimate
is the generalized least-squares MAP solution with that full covariance, its covariance consistent;
outliers are still found under the white model first.

**Cost.** Both steps are O(n) in the ranges of a beacon, so a 24-hour journal is estimated in tens of
milliseconds:

* the generalized least squares never forms the ``n x n`` covariance. The ranges are
  ``r_i = f_i(x) + h_i . g(t_i) + w_i`` with ``g`` a 3-axis Ornstein-Uhlenbeck process and ``w`` white
  (variance ``s^2``); the precision ``Q`` of the stacked ``g(t_i)`` is block-tridiagonal (a Markov
  chain), so by the Woodbury identity ``Sigma^-1 v = v / s^2 - H M^-1 H^T v / s^4`` with
  ``M = Q + H^T H / s^2`` banded (bandwidth 3 in ``3n x 3n``), factored once per linearization by
  LAPACK's banded Cholesky (:class:`CorrelatedRangeProblem`). This is exact, not an approximation.
* the outlier rule (:func:`robust_white_fit`) is the authors' rule with its per-removal re-solve done
  by a rank-one downdate: see there for the reading, which gives the same exclusions.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from oceanloc import _validate
from oceanloc._typing import BoolArray, FloatArray, IntArray
from oceanloc.errors import ArgumentError, ConfigError, DataError
from oceanloc.estimation.map_gauss_newton import (
    GaussianPrior,
    MapOptions,
    MapResult,
    solve_map,
)
from oceanloc.io.usbl import AlignedRanges
from oceanloc.models.measurements import range_jacobian


@dataclass(frozen=True, slots=True, kw_only=True)
class BeaconEstimate:
    """One beacon's estimate.

    Attributes
    ----------
    beacon : int
    position_enu_m : (3,) float
    covariance_m2 : (3, 3) float
    used : (m,) bool
        Over that beacon's ranges, in log order.
    n_excluded : int
    residual_rms_m : float
    """

    beacon: int
    position_enu_m: FloatArray
    covariance_m2: FloatArray
    used: BoolArray
    n_excluded: int
    residual_rms_m: float


@dataclass(frozen=True, slots=True)
class CorrelatedRangeProblem:
    """Ranges to one position with white sensor noise plus a Gauss-Markov GPS error (module docstring).

    The covariance ``Sigma = s^2 I + H P H^T`` (``P`` the Ornstein-Uhlenbeck covariance of the GPS error
    at the range epochs, ``H`` the lines of sight at the linearization point) is held through the banded
    Cholesky factor of ``M = P^-1 + H^T H / s^2``; :meth:`evaluate` applies ``Sigma^-1`` by the Woodbury
    identity in O(n). It returns, instead of the ``n`` whitened residuals ``L^-1 r`` and Jacobian rows
    ``L^-1 J`` (any square root ``L`` of ``Sigma``), four rows ``A = [J_w r_w]`` with
    ``A^T A = [J r]^T Sigma^-1 [J r]``: the same normal matrix, gradient and cost for
    :func:`~oceanloc.estimation.map_gauss_newton.solve_map`, whatever ``n``.

    Attributes
    ----------
    sensor_m : (m, 3) float
        Vehicle positions of the ranges used, metres.
    ranges_m : (m,) float
    los : (m, 3) float
        Lines of sight ``h_i`` at the linearization point (unit vectors).
    state : (m,) int
        Index of each range's GPS-error state (ranges at the same time share one).
    axes : (k,) int
        The GPS axes with a positive sigma (the others carry no error).
    band : (k + 1, k p) float
        Lower banded Cholesky factor of ``M`` (``p`` distinct epochs).
    white_var_m2 : float
        ``s^2``, square metres.
    """

    sensor_m: FloatArray
    ranges_m: FloatArray
    los: FloatArray
    state: IntArray
    axes: IntArray
    band: FloatArray
    white_var_m2: float
    identity: bool = False
    """Each range its own state, in time order (distinct sorted times: no scatter needed)."""
    los_axes: FloatArray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    """``los[:, axes]``, contiguous."""
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def at(
        cls,
        point_m: FloatArray,
        sensor_m: FloatArray,
        ranges_m: FloatArray,
        t_s: FloatArray,
        used: BoolArray,
        *,
        sigma_white_m: float,
        sigma_gps_enu_m: FloatArray,
        correlation_s: float,
    ) -> CorrelatedRangeProblem:
        """The used ranges, with their covariance built at the lines of sight from ``point_m`` (3,).

        ``sensor_m (n, 3)``, ``ranges_m (n,)``, ``t_s (n,)`` (seconds) and ``used (n,)``; white noise
        ``sigma_white_m``, GPS sigma per axis ``sigma_gps_enu_m (3,)`` with time constant ``correlation_s``.
        """
        from scipy.linalg import cholesky_banded  # imported here: the command line starts without scipy

        sensors = np.asarray(sensor_m, dtype=float)[used]
        h = range_jacobian(point_m, sensors)
        t = np.asarray(t_s, dtype=float)[used]
        var = np.square(np.asarray(sigma_gps_enu_m, dtype=float))
        axes = np.flatnonzero(var > 0.0)
        k = axes.size
        epochs_order = None
        if t.size and np.all(np.diff(t) > 0.0):  # time order, distinct (a journal beacon's ranges)
            epochs, state = t, np.arange(t.size)
            epochs_order = state
        else:
            epochs, state = np.unique(t, return_inverse=True)
        p = epochs.size
        s2 = float(sigma_white_m) ** 2
        band = np.zeros((k + 1, k * p))
        if k and p:
            # Ornstein-Uhlenbeck precision per axis (a Markov chain): g_a = phi_a g_(a-1) + e_a,
            # Var e_a = D (1 - phi_a^2), Var g_0 = D.
            dt = np.diff(epochs)
            phi = np.exp(-dt / correlation_s)
            one_minus = -np.expm1(-2.0 * dt / correlation_s)  # 1 - phi^2, accurate for small dt
            d = var[axes]
            q = np.concatenate([np.ones(1), one_minus])[:, None] * d[None, :]  # (p, k)
            diag = 1.0 / q
            diag[:-1] += (phi**2 / one_minus)[:, None] / d[None, :]
            hk = h[:, axes] if p == t.size else np.zeros((p, k))
            if p == t.size:  # distinct epochs (the journal's case): one state per range
                hk = hk if epochs_order is not None else hk[np.argsort(state)]
                band[0] = (diag + hk * hk / s2).reshape(-1)
                for off in range(1, k):
                    sub = np.zeros((p, k))
                    sub[:, : k - off] = hk[:, off:] * hk[:, : k - off] / s2
                    band[off] = sub.reshape(-1)
            else:
                hu = h[:, axes]
                block = np.zeros((p, k, k))
                np.add.at(block, state, hu[:, :, None] * hu[:, None, :] / s2)
                band[0] = (diag + np.diagonal(block, axis1=1, axis2=2)).reshape(-1)
                for off in range(1, k):
                    sub = np.zeros((p, k))
                    sub[:, : k - off] = np.diagonal(block, offset=-off, axis1=1, axis2=2)
                    band[off] = sub.reshape(-1)
            cross = np.zeros((p, k))
            cross[:-1] = -(phi / one_minus)[:, None] / d[None, :]
            band[k] = cross.reshape(-1)
            band = cholesky_banded(band, lower=True, check_finite=False)
        identity = epochs_order is not None
        return cls(
            sensors, np.asarray(ranges_m, dtype=float)[used], h, state, axes, band, s2, identity,
            np.ascontiguousarray(h[:, axes]), {},
        )  # fmt: skip

    @property
    def batch_size(self) -> int:
        return 1

    def gram(self, x: FloatArray, *, newton: bool = False) -> FloatArray:
        """``[J r]^T Sigma^-1 [J r]`` at ``x (3,)``, ``(4, 4)``: ``J = d range / dx``, ``r`` the residuals.

        With ``newton`` the upper-left block is the cost's full Hessian instead of Gauss-Newton's
        ``J^T Sigma^-1 J``: minus ``sum_i y_i (I - h_i h_i^T) / rho_i`` with ``y = Sigma^-1 r`` (the
        ranges' curvature); the gradient and cost entries are unchanged.
        """
        from scipy.linalg.lapack import dtbtrs

        x = np.asarray(x, dtype=float).reshape(3)
        diff = x - self.sensor_m
        rho = np.sqrt(np.einsum("ij,ij->i", diff, diff))
        resid = self.ranges_m - rho
        jac = diff / np.where(rho > 0.0, rho, np.inf)[:, None]
        v = np.column_stack([jac, resid])
        s2 = self.white_var_m2
        gram = v.T @ v / s2
        y = resid / s2
        k = self.axes.size
        if k and resid.size:
            los = self.los_axes
            p = self.band.shape[1] // k
            if self.identity:  # U = H^T V state by state, written column by column (Fortran order)
                u = np.empty((p * k, 4), order="F")
                for c in range(4):
                    u[:, c] = (los * v[:, c : c + 1]).reshape(-1)
            else:  # states shared or out of time order
                acc = np.zeros((p, k, 4))
                np.add.at(acc, self.state, los[:, :, None] * v[:, None, :])
                u = np.asfortranarray(acc.reshape(-1, 4))
            # U^T M^-1 U = W^T W with W = L^-1 U: one banded triangular solve (LAPACK dtbtrs).
            w_mat, info = dtbtrs(self.band, u, uplo="L", overwrite_b=1)
            if info != 0:  # pragma: no cover - the factor is nonsingular
                raise DataError(f"banded triangular solve failed (LAPACK info {info})")
            gram -= w_mat.T @ w_mat / s2**2
            if newton:  # y = Sigma^-1 r needs M^-1 (H^T r) = L^-T (L^-1 H^T r)
                back, info = dtbtrs(self.band, w_mat[:, 3:4].copy(order="F"), uplo="L", trans="T")
                w = back[:, 0].reshape(p, k)
                w = w if self.identity else w[self.state]
                y = y - np.einsum("ik,ik->i", los, w) / s2**2
        gram = 0.5 * (gram + gram.T)
        self._cache["gauss-newton", x.tobytes()] = gram[:3, :3].copy()
        if newton:
            c = y / np.where(rho > 0.0, rho, np.inf)
            curv = np.eye(3) * c.sum() - (jac * c[:, None]).T @ jac
            gram[:3, :3] -= curv
        return gram

    def gauss_newton_information(self, x: FloatArray) -> FloatArray:
        """``J^T Sigma^-1 J`` at ``x (3,)`` (no prior), ``(3, 3)``: kept from the last :meth:`gram`
        there, else computed."""
        x = np.asarray(x, dtype=float).reshape(3)
        hit = self._cache.get(("gauss-newton", x.tobytes()))
        return hit if hit is not None else self.gram(x)[:3, :3]

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        """Four rows ``A`` with ``A^T A`` the Newton form of :meth:`gram` (quadratic convergence of
        :func:`solve_map`; its stationary point is the same), or the Gauss-Newton form where the Newton
        one is not positive semi-definite."""
        key = np.asarray(x, dtype=float).tobytes()
        if (hit := self._cache.get(key)) is not None:  # solve_map evaluates an accepted trial twice
            return hit
        self._cache.clear()
        gram = self.gram(x[0], newton=True)
        w, vec = np.linalg.eigh(gram)
        if w[0] < -1e-10 * abs(w[-1]):
            gram[:3, :3] = self.gauss_newton_information(x[0])
            w, vec = np.linalg.eigh(gram)
        rows4 = np.sqrt(np.maximum(w, 0.0))[:, None] * vec.T  # rows4^T rows4 = gram
        out = rows4[None, :, 3], rows4[None, :, :3]
        self._cache[key] = out
        return out


MIN_BEACON_RANGES = 4
"""Ranges a beacon needs to be localized (three position coordinates, one redundancy)."""

REBASE_STEP_M = 0.1
""":func:`robust_white_fit`: the linearization point is moved (an O(n) pass) once the estimate has moved
this far from it, metres. The linearized estimate is then within about ``10 step^2 / (2 range)`` of the
exact one (the factor 10 is the weak vertical geometry; measured on a 24-hour pier log: at most 5 mm),
inside :data:`EXACT_MARGIN`."""

EXACT_MARGIN = 5e-3
""":func:`robust_white_fit`: a removal decision within this relative margin of the threshold (15 mm of
residual at a 1 m scale) is made on the converged estimate of the current mask, and the decision to stop
on a full :func:`solve_map` re-solve, as the original rule makes them."""


@dataclass(frozen=True, slots=True, kw_only=True)
class WhiteFit:
    """What :func:`robust_white_fit` found for one beacon.

    Attributes
    ----------
    used : (m,) bool
        Ranges kept by the outlier rule.
    result : MapResult
        The last full solve of the rule (batch of one): on ``used``, or, when the rule stopped at its
        removal cap, on ``used`` plus the last range removed (as the original loop does).
    removals : int
        Ranges removed by this call.
    """

    used: BoolArray
    result: MapResult
    removals: int

    @property
    def estimate_m(self) -> FloatArray:
        return self.result.estimate[0]


@dataclass(frozen=True, slots=True)
class NewtonRangeProblem:
    """The white-noise range problem of one beacon in the four-row form of
    :class:`CorrelatedRangeProblem` (``A^T A = [J r]^T [J r] / sigma^2``, the upper-left block the full
    Hessian ``J^T J / sigma^2 - sum_i r_i (I - h_i h_i^T) / (rho_i sigma^2)`` where that is positive
    definite), so :func:`solve_map` converges quadratically to the same minimum as with
    :class:`~oceanloc.estimation.map_gauss_newton.RangeProblem`.

    Attributes
    ----------
    sensor_m : (m, 3) float
        Sensor positions of the used ranges, metres.
    ranges_m : (m,) float
    sigma_m : float
    """

    sensor_m: FloatArray
    ranges_m: FloatArray
    sigma_m: float
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def batch_size(self) -> int:
        return 1

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        key = np.asarray(x, dtype=float).tobytes()
        if (hit := self._cache.get(key)) is not None:  # solve_map evaluates an accepted trial twice
            return hit
        out = self._evaluate(x)
        self._cache.clear()
        self._cache[key] = out
        return out

    def _evaluate(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        diff = x[0] - self.sensor_m
        rho = np.sqrt(np.einsum("ij,ij->i", diff, diff))
        inv_rho = 1.0 / np.where(rho > 0.0, rho, np.inf)
        jac = diff * inv_rho[:, None]
        v = np.column_stack([jac, self.ranges_m - rho])
        gram = v.T @ v / self.sigma_m**2
        c = v[:, 3] * inv_rho / self.sigma_m**2
        newton = gram.copy()
        newton[:3, :3] -= np.eye(3) * c.sum() - (jac * c[:, None]).T @ jac
        w, vec = np.linalg.eigh(newton)
        if w[0] < -1e-10 * abs(w[-1]):
            w, vec = np.linalg.eigh(gram)
        rows4 = np.sqrt(np.maximum(w, 0.0))[:, None] * vec.T
        return rows4[None, :, 3], rows4[None, :, :3]


def prior_mean(
    beacon: int,
    sensors_m: FloatArray,
    ranges_m: FloatArray,
    surface_m: float,
    prior_depth_m: float,
    known_enu_m: Mapping[int, FloatArray] | None = None,
) -> FloatArray:
    """A beacon's prior mean (3,), metres: its known drop position if given, else the point
    ``prior_depth_m`` below the surface ``surface_m`` under the sensor of the shortest range."""
    if known_enu_m is not None and beacon in known_enu_m:
        return np.asarray(known_enu_m[beacon], dtype=float).reshape(3).copy()
    i0 = int(np.argmin(ranges_m))
    return np.array([sensors_m[i0, 0], sensors_m[i0, 1], surface_m - prior_depth_m])


def _solve(
    sensors: FloatArray,
    z: FloatArray,
    sigma: float,
    used: BoolArray,
    prior: GaussianPrior,
    opts: MapOptions,
    x: FloatArray,
) -> MapResult:
    """Full MAP solve of the white problem on the used ranges (Newton form; covariance Gauss-Newton's)."""
    problem = NewtonRangeProblem(sensors[used], z[used], sigma)
    res = solve_map(problem, prior, opts, initial=np.asarray(x, dtype=float).reshape(1, 3))
    # The covariance is Gauss-Newton's (J^T J / sigma^2 + P0^-1)^-1 at the estimate, eq. (22).
    jac = range_jacobian(res.estimate[0], sensors[used]) / sigma
    info = jac.T @ jac + np.linalg.inv(np.asarray(prior.cov, dtype=float).reshape(3, 3))
    cov = np.linalg.inv(info)
    return dataclasses.replace(res, information=info[None], covariance=0.5 * (cov + cov.T)[None])


def robust_white_fit(
    sensors: FloatArray,
    z: FloatArray,
    sigma_m: float,
    prior: GaussianPrior,
    options: MapOptions,
    *,
    initial_m: FloatArray,
    used: BoolArray | None = None,
    outlier_threshold: float = 3.0,
    max_removals: int | None = None,
) -> WhiteFit:
    """The authors' outlier rule under the white model, in O(n + removals) work instead of a full solve
    per removal.

    The rule: solve the MAP problem on the used ranges; compute every residual at the estimate and their
    scale ``max(rms over used, sigma)``; if the largest normalized residual exceeds the threshold, remove
    that range and repeat (at most ``max_removals`` removals, default ``int(0.25 m) + 1``).

    The reading implemented: after a removal the re-solved estimate is the exact minimizer of the
    problem linearized about a reference point ``x_r`` (a rank-one downdate of the normal equations
    ``sum g g^T``, ``sum r g``, ``sum r^2`` kept at ``x_r``: O(1) per removal). The argmax is taken over
    the exact residuals at that estimate: candidates are sorted by their residual at ``x_r``, and since
    ``| |r_j(x)| - |r_j(x_r)| | <= |x - x_r|`` only those within that bound of the best are evaluated. The
    reference is moved (one O(n) pass and a Gauss-Newton step) once ``|x - x_r|`` exceeds
    :data:`REBASE_STEP_M` (the linearized estimate is then within ``~|x - x_r|^2 / (2 range)`` of the
    exact one). Every decision within :data:`EXACT_MARGIN` of the threshold, and the decision to stop, is
    made on a full :func:`solve_map` re-solve, as in the original; decisions clear of it are the same
    under the linearization error. The only difference left is the order in which two ranges far above
    the threshold, with residuals within that error of each other, are removed: both are removed either
    way, so the exclusions equal the original's (tested range for range on the pier logs) and the
    estimate, always a full solve on the final mask, is the original's to its convergence tolerance
    where the problem has one minimum.

    Several consecutive removals are made at once (:func:`_removal_batch`) where the one-at-a-time rule
    provably makes them in that order. Work: O(n) per reference pass (a few per survey) plus O(window)
    per removal, instead of an O(n) solve per removal (O(n^2) on a long journal).

    Parameters
    ----------
    sensors : (m, 3) float
    z : (m,) float
    sigma_m : float
        White range sigma, metres.
    prior, options
        As for :func:`solve_map` (one problem).
    initial_m : (3,) float
        Start of the first solve (a warm start: the previous estimate).
    used : (m,) bool, optional
        Ranges already kept (others stay excluded); all by default.
    """
    m = z.size
    used = np.ones(m, dtype=bool) if used is None else used.copy()
    cap = int(0.25 * m) + 1 if max_removals is None else max_removals
    prior_info = np.linalg.inv(np.asarray(prior.cov, dtype=float).reshape(3, 3))
    mean = np.asarray(prior.mean, dtype=float).reshape(3)
    inv_s2 = 1.0 / sigma_m**2
    res = _solve(sensors, z, sigma_m, used, prior, options, initial_m)
    x = res.estimate[0].copy()
    solved = True  # res is the full solve of the current mask and x its estimate
    refined = True  # x is the converged (Gauss-Newton) estimate of the current mask
    removals = 0

    def gn_step(sums: tuple[float, FloatArray, FloatArray], at: FloatArray) -> FloatArray:
        """The minimizer of the problem linearized at the reference, minus the reference."""
        _, s_rg, s_gg = sums
        return np.linalg.solve(s_gg * inv_s2 + prior_info, -s_rg * inv_s2 - prior_info @ (at - mean))

    while True:
        # Reference pass at x: residuals, their gradients d r / d x, the normal-equation sums.
        x_ref = x.copy()
        diff = sensors - x_ref
        rho = np.sqrt(np.einsum("ij,ij->i", diff, diff))
        g = diff / np.where(rho > 0.0, rho, 1.0)[:, None]
        r0 = z - rho
        wr = np.where(used, r0, 0.0)
        sum_rr, sum_rg, sum_gg = float(wr @ r0), wr @ g, (g * used[:, None]).T @ g
        n_used = int(used.sum())
        # Second order in the step: r_i(x_r + d) = r_i + g_i.d - d^T A_i d / 2 with
        # A_i = (I - g_i g_i^T) / rho_i, so the sums take K = sum g g^T - sum r_i A_i (the Newton form;
        # Gauss-Newton's where that is not positive definite). Each range contributes
        # g g^T - coef (I - g g^T) with coef = r_i / rho_i.
        coef = wr / np.where(rho > 0.0, rho, np.inf)
        newton_gg = sum_gg - (np.eye(3) * coef.sum() - (g * coef[:, None]).T @ g)
        if np.linalg.eigvalsh(newton_gg * inv_s2 + prior_info)[0] > 0.0:
            sum_gg = newton_gg
        else:
            coef = np.zeros_like(coef)
        if not refined:  # a Newton step at the new reference (converged once it is tiny)
            step = gn_step((sum_rr, sum_rg, sum_gg), x_ref)
            if np.linalg.norm(step) > 0.5 * REBASE_STEP_M:  # far: a full solve
                res = _solve(sensors, z, sigma_m, used, prior, options, x)
                x, solved, refined = res.estimate[0].copy(), True, True
                continue
            x = x_ref + step
            refined = bool(np.linalg.norm(step) <= options.delta_min_m)
            if refined:
                x = x_ref  # converged: the reference itself, where the sums are exact
        # Candidates: a range below this can not reach the threshold before the next reference pass.
        low = outlier_threshold * sigma_m - 2.0 * REBASE_STEP_M
        cand = np.flatnonzero(used & (np.abs(r0) >= low))
        cand = cand[np.argsort(-np.abs(r0[cand]), kind="stable")]
        alive = np.ones(cand.size, dtype=bool)
        head = 0
        while True:
            d = x - x_ref
            bound = float(np.linalg.norm(d))
            if bound > REBASE_STEP_M:
                break
            while head < cand.size and not alive[head]:
                head += 1
            if head < cand.size and cap - removals > 2:
                # Several removals at once where the one-at-a-time rule provably makes them in this order.
                pos = head + np.flatnonzero(alive[head : head + 4 * _WINDOW])[:_WINDOW]
                after = pos[-1] + 1 + np.flatnonzero(alive[pos[-1] + 1 :])[:1]
                outside = float(np.abs(r0[cand[after[0]]])) if after.size else 0.0
                taken = _removal_batch(
                    cand[pos], x, x_ref, z, sensors, r0, g, coef, (sum_rr, sum_rg, sum_gg), n_used,
                    min(_WINDOW // 2, cap - removals - 2), outside, sigma_m, outlier_threshold,
                    prior_info @ (x_ref - mean), prior_info,
                )  # fmt: skip
                if taken is not None:
                    order, x, (sum_rr, sum_rg, sum_gg) = taken
                    used[cand[pos[order]]] = False
                    alive[pos[order]] = False
                    removals += order.size
                    n_used -= order.size
                    solved = refined = False
                    continue
            if head == cand.size:
                worst, best = -1, 0.0
            else:
                width = 8
                while True:
                    window = np.arange(head, min(head + width, cand.size))
                    window = window[alive[window]]
                    idx = cand[window]
                    res_abs = np.abs(z[idx] - np.linalg.norm(sensors[idx] - x, axis=1))
                    k = int(np.argmax(res_abs))
                    best = float(res_abs[k])
                    end = window[-1] + 1
                    if end >= cand.size or abs(r0[cand[end]]) + bound < best:
                        break
                    width *= 4
                worst = int(window[k])
            s = sum_rr + 2.0 * float(sum_rg @ d) + float(d @ sum_gg @ d)
            scale = max(np.sqrt(max(s, 0.0) / max(n_used, 1)), sigma_m)
            ratio = best / scale
            if ratio <= outlier_threshold * (1.0 + EXACT_MARGIN) and not refined:
                break  # decide on the converged estimate: reference passes until it is
            if ratio <= outlier_threshold:
                if solved:
                    return WhiteFit(used=used, result=res, removals=removals)
                res = _solve(sensors, z, sigma_m, used, prior, options, x)  # the original stops on one
                x, solved, refined = res.estimate[0].copy(), True, True
                break
            j = int(cand[worst])
            if removals + 1 >= cap:  # the original's last pass: removes without re-solving
                if not solved:
                    res = _solve(sensors, z, sigma_m, used, prior, options, x)
                used[j] = False
                return WhiteFit(used=used, result=res, removals=removals + 1)
            used[j] = False
            removals += 1
            alive[worst] = False
            n_used -= 1
            sum_rr -= r0[j] ** 2
            sum_rg = sum_rg - r0[j] * g[j]
            gj = np.outer(g[j], g[j])
            sum_gg = sum_gg - gj + coef[j] * (np.eye(3) - gj)
            x = x_ref + gn_step((sum_rr, sum_rg, sum_gg), x_ref)
            solved = refined = False


_WINDOW = 64
"""Candidates looked at per batch of removals in :func:`robust_white_fit`."""


def _removal_batch(
    idx: IntArray,
    x: FloatArray,
    x_ref: FloatArray,
    z: FloatArray,
    sensors: FloatArray,
    r0: FloatArray,
    g: FloatArray,
    coef: FloatArray,
    sums: tuple[float, FloatArray, FloatArray],
    n_used: int,
    most: int,
    outside_m: float,
    sigma_m: float,
    threshold: float,
    prior_dev: FloatArray,
    prior_info: FloatArray,
) -> tuple[IntArray, FloatArray, tuple[float, FloatArray, FloatArray]] | None:
    """Up to ``most`` consecutive removals of :func:`robust_white_fit` at once, or None.

    The candidates ``idx`` (a window of the largest residuals; every other range's residual is at most
    ``outside_m`` at ``x_ref``) are removed in the order of their residuals at ``x``; the estimate after
    each removal is the downdated linearized solve, vectorized over the batch. The longest leading run
    is kept in which, before each removal, that range is the exact argmax of the residuals at the
    current estimate (window evaluated, the rest bounded), its ratio clears the threshold by
    :data:`EXACT_MARGIN`, and the estimate is within :data:`REBASE_STEP_M` of ``x_ref``: exactly the
    one-at-a-time rule's steps. Returns the window positions removed, the new estimate and the sums.
    """
    if most < 2:
        return None
    sum_rr, sum_rg, sum_gg = sums
    inv_s2 = 1.0 / sigma_m**2
    e_now = np.abs(z[idx] - np.linalg.norm(sensors[idx] - x, axis=1))
    order = np.argsort(-e_now, kind="stable")[:most]
    b = order.size
    gk, rk = g[idx[order]], r0[idx[order]]
    outer = gk[:, :, None] * gk[:, None, :]
    ck = coef[idx[order]][:, None, None]
    c_gg = sum_gg - np.cumsum(outer - ck * (np.eye(3) - outer), axis=0)
    c_rg = sum_rg - np.cumsum(rk[:, None] * gk, axis=0)
    c_rr = sum_rr - np.cumsum(rk**2)
    rhs = -(c_rg * inv_s2 + prior_dev)
    x_after = x_ref + np.linalg.solve(c_gg * inv_s2 + prior_info, rhs[..., None])[..., 0]
    x_before = np.vstack([x[None], x_after[:-1]])
    rr_b = np.concatenate([[sum_rr], c_rr[:-1]])
    rg_b = np.vstack([sum_rg[None], c_rg[:-1]])
    gg_b = np.concatenate([sum_gg[None], c_gg[:-1]])
    dev = x_before - x_ref
    bounds = np.linalg.norm(dev, axis=1)
    resid = np.abs(z[idx][None] - np.linalg.norm(sensors[idx][None] - x_before[:, None], axis=-1))
    rank = np.full(idx.size, b)
    rank[order] = np.arange(b)
    resid = np.where(rank[None, :] < np.arange(b)[:, None], -np.inf, resid)
    pick = np.argmax(resid, axis=1)
    best = resid[np.arange(b), pick]
    ss = rr_b + 2.0 * np.einsum("bi,bi->b", rg_b, dev) + np.einsum("bi,bij,bj->b", dev, gg_b, dev)
    scale = np.maximum(np.sqrt(np.maximum(ss, 0.0) / np.maximum(n_used - np.arange(b), 1)), sigma_m)
    ok = (
        (pick == order)
        & (best > threshold * (1.0 + EXACT_MARGIN) * scale)
        & (best > outside_m + bounds)
        & (bounds <= REBASE_STEP_M)
    )
    taken = int(np.argmin(ok)) if not ok.all() else b
    if taken == 0:
        return None
    k = taken - 1
    return order[:taken], x_after[k], (float(c_rr[k]), c_rg[k], c_gg[k])


def correlated_fit(
    sensors: FloatArray,
    z: FloatArray,
    t_s: FloatArray,
    used: BoolArray,
    prior: GaussianPrior,
    options: MapOptions,
    *,
    initial_m: FloatArray,
    sigma_range_m: float,
    sigma_gps_m: float,
    gps_correlation_s: float,
    passes: int = 2,
    linearize_at: FloatArray | None = None,
    first_pass: list[FloatArray] | None = None,
    warm_start: bool = False,
    last_start_m: FloatArray | None = None,
) -> MapResult:
    """The generalized least-squares MAP estimate on the used ranges with the Gauss-Markov GPS error
    (module docstring): ``passes`` solves, each with the covariance at the previous estimate's lines of
    sight (O(n) each, :class:`CorrelatedRangeProblem`); the first at ``linearize_at`` (default: the
    start ``initial_m``). The solves start at ``initial_m``, then at the previous pass's estimate, which
    is appended to ``first_pass`` when given (a warm start for the next call).

    With ``warm_start`` (``initial_m`` the previous call's first-pass estimate, a few millimetres
    away) the passes are Newton steps instead of :func:`solve_map`: one for the first pass (it lands
    within the square of that distance), to convergence (``delta_min_m``) for the last, falling back to
    the solver where a step is longer than :data:`WARM_STEP_M`. ``last_start_m``: with ``warm_start``,
    where the last pass starts (the previous call's result, a few millimetres from this one's) instead
    of the previous pass's estimate (which the change of linearization point can move by decimetres);
    the pass's problem, linearized at the previous pass's estimate, is the same either way."""
    x = np.asarray(initial_m, dtype=float).reshape(1, 3)
    point = x[0] if linearize_at is None else np.asarray(linearize_at, dtype=float).reshape(3)
    res = problem = None
    prior_info = np.linalg.inv(np.asarray(prior.cov, dtype=float).reshape(3, 3))
    for k in range(passes):
        problem = CorrelatedRangeProblem.at(
            point,
            sensors,
            z,
            t_s,
            used,
            sigma_white_m=float(np.sqrt(sigma_range_m**2 - sigma_gps_m**2)),
            sigma_gps_enu_m=np.array([1.0, 1.0, 0.5]) * sigma_gps_m,
            correlation_s=gps_correlation_s,
        )
        warm = None
        if warm_start:
            last = k == passes - 1
            start = (
                np.asarray(last_start_m, dtype=float).reshape(1, 3)
                if last and last_start_m is not None
                else x
            )
            warm = _newton(problem, start, prior, prior_info, options, 4 if last else 1)
        if warm is not None:
            x, res = warm
        else:
            res = solve_map(problem, prior, options, initial=x)
            x = res.estimate
        point = x[0]
        if first_pass is not None:
            first_pass.append(x[0].copy())
    assert res is not None and problem is not None
    # The covariance is Gauss-Newton's (J^T Sigma^-1 J + P0^-1)^-1 at the estimate, eq. (22).
    info = problem.gauss_newton_information(res.estimate[0]) + prior_info
    cov = np.linalg.inv(info)
    return dataclasses.replace(res, estimate=x, information=info[None], covariance=0.5 * (cov + cov.T)[None])


WARM_STEP_M = 0.05
""":func:`correlated_fit` with ``warm_start``: a Newton step longer than this falls back to
:func:`solve_map` (the start was not close)."""


def _newton(
    problem: CorrelatedRangeProblem,
    x: FloatArray,
    prior: GaussianPrior,
    prior_info: FloatArray,
    options: MapOptions,
    steps: int,
) -> tuple[FloatArray, MapResult] | None:
    """Up to ``steps`` Newton steps from a warm start ``x (1, 3)``, stopping after one below
    ``delta_min_m``; None where a step is long or the Hessian not positive definite (then solve).
    Returns the estimate and a :class:`MapResult` at the point of the last Hessian (its ``estimate``
    is within the last, tiny, step of the returned one)."""
    mean = np.asarray(prior.mean, dtype=float).reshape(3)
    it = 0
    while it < steps:
        it += 1
        gram = problem.gram(x[0], newton=True)
        hess = gram[:3, :3] + prior_info
        if np.linalg.eigvalsh(hess)[0] <= 0.0:
            return None
        dev = x[0] - mean
        step = np.linalg.solve(hess, gram[:3, 3] - prior_info @ dev)
        if np.linalg.norm(step) > WARM_STEP_M:
            return None
        at = x
        x = _to_water_one(x + step, options)
        if np.linalg.norm(step) <= options.delta_min_m:
            break
    cost = 0.5 * (gram[3, 3] + dev @ prior_info @ dev)
    res = MapResult(
        estimate=at,
        covariance=np.zeros((1, 3, 3)),
        information=np.zeros((1, 3, 3)),
        iterations=np.array([it]),
        converged=np.array([bool(np.linalg.norm(step) <= options.delta_min_m)]),
        cost=np.array([cost]),
        status=np.array(["converged" if np.linalg.norm(step) <= options.delta_min_m else "max-iterations"]),
        message=np.array([""]),
    )
    return x, res


def _to_water_one(x: FloatArray, options: MapOptions) -> FloatArray:
    """A point above the surface reflected below it (as :func:`solve_map` does), ``(1, 3)``."""
    if options.surface_z_m is None:
        return x
    out = x.copy()
    z = out[0, options.surface_axis]
    out[0, options.surface_axis] = 2.0 * options.surface_z_m - z if z > options.surface_z_m else z
    return out


def beacon_prior(
    sensors: FloatArray,
    z: FloatArray,
    surface_m: float,
    prior_sigma_enu_m: tuple[float, float, float],
    prior_depth_m: float,
    known_mean_m: FloatArray | None = None,
) -> GaussianPrior:
    """The prior of one beacon: at its drop position ``known_mean_m`` (3,) when known, else
    ``prior_depth_m`` under the surface, below the shortest range's sensor (:func:`prior_mean`)."""
    known = None if known_mean_m is None else {0: known_mean_m}
    mean = prior_mean(0, sensors, z, surface_m, prior_depth_m, known)[None]
    return GaussianPrior(mean=mean, cov=np.diag(np.square(prior_sigma_enu_m)))


def check_gps_model(sigma_range_m: float, sigma_gps_m: float, gps_correlation_s: float | None) -> None:
    """ConfigError for a GPS error model that cannot be used."""
    if gps_correlation_s is not None:
        if gps_correlation_s <= 0.0:
            raise ConfigError(f"gps_correlation_s must be positive, got {gps_correlation_s}")
        if not 0.0 <= sigma_gps_m < sigma_range_m:
            raise ConfigError(
                f"sigma_gps_m ({sigma_gps_m} m) must be non-negative and below"
                f" sigma_range_m ({sigma_range_m} m)"
            )


def beacon_range_counts(aligned: AlignedRanges) -> dict[int, int]:
    """Per beacon of the log, its number of aligned ranges."""
    beacons, counts = np.unique(aligned.beacon, return_counts=True)
    return {int(b): int(c) for b, c in zip(beacons, counts, strict=True)}


def _check_aligned(aligned: AlignedRanges) -> None:
    """The aligned log's arrays are finite and of one length, ranges in ``[0, MAX_LENGTH_M]``."""
    big = _validate.MAX_LENGTH_M
    z = _validate.float_array("aligned.range_m", aligned.range_m, shape=(None,), max_abs=big, unit="m")
    m = z.shape[0]
    _validate.float_array("aligned.vehicle_enu_m", aligned.vehicle_enu_m, shape=(m, 3), max_abs=big, unit="m")
    _validate.float_array("aligned.t_unix_s", aligned.t_unix_s, shape=(m,), max_abs=1e11, unit="s")
    if np.asarray(aligned.beacon).shape != (m,):
        raise ArgumentError(f"aligned.beacon: shape {np.asarray(aligned.beacon).shape}, expected ({m},)")
    if np.any(z < 0.0):
        raise ArgumentError(f"aligned.range_m: {z.min():g} m is negative")


def localize_beacons(
    aligned: AlignedRanges,
    *,
    sigma_range_m: float = 1.006,
    prior_sigma_enu_m: tuple[float, float, float] = (100.0, 100.0, 10.0),
    prior_depth_m: float = 2.0,
    outlier_threshold: float = 3.0,
    max_outlier_fraction: float = 0.25,
    sigma_gps_m: float = 1.0,
    gps_correlation_s: float | None = 60.0,
    skip_short: bool = False,
    prior_means_enu_m: Mapping[int, FloatArray] | None = None,
) -> list[BeaconEstimate]:
    """Localize every beacon in the log (see the module docstring).

    The prior mean is below the position of the shortest range to the beacon, ``prior_depth_m`` under
    the antenna's median height; the surface constraint keeps estimates below that height. Outliers:
    :func:`robust_white_fit`; then :func:`correlated_fit` with ``gps_correlation_s``.

    Parameters
    ----------
    aligned : AlignedRanges
    sigma_range_m : float
        Total range noise ``sigma_eps`` (journal VI-B: 1.006 m), metres.
    sigma_gps_m : float
        The GPS part of it (horizontal, per axis; half of it vertically), metres; the rest,
        ``sqrt(sigma_eps^2 - sigma_gps^2)``, is white.
    gps_correlation_s : float or None
        Time constant of the GPS error; None treats it as white (the journal's model).
    skip_short : bool
        Leave out a beacon with fewer than :data:`MIN_BEACON_RANGES` ranges (else it is a
        :class:`DataError`); :func:`beacon_range_counts` says which.
    prior_means_enu_m : mapping of beacon id to (3,) float, optional
        Prior means (ENU metres) for the beacons whose drop position is known; the others get the point
        below their shortest range (:func:`prior_mean`).
    """
    check_gps_model(sigma_range_m, sigma_gps_m, gps_correlation_s)
    _check_aligned(aligned)
    _validate.sigmas("prior_sigma_enu_m", prior_sigma_enu_m)
    _validate.number("prior_depth_m", prior_depth_m, lo=0.0, hi=11_000.0, unit="m")
    _validate.number("outlier_threshold", outlier_threshold, lo=0.0, hi=1e6, lo_open=True)
    _validate.number("max_outlier_fraction", max_outlier_fraction, lo=0.0, hi=1.0)
    out = []
    surface = float(np.median(aligned.vehicle_enu_m[:, 2]))
    for beacon in np.unique(aligned.beacon):
        sel = aligned.select(int(beacon))
        sensors = aligned.vehicle_enu_m[sel]
        z = aligned.range_m[sel]
        if z.size < MIN_BEACON_RANGES and skip_short:
            continue
        if z.size < MIN_BEACON_RANGES:
            raise DataError(f"beacon {beacon}: {z.size} ranges, need at least 4")
        known = None if prior_means_enu_m is None else prior_means_enu_m.get(int(beacon))
        prior = beacon_prior(sensors, z, surface, prior_sigma_enu_m, prior_depth_m, known)
        opts = MapOptions(surface_z_m=surface)
        fit = robust_white_fit(
            sensors,
            z,
            sigma_range_m,
            prior,
            opts,
            initial_m=prior.mean[0],
            outlier_threshold=outlier_threshold,
            max_removals=int(max_outlier_fraction * z.size) + 1,
        )
        used, res = fit.used, fit.result
        if gps_correlation_s is not None:
            res = correlated_fit(
                sensors,
                z,
                aligned.t_unix_s[sel] - aligned.t_unix_s[0],
                used,
                prior,
                opts,
                initial_m=res.estimate[0],
                sigma_range_m=sigma_range_m,
                sigma_gps_m=sigma_gps_m,
                gps_correlation_s=gps_correlation_s,
            )
        x = res.estimate[0]
        resid = z - np.linalg.norm(sensors - x, axis=1)
        out.append(
            BeaconEstimate(
                beacon=int(beacon),
                position_enu_m=x.copy(),
                covariance_m2=res.covariance[0],
                used=used,
                n_excluded=int((~used).sum()),
                residual_rms_m=float(np.sqrt(np.mean(resid[used] ** 2))),
            )
        )
    return out
