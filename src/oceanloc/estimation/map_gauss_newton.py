"""Batch maximum a posteriori localization by Gauss-Newton with step control.

Garcia et al. (2019), Section IV-A, eqs. (10)-(22): the MAP estimate of a transponder position from
ranges taken at known vehicle positions and a Gaussian prior ``N(p0, P0)`` minimizes

    J_MAP(p) = 1/2 [y - f(p)]^T C^-1 [y - f(p)],    y = [z; p0],  f(p) = [r(p); p],  C = blkdiag(R, P0)

(14). Gauss-Newton iterates ``p <- p + (V^T C^-1 V)^-1 V^T C^-1 (y - f(p))`` (20)-(21) until the step is
shorter than ``delta_min`` or ``J_max`` iterations have run; the covariance is ``(V^T C^-1 V)^-1`` (22),
evaluated here at the final estimate, and its inverse is the information matrix ``Y``.

Two additions the papers do not spell out:

* **Step control.** A plain Gauss-Newton step can increase the cost (with one range and a weak prior it
  oscillates along the range sphere). Each step is a Levenberg-Marquardt step ``(A + lambda diag A)^-1 g``
  that starts as the pure Gauss-Newton step (``lambda = 0``) and is damped only when it fails to lower
  the cost, so no accepted iteration ever increases ``J_MAP``.
* **The surface.** Ranges taken from the sea surface cannot tell depth ``z`` from ``-z`` (the likelihood
  is symmetric about the sensors' plane). Transponders lie below the surface, so any trial point above
  ``surface_z_m`` is reflected back below it before its cost is compared; the estimate never leaves the
  water. A prior mean drawn above the surface is reflected the same way before iterating.

Bad input is refused, not iterated on: a prior mean or covariance with NaN or infinite values, or a prior
covariance that is not symmetric positive definite (singular included), is a :class:`ConfigError` naming
the problem and the offending values. A solution the data cannot define is reported, not called
converged: when a measurement carries no information at the estimate although it disagrees with it (a
range whose sensor sits on the estimate, where the range has no direction), the problem's ``status`` is
``degenerate`` with a message saying which measurement.

The solver is generic over small least-squares models (:class:`WhitenedModel`), batched over any number
of independent problems (Monte Carlo runs times transponders), so other measurement models (two-way
travel times, an unknown sound speed) reuse it. A model whose Jacobian is sparse (a GNSS-A survey: tens of
thousands of rows, each touching a few of its hundreds of columns) may also be a :class:`NormalModel`:
it then forms ``J^T J`` and ``J^T r`` itself from its structure, and gives residuals without a Jacobian
for the cost of a trial step, so the solver never holds the dense ``(n, d)`` Jacobian.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from oceanloc import _validate
from oceanloc._typing import ArrayLike, BoolArray, FloatArray, IntArray, StrArray
from oceanloc.errors import ArgumentError, ConfigError
from oceanloc.estimation.factors import RangeFactor


class WhitenedModel(Protocol):
    """A batch of small nonlinear least-squares problems.

    ``evaluate(x, rows)`` returns the whitened residuals ``(z - h(x)) / sigma`` with shape ``(b, n)`` and
    the whitened Jacobian ``dh/dx / sigma`` with shape ``(b, n, d)`` for the batch elements ``rows``
    (shape ``(b,)``) at the states ``x`` (shape ``(b, d)``). Excluded measurements have zero rows.
    """

    @property
    def batch_size(self) -> int: ...

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]: ...


@dataclass(frozen=True, slots=True, kw_only=True)
class NormalEquations:
    """The Gauss-Newton normal equations of a batch at given states (:meth:`NormalModel.normal_equations`).

    Attributes
    ----------
    residual : (b, n) float
        Whitened residuals ``(z - h(x)) / sigma``.
    gradient : (b, d) float
        ``J^T r`` (``J`` the whitened Jacobian ``dh/dx / sigma``).
    normal : (b, d, d) float
        ``J^T J``, symmetric.
    blind : (b, n) bool
        Measurements whose Jacobian row is zero although their residual is not (see :func:`solve_map`).
    """

    residual: FloatArray
    gradient: FloatArray
    normal: FloatArray
    blind: BoolArray


class NormalModel(WhitenedModel, Protocol):
    """A :class:`WhitenedModel` that forms its own normal equations (for sparse Jacobians).

    ``residuals(x, rows)`` returns the whitened residuals ``(b, n)`` alone (the cost of a trial step needs
    no Jacobian); ``normal_equations(x, rows)`` the :class:`NormalEquations` at ``x``. Both must agree with
    ``evaluate`` (``normal == J^T J``, ``gradient == J^T r`` to rounding), which stays the reference.
    """

    def residuals(self, x: FloatArray, rows: IntArray) -> FloatArray: ...

    def normal_equations(self, x: FloatArray, rows: IntArray) -> NormalEquations: ...


@dataclass(frozen=True, slots=True, kw_only=True)
class GaussianPrior:
    """Gaussian prior ``N(mean, cov)`` for each problem of a batch.

    Attributes
    ----------
    mean : (B, d) float
        Prior means (the papers' ``0p_T``), metres.
    cov : (B, d, d) or (d, d) float
        Prior covariances (``0P_T``), square metres; a single matrix is shared by the batch.
    """

    mean: FloatArray
    cov: FloatArray


@dataclass(frozen=True, slots=True, kw_only=True)
class MapOptions:
    """Stopping rules and constraints of :func:`solve_map`.

    Attributes
    ----------
    delta_min_m : float
        Stop when the step is shorter than this (the papers' ``delta_min``), metres.
    max_iterations : int
        Iteration limit (the papers' ``J_max``); rejected Levenberg-Marquardt trials count.
    surface_z_m : float or None
        Height of the sea surface; estimates are kept at or below it. ``None`` disables the constraint.
    surface_axis : int
        Index of the vertical coordinate in the state vector.
    step_control : bool
        Damp steps that would increase the cost (Levenberg-Marquardt); ``False`` is the papers' plain
        Gauss-Newton, kept for comparison.
    """

    delta_min_m: float = 1e-6
    max_iterations: int = 200
    surface_z_m: float | None = 0.0
    surface_axis: int = 2
    step_control: bool = True

    def __post_init__(self) -> None:
        if not (self.delta_min_m > 0.0 and np.isfinite(self.delta_min_m)):
            raise ConfigError(f"delta_min_m must be a positive number, got {self.delta_min_m}")
        if self.max_iterations < 1:
            raise ConfigError(f"max_iterations must be at least 1, got {self.max_iterations}")
        _validate.integer("max_iterations", self.max_iterations, lo=1, hi=1_000_000)


MAP_STATUS: tuple[str, ...] = ("converged", "max-iterations", "degenerate", "non-finite")
"""Values of :attr:`MapResult.status`."""


@dataclass(frozen=True, slots=True, kw_only=True)
class MapResult:
    """Result of a batch of MAP solves.

    Attributes
    ----------
    estimate : (B, d) float
        MAP estimates, metres.
    covariance : (B, d, d) float
        ``(V^T C^-1 V)^-1`` at the estimate, eq. (22), square metres.
    information : (B, d, d) float
        Inverse of ``covariance``: the information matrix ``Y`` (prior included).
    iterations : (B,) int
        Iterations used.
    converged : (B,) bool
        True where the step-size test was met within ``max_iterations`` at a well-defined solution
        (``status == "converged"``).
    cost : (B,) float
        Final ``J_MAP`` (eq. 14, with the factor 1/2).
    status : (B,) str
        One of :data:`MAP_STATUS`: ``converged``; ``max-iterations`` (the step test was not met);
        ``degenerate`` (a measurement has no information at the estimate although it disagrees with it,
        e.g. the estimate sits on the only sensor: not a solution); ``non-finite`` (the estimate or cost
        is NaN or infinite).
    message : (B,) str
        Empty where converged; otherwise what happened, for a human.
    """

    estimate: FloatArray
    covariance: FloatArray
    information: FloatArray
    iterations: IntArray
    converged: BoolArray
    cost: FloatArray
    status: StrArray
    message: StrArray


@dataclass(frozen=True, slots=True)
class RangeProblem:
    """Ranges from known sensor positions to one unknown position per problem, eq. (3)-(4).

    Attributes
    ----------
    sensor_m : (B, n, 3) float
        Sensor (vehicle) positions at each measurement, metres.
    ranges_m : (B, n) float
        Measured ranges, metres.
    sigma_m : (B, n) float
        Range noise standard deviations, metres.
    mask : (B, n) bool
        True for measurements to use.
    """

    sensor_m: FloatArray
    ranges_m: FloatArray
    sigma_m: FloatArray
    mask: BoolArray = field(repr=False)

    @classmethod
    def build(
        cls,
        sensor_m: ArrayLike,
        ranges_m: ArrayLike,
        sigma_m: ArrayLike,
        mask: ArrayLike | None = None,
    ) -> RangeProblem:
        """Validate and broadcast ``sigma_m`` and ``mask`` to ``(B, n)``.

        Ranges lie in ``[0, MAX_LENGTH_M]``, sensor coordinates within ``MAX_LENGTH_M``, sigmas within
        ``SIGMA_RANGE_M`` (:mod:`oceanloc._validate`); an ArgumentError names the argument otherwise.
        """
        z = np.atleast_2d(
            _validate.float_array("ranges_m", ranges_m, max_abs=_validate.MAX_LENGTH_M, unit="m")
        )
        if z.ndim != 2:
            raise ArgumentError(f"ranges_m: shape {z.shape}, expected (B, n)")
        if np.any(z < 0.0):
            raise ArgumentError(f"ranges_m: {z.min():g} m is negative; ranges lie in [0, 1e+08] m")
        sensors = _validate.float_array("sensor_m", sensor_m, max_abs=_validate.MAX_LENGTH_M, unit="m")
        if sensors.ndim == 2 and sensors.shape == (z.shape[-1], 3):
            sensors = np.broadcast_to(sensors, (*z.shape, 3))
        if sensors.shape != (*z.shape, 3):
            raise ArgumentError(f"sensor_m: shape {sensors.shape}, expected {(*z.shape, 3)}")
        try:
            sig = np.broadcast_to(_validate.sigmas("sigma_m", sigma_m), z.shape)
        except ValueError as exc:
            if isinstance(exc, ArgumentError):
                raise
            raise ArgumentError(f"sigma_m: cannot broadcast to the ranges' shape {z.shape}") from None
        use = np.ones(z.shape, bool) if mask is None else np.broadcast_to(np.asarray(mask, bool), z.shape)
        return cls(sensor_m=sensors, ranges_m=z, sigma_m=sig, mask=use)

    @property
    def batch_size(self) -> int:
        return self.ranges_m.shape[0]

    def factor(self) -> RangeFactor:
        """The problem as one :class:`~oceanloc.estimation.factors.RangeFactor` on the block
        ``transponder`` (the factor layer the USBL calibration stacks; the numbers are the same)."""
        return RangeFactor(
            target="transponder", ranges_m=self.ranges_m, sigma_m=self.sigma_m, mask=self.mask,
            sensor_m=self.sensor_m,
        )  # fmt: skip

    def evaluate(self, x: FloatArray, rows: IntArray) -> tuple[FloatArray, FloatArray]:
        lin = self.factor().linearize({"transponder": x}, rows)
        return lin.residual, lin.jacobians[0]


def solve_map(
    problem: WhitenedModel,
    prior: GaussianPrior,
    options: MapOptions | None = None,
    initial: ArrayLike | None = None,
) -> MapResult:
    """Solve a batch of MAP problems, eqs. (10)-(22), with monotone step control.

    Parameters
    ----------
    problem : WhitenedModel
        ``B`` independent least-squares problems (for example :class:`RangeProblem`); a
        :class:`NormalModel` gives its normal equations itself.
    prior : GaussianPrior
        Prior mean ``(B, d)`` and covariance ``(B, d, d)`` or ``(d, d)``.
    options : MapOptions, optional
    initial : (B, d) float, optional
        Starting points; the prior mean by default. Warm-starting from the previous epoch's estimate
        keeps a sequential survey in its basin.

    Returns
    -------
    MapResult
        Per problem a ``status`` and ``message``: a degenerate geometry (the estimate on the only sensor)
        is reported there, never as converged.

    Raises
    ------
    ConfigError
        If a prior mean or covariance holds NaN or infinite values, or a prior covariance is not
        symmetric positive definite (singular included), naming the problem.
    """
    opts = options or MapOptions()
    mean = np.atleast_2d(np.asarray(prior.mean, dtype=float))  # values: _prior_information
    if mean.ndim != 2:
        raise ArgumentError(f"prior.mean: shape {np.shape(prior.mean)}, expected (B, d)")
    batch, dim = mean.shape
    if problem.batch_size != batch:
        raise ConfigError(f"prior has {batch} problems but the measurements have {problem.batch_size}")
    cov = np.asarray(prior.cov, dtype=float)
    stacked = cov.ndim == 3 and cov.shape[0] in (1, batch)
    if cov.shape[-2:] != (dim, dim) or not (cov.ndim == 2 or stacked):
        raise ArgumentError(
            f"prior.cov: shape {cov.shape}, expected ({dim}, {dim}) or ({batch}, {dim}, {dim})"
        )
    cov = np.broadcast_to(cov, (batch, dim, dim))
    prior_info = _prior_information(mean, cov)
    start = mean if initial is None else _validate.float_array("initial", initial, shape=(batch, dim))
    x = _to_water(np.array(start, dtype=float), opts)

    all_rows = np.arange(batch)
    with np.errstate(over="ignore", invalid="ignore"):
        cost = _cost(problem, x, all_rows, mean, prior_info)
    _check_measurements(problem, x, cost)
    lam = np.zeros(batch)
    iterations = np.zeros(batch, dtype=np.int64)
    converged = np.zeros(batch, dtype=bool)
    active = all_rows
    for _ in range(opts.max_iterations):
        if active.size == 0:
            break
        xa = x[active]
        ne = _normal_equations(problem, xa, active)
        info_a = prior_info[active]
        dev = xa - mean[active]
        normal = ne.normal + info_a
        grad = ne.gradient - np.einsum("bij,bj->bi", info_a, dev)
        lam_a = lam[active]
        damped = normal + lam_a[:, None, None] * (normal * np.eye(dim))
        step = np.linalg.solve(damped, grad[..., None])[..., 0]
        trial = _to_water(xa + step, opts)
        trial_cost = _cost(problem, trial, active, mean, prior_info)
        accept = (trial_cost <= cost[active]) | (not opts.step_control)
        accept &= np.all(np.isfinite(trial), axis=-1)
        iterations[active] += 1
        x[active] = np.where(accept[:, None], trial, xa)
        cost[active] = np.where(accept, trial_cost, cost[active])
        lam[active] = np.where(accept, lam_a / 10.0, np.maximum(lam_a * 10.0, 1e-4))
        lam[active] = np.where(lam[active] < 1e-8, 0.0, lam[active])
        done = np.linalg.norm(step, axis=-1) <= opts.delta_min_m
        converged[active] = done
        active = active[~done]

    # A measurement that disagrees with the estimate but has no derivative there (a range from a sensor
    # at the estimate) leaves the step at zero without the estimate being a minimum.
    ne = _normal_equations(problem, x, all_rows, blind=True)
    information = ne.normal + prior_info
    covariance = np.linalg.inv(information)
    covariance = 0.5 * (covariance + np.swapaxes(covariance, -1, -2))
    blind = ne.blind
    degenerate = blind.any(axis=-1)
    finite = np.all(np.isfinite(x), axis=-1) & np.isfinite(cost)
    status = np.where(converged, "converged", "max-iterations").astype("<U14")
    status[degenerate] = "degenerate"
    status[~finite] = "non-finite"
    message = np.full(batch, "", dtype=object)
    message[status == "max-iterations"] = f"step test not met in {opts.max_iterations} iterations"
    for b in np.flatnonzero(degenerate & finite):
        i = int(np.argmax(blind[b]))
        message[b] = (
            f"measurement {i} has no information at the estimate although it disagrees with it (for a "
            "range: the estimate is on its sensor); not a solution - start elsewhere or add measurements"
        )
    message[~finite] = "the estimate or its cost is NaN or infinite"
    return MapResult(
        estimate=x,
        covariance=covariance,
        information=information,
        iterations=iterations,
        converged=status == "converged",
        cost=cost,
        status=status,
        message=message.astype(str),
    )


_BLAS_GRAM_SIZE = 50_000
"""Rows times unknowns of one problem from which ``J^T J`` is formed by BLAS, element by element."""


def _gram(jac: FloatArray) -> FloatArray:
    """``J^T J`` per batch element, ``(b, d, d)``: by BLAS element by element for large problems (a GNSS-A
    survey of tens of thousands of rows, where einsum is several times slower), by one einsum for small
    ones (Monte Carlo batches of many small problems). The choice depends on one problem's size only, so
    a problem's numbers do not depend on the batch it is solved in."""
    if jac.shape[1] * jac.shape[2] >= _BLAS_GRAM_SIZE:
        return np.stack([a.T @ a for a in jac])
    return np.einsum("bni,bnj->bij", jac, jac)


def _normal_equations(
    problem: WhitenedModel, x: FloatArray, rows: IntArray, blind: bool = False
) -> NormalEquations:
    """The normal equations of ``problem`` at ``x``: its own (:class:`NormalModel`) or from ``evaluate``;
    ``blind`` rows are found only when asked (for a dense model they cost a pass over the Jacobian)."""
    own = getattr(problem, "normal_equations", None)
    if own is not None:
        return own(x, rows)
    resid, jac = problem.evaluate(x, rows)
    mark = np.all(jac == 0.0, axis=-1) & (resid != 0.0) if blind else np.zeros(resid.shape, dtype=bool)
    return NormalEquations(
        residual=resid, gradient=np.einsum("bni,bn->bi", jac, resid), normal=_gram(jac), blind=mark
    )


MAX_WHITENED_RESIDUAL = 1e12
"""Largest ``|z - h(x)| / sigma`` at the start point accepted (beyond it a measurement cannot belong to the
problem: a range of 1e300 m, a sigma of 1e-300 m), checked only when the start's cost is that large."""


def _check_measurements(problem: WhitenedModel, x: FloatArray, cost: FloatArray) -> None:
    """ArgumentError naming the first measurement whose whitened residual at the start is NaN, infinite
    or beyond :data:`MAX_WHITENED_RESIDUAL` (the residuals are evaluated only if the cost says so)."""
    suspect = np.flatnonzero(~(cost <= 0.5 * MAX_WHITENED_RESIDUAL**2))
    if suspect.size == 0:
        return
    rows = suspect[:1]
    with np.errstate(all="ignore"):
        resid = (
            problem.residuals(x[rows], rows)
            if hasattr(problem, "residuals")
            else problem.evaluate(x[rows], rows)[0]
        )
    bad = ~(np.abs(resid[0]) <= MAX_WHITENED_RESIDUAL)
    b = int(rows[0])
    if bad.any():
        i = int(np.argmax(bad))
        raise ArgumentError(
            f"problem: measurement {i} of problem {b} has a whitened residual of {resid[0, i]:.3g} at the "
            f"start (NaN, infinite or beyond {MAX_WHITENED_RESIDUAL:g} sigmas): a measurement or sigma out "
            "of range"
        )
    raise ArgumentError(
        f"problem: the start point's cost of problem {b} is {cost[b]:.3g}: the measurements or their sigmas "
        "are out of range"
    )


def _prior_information(mean: FloatArray, cov: FloatArray) -> FloatArray:
    """The prior information matrices ``P0^-1``; ConfigError for a prior that is not a valid Gaussian.

    Beyond a finite mean and a symmetric positive definite covariance, the mean must lie within
    ``MAX_LENGTH_M`` and no covariance eigenvalue exceed ``MAX_VARIANCE`` (:mod:`oceanloc._validate`):
    a prior of 1e300 m^2 ends in a singular normal matrix, not in a weak prior.
    """
    bad = ~np.all(np.isfinite(mean), axis=-1)
    if bad.any():
        b = int(np.argmax(bad))
        raise ConfigError(f"prior mean of problem {b} holds NaN or infinite values: {mean[b].tolist()}")
    bad = np.any(np.abs(mean) > _validate.MAX_LENGTH_M, axis=-1)
    if bad.any():
        b = int(np.argmax(bad))
        raise ArgumentError(
            f"prior mean of problem {b}: {mean[b].tolist()} is beyond the allowed magnitude "
            f"{_validate.MAX_LENGTH_M:g}"
        )
    bad = ~np.all(np.isfinite(cov), axis=(-1, -2))
    if bad.any():
        b = int(np.argmax(bad))
        raise ConfigError(
            f"prior covariance of problem {b} holds NaN or infinite values (a sigma beyond 1e154 m "
            f"overflows): diagonal {np.diagonal(cov[b]).tolist()} m^2"
        )
    scale = np.max(np.abs(cov), axis=(-1, -2))
    bad = np.max(np.abs(cov - np.swapaxes(cov, -1, -2)), axis=(-1, -2)) > 1e-9 * scale
    if bad.any():
        b = int(np.argmax(bad))
        raise ConfigError(f"prior covariance of problem {b} is not symmetric: {cov[b].tolist()} m^2")
    w = np.linalg.eigvalsh(cov)
    bad = w[:, -1] > _validate.MAX_VARIANCE
    if bad.any():
        b = int(np.argmax(bad))
        raise ArgumentError(
            f"prior covariance of problem {b}: eigenvalue {w[b, -1]:.3g} is beyond the allowed "
            f"{_validate.MAX_VARIANCE:g} (a sigma of {np.sqrt(_validate.MAX_VARIANCE):g})"
        )
    bad = ~(w[:, 0] > 1e-15 * w[:, -1])
    if bad.any():
        b = int(np.argmax(bad))
        kind = "singular" if w[b, 0] >= 0.0 else "not positive definite"
        raise ConfigError(
            f"prior covariance of problem {b} is {kind} (eigenvalues {', '.join(f'{v:.3g}' for v in w[b])} "
            "m^2; every prior sigma must be positive, and the matrix positive definite)"
        )
    info = np.linalg.inv(cov)
    bad = ~np.all(np.isfinite(info), axis=(-1, -2))
    if bad.any():
        b = int(np.argmax(bad))
        raise ConfigError(f"prior covariance of problem {b} is too small to invert: {cov[b].tolist()} m^2")
    return info


def _cost(
    problem: WhitenedModel, x: FloatArray, rows: IntArray, mean: FloatArray, prior_info: FloatArray
) -> FloatArray:
    own = getattr(problem, "residuals", None)
    resid = own(x, rows) if own is not None else problem.evaluate(x, rows)[0]
    dev = x - mean[rows]
    prior_term = np.einsum("bi,bij,bj->b", dev, prior_info[rows], dev)
    return 0.5 * (np.sum(resid * resid, axis=-1) + prior_term)


def _to_water(x: FloatArray, opts: MapOptions) -> FloatArray:
    """Reflect states above the surface to their mirror image below it."""
    if opts.surface_z_m is None:
        return x
    out = x.copy()
    z = out[..., opts.surface_axis]
    out[..., opts.surface_axis] = np.where(z > opts.surface_z_m, 2.0 * opts.surface_z_m - z, z)
    return out
